"""The search: every candidate through the proxy, exhaustively where the
space fits, else by NSGA-II (pymoo); seeded and resumable.

Exhaustive: the canonical layouts of each tile size (:mod:`.layouts`), in
chunks of raw codes; each chunk's layouts and proxies are saved under
``OUT/.design/`` atomically as soon as they are done, so an interrupted run
redoes only the missing chunks.

NSGA-II (Deb et al. 2002, pymoo's implementation): one run per tile size,
the decision vector in [0, 1]^n: one gene per pixel (letter floor(k x)),
then the free spectra's parameters (:func:`.spectra.decode_params`);
objectives the proxies the design's objectives need; density bounds as
inequality constraints.  Every evaluated candidate is kept, keyed by its
canonical layout and spectra, in ``OUT/.design/nsga-HxW.json`` (rewritten
atomically after each generation); a rerun with the same seed retraces
the same generations and takes their values from the file instead of
evaluating them again.
"""

from __future__ import annotations

__all__ = ["SearchResult", "run_search", "proxy_settings", "fixed_models", "cfa_proxies", "used_proxies"]

import dataclasses
import functools
import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .. import spectra as _spectra
from ..io import atomic_output
from ..io.guard import open_regular, read_json
from . import layouts as L
from . import proxy as P
from .spectra import decode_params, letter_curves, n_params


@dataclass
class SearchResult:
    """Every candidate (a pandas DataFrame, one row each: ``key``, ``tile``
    (HxW), ``layout`` (letters row by row), ``tile_text``, the densities,
    ``params`` (JSON of the free spectra, '' when none), the proxies) and
    how many were evaluated now or taken from an earlier run."""

    candidates: object
    evaluated: int = 0
    reused: int = 0
    engines: dict = field(default_factory=dict)


def used_proxies(config) -> tuple[str, ...]:
    """The proxies the design's objectives need, in :data:`.proxy.PROXY_NAMES` order."""
    wanted = {p for o in config.objectives for p in o.proxies}
    return tuple(p for p in P.PROXY_NAMES if p in wanted)


def proxy_settings(config) -> P.ProxySettings:
    """The study's optics, sensor and exposure policy (the study's own
    default, the exposure program, when the config names none), at the
    lowest luminance of an objective that the noise proxy predicts; the
    noise proxy takes the best of the objectives' demosaics, each predicted
    by its linear core (itself when its record says it is linear)."""
    st = config.study
    chain = st.chain_settings()
    sensor = chain.sensor
    lums = [o.luminance for o in config.objectives if {"noise", "noise_area"} & set(o.proxies)] or list(st.luminances)
    program = chain.exposure_program
    if program.policy == "fixed":  # no scene to fix a time for: the proxy predicts the program's exposure
        program = dataclasses.replace(program, policy="program")
    ratio = 1.0 if program.policy == "each" else min(lums) / program.reference_luminance_cd_m2
    edge = min([o.luminance for o in config.objectives if o.scene == "slanted-edge"] or [100.0])
    f_number = float(st.optics.get("f_number", 4.0))
    wanted = [d for o in config.objectives
              if {"noise", "noise_area", "snr10", "snr10_area", "blur", "neg_capacity"} & set(o.proxies)
              for d in (st.demosaics if o.demosaic == "best" else (o.demosaic,))]
    demosaics = tuple(dict.fromkeys(P.linear_core(d) for d in wanted)) or ("bilinear",)
    return P.ProxySettings(f_number, float(sensor.pixel_pitch_um), float(sensor.well_capacity_e),
                           float(sensor.read_noise_e), ratio, exposure=program, luminance_cd_m2=float(min(lums)),
                           fill_factor=float(sensor.fill_factor), demosaics=demosaics, edge_luminance_cd_m2=edge,
                           edge_both=any(o.orientation == "both" for o in config.objectives))


def _bands(curves: dict, letters) -> np.ndarray:
    wl = _spectra.DEFAULT_WAVELENGTHS
    return np.stack([_spectra.band_average(*curves[a], wl) for a in letters])


def fixed_models(curves: dict, alphabet, settings: P.ProxySettings | None = None):
    """A cached function: tuple of letter indices -> ColourModel (with
    ``settings``, the image processor's noise-regularised colour matrix)."""
    qe = _bands(curves, alphabet)
    kw = {} if settings is None else {"well_e": settings.well_e, "read_noise_e": settings.read_noise_e}

    @functools.lru_cache(maxsize=None)
    def model(idx):
        return P.colour_model(qe[list(idx)], **kw)

    return model


def cfa_proxies(cfa, settings: P.ProxySettings) -> dict:
    """The proxies of a built CFA (a named one) with its own spectra."""
    qe = cfa.sensitivities(_spectra.DEFAULT_WAVELENGTHS)
    lut = {c: i for i, c in enumerate(cfa.channels)}
    h, w = cfa.tile_shape
    layout = np.array([[lut[c] for c in cfa.pattern.ravel()]], dtype=np.uint8)
    kw = {"well_e": settings.well_e, "read_noise_e": settings.read_noise_e}
    got = P.evaluate_layouts(layout, h, w, lambda idx: P.colour_model(qe[list(idx)], **kw), settings)
    return {k: float(v[0]) for k, v in got.items()}


def _rows(layouts, h, w, alphabet, proxies, params=""):
    """The candidates table (a DataFrame) of ``layouts`` with their proxies."""
    import pandas as pd

    layouts = np.asarray(layouts, dtype=np.uint8).reshape(-1, h * w)
    names = np.array([a if len(a) == 1 else f"[{a}]" for a in alphabet])
    spaced = np.array(list(alphabet))
    letters = ["".join(r) for r in names[layouts]]
    rows_text = [" / ".join(" ".join(r[i * w:(i + 1) * w]) for i in range(h)) for r in spaced[layouts]]
    df = pd.DataFrame({"key": [f"{h}x{w}:{x}:{params}" for x in letters], "tile": f"{h}x{w}", "layout": letters,
                       "tile_text": rows_text, "params": params})
    counts = L.letter_counts(layouts, len(alphabet)) / (h * w)
    for j, a in enumerate(alphabet):
        df[f"density_{a}"] = counts[:, j]
    for k, v in proxies.items():
        df[k] = np.asarray(v, dtype=np.float64)
    return df


def _state_key(settings) -> str:
    """A short hash of the proxy's settings and names: saved state is reused
    only by a run that would compute the same proxies."""
    import hashlib

    return hashlib.sha1(repr((settings, P.PROXY_NAMES)).encode()).hexdigest()[:8]


def _save_npz(path: Path, **arrays) -> None:
    with atomic_output(path) as tmp:
        with open(tmp, "wb") as fh:
            np.savez(fh, **arrays)


def _exhaustive(config, h, w, state: Path, settings, models, log, bar=None) -> tuple[list[dict], int, int]:
    k = len(config.alphabet)
    lo, hi = L.density_limits(config.density, config.alphabet, h * w)
    rows, evaluated, reused = [], 0, 0
    names = ("aliasing", "aliasing_h", "crosstalk", "sampling", "blur", "neg_capacity", "noise", "noise_xyz",
             "noise_area", "snr10", "snr10_area", "colour", "vora_trussell")
    for i in range(L.n_chunks(h, w, k)):
        f = state / f"exhaustive-{h}x{w}-{_state_key(settings)}-{i:05d}.npz"
        if f.exists():
            with open_regular(f, "design state file") as fh, np.load(fh, allow_pickle=False) as z:
                lay, got = z["layouts"], {n: z[n] for n in names}
            reused += len(lay)
        else:
            lay = L.enumerate_chunk(i, h, w, k, lo, hi, config.mirrors, config.tiles)
            got = P.evaluate_layouts(lay, h, w, models, settings) if len(lay) else {n: np.zeros(0) for n in names}
            _save_npz(f, layouts=lay, **{n: got[n] for n in names})
            evaluated += len(lay)
        rows.append(_rows(lay, h, w, config.alphabet, {n: got[n] for n in names}))
        if bar is not None:
            bar.update(1)
    import pandas as pd

    df = pd.concat(rows, ignore_index=True)
    log(f"  {h}x{w}: exhaustive, {L.raw_count(h, w, k):,} raw layouts -> {len(df):,} distinct within the "
        f"density bounds")
    return df, evaluated, reused


class _Archive:
    """Evaluated NSGA-II candidates by key, persisted atomically."""

    def __init__(self, path: Path):
        self.path = path
        self.rows: dict = read_json(path, "design archive", allow_nan=True) if path.exists() else {}
        self.evaluated = self.reused = 0

    def save(self):
        with atomic_output(self.path) as tmp:
            tmp.write_text(json.dumps(self.rows))


def _nsga2(config, h, w, state: Path, settings, models, objectives, log, bar=None) -> tuple[list[dict], int, int]:
    from pymoo.algorithms.moo.nsga2 import NSGA2
    from pymoo.core.problem import Problem
    from pymoo.optimize import minimize

    k, n = len(config.alphabet), h * w
    spec = config.spectra
    n_spec = n_params(spec) * (len(spec.letters) if spec else 0)
    lo, hi = L.density_limits(config.density, config.alphabet, n)
    archive = _Archive(state / f"nsga-{h}x{w}-{_state_key(settings)}.json")

    def decode(x):
        lay = np.minimum((x[:, :n] * k).astype(np.int64), k - 1).astype(np.uint8)
        return L.canonical(lay, h, w, k, config.mirrors), x[:, n:]

    def evaluate_one(lay, unit):
        params = ""
        model = models
        if spec is not None:
            decoded = decode_params(spec, unit)
            params = json.dumps([{a: round(v, 4) if isinstance(v, float) else [round(u, 4) for u in v]
                                  for a, v in p.items()} for p in decoded])
            curves = letter_curves(config.alphabet, config.spectra_set, spec, json.loads(params))
            model = fixed_models(curves, config.alphabet, settings)
        key = _rows(lay[None, :], h, w, config.alphabet, {}, params)["key"].iloc[0]
        if key in archive.rows:
            archive.reused += 1
            return archive.rows[key]
        got = P.evaluate_layouts(lay[None, :], h, w, model, settings)
        row = _rows(lay[None, :], h, w, config.alphabet, got, params).to_dict("records")[0]
        archive.rows[key] = row
        archive.evaluated += 1
        return row

    class Design(Problem):
        def __init__(self):
            super().__init__(n_var=n + n_spec, n_obj=len(objectives), n_ieq_constr=2 * k, xl=0.0, xu=1.0)

        def _evaluate(self, x, out, *args, **kwargs):
            lay, unit = decode(x)
            rows = [evaluate_one(lay[i], unit[i]) for i in range(len(x))]
            out["F"] = np.array([[r[o] for o in objectives] for r in rows])
            counts = L.letter_counts(lay, k)
            out["G"] = np.concatenate([lo[None, :] - counts, counts - hi[None, :]], axis=1).astype(float)
            archive.save()

    from pymoo.core.callback import Callback

    class Tick(Callback):  # one step of the progress bar per generation
        def notify(self, algorithm):
            if bar is not None:
                bar.update(1)

    minimize(Design(), NSGA2(pop_size=config.population), ("n_gen", config.generations), seed=config.seed,
             verbose=False, callback=Tick())
    rows = list(archive.rows.values())
    counts = np.array([[r[f"density_{a}"] * n for a in config.alphabet] for r in rows]).round()
    ok = np.all((counts >= lo) & (counts <= hi), axis=1) if rows else np.zeros(0, bool)
    rows = [r for r, good in zip(rows, ok) if good]
    log(f"  {h}x{w}: NSGA-II, population {config.population} x {config.generations} generations, "
        f"{archive.evaluated} candidates evaluated now, {archive.reused} answered from the archive (repeats or an "
        f"earlier run); "
        f"{len(rows)} distinct within the density bounds")
    import pandas as pd

    return pd.DataFrame(rows), archive.evaluated, archive.reused


def run_search(config, out_dir, *, log=print, progress: bool = False) -> SearchResult:
    """Search every tile size of ``config`` (a DesignConfig); keeps its state
    under ``out_dir/.design`` (module doc).  ``progress``: a bar on a
    terminal, one step per exhaustive chunk or NSGA-II generation."""
    import pandas as pd

    from ..io.progress import progress_bar

    state = Path(out_dir) / ".design"
    state.mkdir(parents=True, exist_ok=True)
    settings = proxy_settings(config)
    objectives = used_proxies(config)
    curves = letter_curves(config.alphabet, config.spectra_set) if config.spectra is None else None
    models = fixed_models(curves, config.alphabet, settings) if curves else None
    rows, evaluated, reused = [], 0, 0
    steps = sum(L.n_chunks(h, w, len(config.alphabet)) if config.engine[(h, w)] == "exhaustive"
                else config.generations for h, w in config.tiles)
    bar = progress_bar(steps, "search", enabled=progress)
    try:
        for h, w in config.tiles:
            if config.engine[(h, w)] == "exhaustive":
                got, e, r = _exhaustive(config, h, w, state, settings, models, log, bar)
            else:
                got, e, r = _nsga2(config, h, w, state, settings, models, objectives, log, bar)
            rows.append(got)
            evaluated += e
            reused += r
    finally:
        bar.close()
    df = pd.concat(rows, ignore_index=True).drop_duplicates("key").reset_index(drop=True)
    return SearchResult(df, evaluated, reused, dict(config.engine))
