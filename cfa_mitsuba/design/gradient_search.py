"""``[design] method = "gradient"``: filter spectra of a fixed layout by a
gradient method on the differentiable proxy (:mod:`.gradient`).

Each free letter's curve is linear in its parameters theta
(:mod:`.spectra`): ``spline`` a dye transmittance T = sum_k theta_k B_k(l)
of cubic B-splines (clamped, uniform knots over 380-720 nm) on the common
IR cut and silicon, so theta in [0, 1] bounds T in [0, 1] (a B-spline
basis is non-negative and sums to 1); ``mixture`` a non-negative mixture
of measured curves of one or more spectra sets (the dye library), with a
quadratic penalty where the QE would pass 1.  The band QE is A theta, A
the basis band-averaged exactly as a CFA TOML's curve is (so the full
chain sees what the search optimised).

For each colour weight w of ``weights`` the search minimises
  w log(colour) + (1 - w) log(noise objective)
(the weighted product of the two proxies: it also reaches the concave parts
of a front that a weighted sum misses) by L-BFGS-B with the bounds
(scipy.optimize; Byrd, Lu, Nocedal & Zhu 1995) from several starts: the
spectra set's own curves fitted to the basis and seeded random band-pass
curves.  Every finished run is a candidate; the full chain takes the best
of their front (:func:`gradient_selection`).
"""

from __future__ import annotations

__all__ = ["GradientSpec", "parse_gradient", "run_gradient", "gradient_selection", "gradient_objectives",
           "GRADIENT_COLUMNS", "NOISE_PROXY_OF", "DEFAULT_WEIGHTS"]

import json
import time
from dataclasses import dataclass

import numpy as np

from .. import spectra as _spectra

#: The gradient's noise term for each noise objective metric (and snr10's basis).
NOISE_PROXY_OF = {("snr10", "ysnr"): "snr10", ("snr10", "ysnr-area"): "snr10_area", ("ysnr", ""): "noise",
                  ("ysnr-area", ""): "noise_area"}
COLOUR_METRICS = ("delta-e",)
#: The candidates' columns of the gradient's own two objectives (what it optimised).
GRADIENT_COLUMNS = ("gradient_colour", "gradient_noise")
DEFAULT_WEIGHTS = (0.15, 0.3, 0.45, 0.6, 0.75, 0.9)
#: Spline coefficients' lower bound: a channel never goes wholly dark (its white balance would divide by 0).
_FLOOR = 1e-4
_PENALTY = 1e3


@dataclass(frozen=True)
class GradientSpec:
    """``[gradient]``: the fixed ``layout`` (tile text), the colour weights
    of the front, starts per weight, L-BFGS-B iterations, the colour chart."""

    layout: str
    weights: tuple = DEFAULT_WEIGHTS
    starts: int = 3
    max_iter: int = 150
    chart: str = "macbeth"


def parse_gradient(ck, data, tiles, alphabet, spectra, objectives) -> GradientSpec:
    """Validate ``[gradient]`` against the rest of a design config (one-line errors)."""
    from .gradient import CHARTS

    if data is None:
        ck.fail("gradient", "missing: method = \"gradient\" needs a [gradient] table with layout = \"G R / B G\"")
    ck.table(data, "gradient", {"layout": None, "weights": None, "starts": None, "max_iter": None, "chart": None})
    text = ck.string(data.get("layout", ""), "gradient.layout")
    rows = [r.split() for r in text.split("/")]
    if not text.strip() or any(len(r) != len(rows[0]) or not r for r in rows):
        ck.fail("gradient.layout", f"must be rows of letters separated by '/', e.g. \"G R / B G\" (got {text!r})")
    bad = next((c for r in rows for c in r if c not in alphabet), None)
    if bad is not None:
        ck.fail("gradient.layout", f"letter {bad!r} is not in layout.alphabet")
    if (len(rows), len(rows[0])) not in tiles:
        ck.fail("gradient.layout", f"a {len(rows)}x{len(rows[0])} tile is not one of layout.tiles")
    if spectra is None or spectra.family not in ("spline", "mixture"):
        ck.fail("spectra.family", "method = \"gradient\" needs family = \"spline\" or \"mixture\"")
    absent = [a for a in spectra.letters if a not in {c for r in rows for c in r}]
    if absent:
        ck.fail("spectra.letters", f"{absent[0]!r} is free but not in gradient.layout")
    weights = data.get("weights", list(DEFAULT_WEIGHTS))
    if not isinstance(weights, list) or not weights:
        ck.fail("gradient.weights", "must be a non-empty list of colour weights in [0, 1]")
    weights = tuple(ck.number(w, f"gradient.weights[{i}]") for i, w in enumerate(weights))
    if any(not 0.0 <= w <= 1.0 for w in weights):
        ck.fail("gradient.weights", "each colour weight must lie in [0, 1]")
    colour = [o for o in objectives if o.metric in COLOUR_METRICS]
    noise = [o for o in objectives if (o.metric, o.basis if o.metric == "snr10" else "") in NOISE_PROXY_OF]
    if len(colour) != 1 or len(noise) != 1 or len(objectives) != 2:
        ck.fail("objective", "method = \"gradient\" takes two objectives: delta-e and one of snr10, ysnr, "
                             "ysnr-area")
    for i, o in enumerate(objectives):
        if o.demosaic != "bilinear":
            ck.fail(f"objective[{i}].demosaic", "method = \"gradient\" propagates noise through \"bilinear\" "
                                                "(its weights do not depend on the spectra)")
    return GradientSpec(text.strip(), weights, ck.integer(data.get("starts", 3), "gradient.starts", 1),
                        ck.integer(data.get("max_iter", 150), "gradient.max_iter", 1),
                        ck.string(data.get("chart", "macbeth"), "gradient.chart", CHARTS))


def _noise_name(config) -> str:
    o = next(o for o in config.objectives if o.metric not in COLOUR_METRICS)
    return NOISE_PROXY_OF[(o.metric, o.basis if o.metric == "snr10" else "")]


class _Problem:
    """theta (all free letters' parameters) -> (C, B) band QE and the objective."""

    def __init__(self, config, present, gp):
        from .spectra import basis_matrices, letter_curves

        self.config, self.present, self.gp = config, present, gp
        spec = config.spectra
        wl = _spectra.DEFAULT_WAVELENGTHS
        fixed = letter_curves(config.alphabet, config.spectra_set)
        self.free = [a for a in spec.letters if a in present]
        self.fixed_qe = {a: _spectra.band_average(*fixed[a], wl) for a in present if a not in self.free}
        self.grid, self.bands = basis_matrices(spec)      # (G, K) on GRID_NM, (B, K)
        k = self.bands.shape[1]
        self.sizes = [k] * len(self.free)
        lo, hi = (_FLOOR, 1.0) if spec.family == "spline" else spec.weight
        self.bounds = [(lo, hi)] * sum(self.sizes)

    def qe(self, theta):
        import autograd.numpy as anp

        rows, i = [], 0
        for a in self.present:
            if a in self.free:
                rows.append(anp.dot(self.bands, theta[i:i + self.bands.shape[1]]))
                i += self.bands.shape[1]
            else:
                rows.append(anp.array(self.fixed_qe[a]))
        return anp.stack(rows)

    def loss(self, theta, w, noise_name):
        import autograd.numpy as anp

        q = self.qe(theta)
        f = w * anp.log(self.gp.colour(q)) + (1.0 - w) * anp.log(self.gp.objective(noise_name, q))
        if self.config.spectra.family == "mixture":  # QE above 1 nowhere (module doc)
            over = anp.maximum(anp.dot(self.grid, anp.reshape(theta, (len(self.free), -1)).T) - 1.0, 0.0)
            f = f + _PENALTY * anp.sum(over ** 2)
        return f

    def starts(self, n: int, seed: int) -> list:
        """The set's own curves fitted to the basis, then seeded random band-pass curves."""
        from .spectra import GRID_NM, common_qe, fit_to_basis, letter_curves

        rng = np.random.default_rng(seed)
        own = letter_curves(self.config.alphabet, self.config.spectra_set)
        out = [np.concatenate([fit_to_basis(self.config.spectra, np.interp(GRID_NM, *own[a]), self.grid)
                               for a in self.free])]
        nominal = {"R": 610.0, "G": 540.0, "B": 460.0, "C": 500.0, "M": 560.0, "Y": 570.0, "W": 550.0}
        for _ in range(n - 1):
            parts = []
            for a in self.free:
                c = nominal.get(a, 550.0) + rng.uniform(-40, 40)
                width = rng.uniform(60, 180)
                t = 0.95 * np.exp(-np.log(2.0) * np.abs(2.0 * (GRID_NM - c) / width) ** 4) + 0.02
                parts.append(fit_to_basis(self.config.spectra, t * common_qe(), self.grid))
            out.append(np.concatenate(parts))
        lo, hi = self.bounds[0]
        return [np.clip(x, lo, hi) for x in out][:n]


def _params(problem, theta) -> list[dict]:
    key = "coefficients" if problem.config.spectra.family == "spline" else "weights"
    out, i = [], 0
    for a, k in zip(problem.free, problem.sizes):
        out.append({key: [round(float(v), 6) for v in theta[i:i + k]]})
        i += k
    return out


def run_gradient(config, out_dir, *, log=print):
    """The gradient search of ``config`` (module doc; ``out_dir`` unused: the
    search keeps no state, a rerun repeats it, seeded, and the full chain
    resumes from its study's ``.work/``): a :class:`.search.SearchResult`
    whose candidates carry the standard proxies of the emitted curves and
    ``gradient_colour``, ``gradient_noise``, ``weight``, ``start``,
    ``iterations``, ``converged`` and the manufacturability columns."""
    import pandas as pd
    from autograd import value_and_grad
    from scipy.optimize import minimize

    from . import layouts as L
    from . import proxy as P
    from .gradient import make_gradient_proxy
    from .manufacture import manufacturability
    from .search import SearchResult, _rows, fixed_models, proxy_settings
    from .spectra import letter_curves

    gs = config.gradient
    rows_t = [r.split() for r in gs.layout.split("/")]
    h, w = len(rows_t), len(rows_t[0])
    index = {a: i for i, a in enumerate(config.alphabet)}
    codes = np.array([index[c] for r in rows_t for c in r], dtype=np.uint8)
    present = [a for a in config.alphabet if a in {c for r in rows_t for c in r}]
    local = np.array([[present.index(c) for c in r] for r in rows_t])
    settings = proxy_settings(config)
    gp = make_gradient_proxy(local, len(present), settings, chart=gs.chart)
    problem = _Problem(config, present, gp)
    noise_name = _noise_name(config)
    lay = L.canonical(codes[None, :], h, w, len(config.alphabet), config.mirrors)
    fun = value_and_grad(lambda th, wt: problem.loss(th, wt, noise_name))
    t0 = time.perf_counter()
    starts = problem.starts(gs.starts, config.seed)
    found = []
    for wt in gs.weights:
        for s, x0 in enumerate(starts):
            res = minimize(lambda th: tuple(np.asarray(v, dtype=float) for v in fun(th, wt)), x0, jac=True,
                           method="L-BFGS-B", bounds=problem.bounds, options={"maxiter": gs.max_iter})
            q = np.asarray(problem.qe(res.x))
            found.append((wt, s, res, float(gp.colour(q)), float(gp.objective(noise_name, q))))
    log(f"  gradient: {len(found)} L-BFGS-B runs ({len(gs.weights)} weights x {len(starts)} starts, "
        f"{sum(int(f[2].nit) for f in found):,} iterations) in {time.perf_counter() - t0:.1f} s")
    frames = []
    for wt, s, res, colour, noise in found:
        params = json.dumps(_params(problem, res.x))
        curves = letter_curves(config.alphabet, config.spectra_set, config.spectra, json.loads(params))
        got = P.evaluate_layouts(lay, h, w, fixed_models(curves, config.alphabet, settings), settings)
        df = _rows(lay, h, w, config.alphabet, got, params)
        df["gradient_colour"], df["gradient_noise"] = colour, noise
        df["weight"], df["start"], df["iterations"], df["converged"] = wt, s, int(res.nit), bool(res.success)
        for k, v in manufacturability(config, json.loads(params)).items():
            df[k] = v
        frames.append(df)
    cands = pd.concat(frames, ignore_index=True).drop_duplicates("key").reset_index(drop=True)
    return SearchResult(cands, len(found), 0, {(h, w): "gradient"})


def gradient_selection(cands):
    """(proxy score, proxies) for choosing the full chain's candidates: the
    front of the gradient's own two objectives, min-max normalised and
    averaged (:func:`.front.select` takes the rest)."""
    from .front import _normalise

    proxies = ("gradient_colour", "gradient_noise")
    score = np.mean([_normalise(np.log(cands[p].to_numpy(dtype=float))) for p in proxies], axis=0)
    return score, proxies


class _Predicted:
    """An objective whose proxy is the gradient's own column (the rest delegated)."""

    def __init__(self, objective, column: str):
        self._o, self.proxies = objective, (column,)

    def __getattr__(self, name):
        return getattr(self._o, name)


def gradient_objectives(config) -> list:
    """The design's objectives, each predicted by the gradient's own
    objective (``gradient_colour`` for ΔE00, ``gradient_noise`` for the
    noise one) in the agreement (:func:`.front.agreement`)."""
    return [_Predicted(o, GRADIENT_COLUMNS[0] if o.metric in COLOUR_METRICS else GRADIENT_COLUMNS[1])
            for o in config.objectives]
