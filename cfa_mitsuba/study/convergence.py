"""Error against run time: what render quality (samples per pixel) and
processing quality (POCS iterations) buy, measured against a reference.

For one scene, :func:`run_convergence`

1. renders a **reference** as the mean of two independent renders (seeds
   ``seed + 1`` and ``seed + 2``) at ``reference_spp`` each; half their
   difference is the reference's own noise, measured, not assumed;
2. renders the scene at each **spp level** (seed ``seed``), timing the whole
   :func:`cfa_mitsuba.render.render` call (scene build, Mitsuba load, kernel
   compile, render, white probe); with ``repeat`` > 1 the fastest of the runs
   counts (the first run of a new spp compiles a kernel: 2-4 s on the puppy);
3. reports, per level and per band, the **radiance error**: the rms over the
   image of (level - reference), divided by the reference's mean, and the
   same over the scene's most uniform window (:func:`uniform_region`);
4. runs every level and the reference through the study's chain (optics,
   capture with the CFA, processing with the demosaic, the scene's metrics
   against the ideal XYZ sensor: :mod:`cfa_mitsuba.study.tasks`) and reports
   each **metric's deviation** from the reference's value.  The capture is
   noise-free by default (``render_noise='off'``): the sensor's Poisson
   sampler draws a new realisation whenever the mean signal changes at all
   (a 1e-4 relative change of the radiance re-draws 95 % of the pixels), so
   a fixed noise seed does not freeze the sensor noise across renders and
   would bury the render-induced deviation under seed-to-seed noise.  A
   deviation from one render is one draw of a random variable (it crosses
   zero now and then), so the default spp is rendered with a few more seeds
   and the check uses the rms over them;
5. on the processing side, captures the reference once with sensor noise
   (the study's seed for this scene and CFA) and processes it with POCS at
   each iteration count (tolerance 0, so exactly that many iterations),
   reporting each metric's deviation from a converged POCS
   (``pocs_reference_iterations``, tolerance 0) against the processing time;
6. puts the deviations in context: each metric's spread across a few CFAs
   (the differences a study reports; the study's noise seeds) and its
   seed-to-seed sensor-noise standard deviation.

Results are a tidy table (:data:`CSV_COLUMNS`) and a summary dict with the
fitted convergence rates (:func:`fit_rate`); :func:`write_outputs` writes
``convergence_<scene>.csv`` and ``.json``; the plot (``.png``, ``.svg``) is
drawn by :mod:`cfa_mitsuba.report.convergence`.
"""


from __future__ import annotations

__all__ = [
    "CSV_COLUMNS",
    "ConvergencePlan",
    "ConvergenceResult",
    "make_plan",
    "default_spp_levels",
    "run_convergence",
    "uniform_region",
    "relative_rms_per_band",
    "fit_rate",
    "write_outputs",
    "format_table",
    "rows_frame",
    "radiance_series",
    "rate_text",
]

import time
from pathlib import Path

import numpy as np

# the public names live in the two modules below; this one re-exports them
from .convergence_plan import (CSV_COLUMNS, DEFAULT_COMPARE_CFAS, FLOAT_FLOOR, ConvergencePlan,  # noqa: F401
                               ConvergenceResult, default_spp_levels, make_plan)
from .convergence_summary import (fit_rate, format_table, radiance_series, rate_text,  # noqa: F401
                                  relative_rms_per_band, rows_frame, summarise, uniform_region, write_outputs)


class _Chain:
    """The camera chain (:class:`.chain.CameraChain`) as the convergence study
    calls it: the study's default settings at the plan's luminance."""

    def __init__(self, plan: ConvergencePlan):
        from .chain import CameraChain
        from .conditions import Condition

        self.plan = plan
        self.chain = CameraChain()
        self.cond = Condition(luminance=plan.luminance_cd_m2)

    def optical(self, img):
        return self.chain.optical(img, self.cond)

    def ideal(self, oi):
        return self.chain.ideal(oi, self.cond)

    def capture(self, oi, cfa: str, noise: str, seed: int):
        return self.chain.capture(oi, cfa, self.cond, seed, noise=noise)

    def metrics(self, ideal, raw, method: str, **opts) -> tuple[dict, dict, float]:
        """({metric: value}, {metric: unit}, processing wall time s)."""
        from .. import metrics as m

        t = time.perf_counter()
        out = self.chain.process(raw, method, **opts)
        dt = time.perf_counter() - t
        cam = m.mean_match(out.xyz, ideal.xyz)
        rows = m.result_rows(m.evaluate_many(self.plan.metrics, self.chain.inputs(ideal, cam, self.cond)))
        return {r["metric"]: r["value"] for r in rows}, {r["metric"]: r["unit"] for r in rows}, dt

    def evaluate(self, img, cfa: str, method: str, noise: str, seed: int):
        oi = self.optical(img)
        ideal = self.ideal(oi)
        return self.metrics(ideal, self.capture(oi, cfa, noise, seed), method)


def _timed_render(plan: ConvergencePlan, spp: int, seed: int, runs: int):
    from .. import render

    times, img = [], None
    for _ in range(runs):
        t = time.perf_counter()
        img = render.render(plan.scene, width=plan.width, height=plan.height, spp=spp, seed=seed,
                            luminance=plan.luminance_cd_m2, variant=plan.variant)
        times.append(time.perf_counter() - t)
    return img, min(times), times


def _luminance(img) -> np.ndarray:
    from .. import spectra

    return spectra.luminance_cd_m2(img.data, img.wavelengths)


def _band_names(wl) -> list[str]:
    return [f"{w:g}nm" for w in np.asarray(wl, dtype=np.float64)]



class _Rows:
    """The convergence table as it grows, with each quantity's unit."""

    def __init__(self, name: str):
        self.name, self.rows, self.units = name, [], {}

    def add(self, stage, quality, wall_s, quantity, error, unit, value=None):
        self.rows.append({"scene": self.name, "stage": stage, "quality": quality, "wall_s": wall_s,
                          "quantity": quantity, "error": float(error), "unit": unit,
                          "value": None if value is None else float(value)})


def _reference_step(p, chain, out: _Rows, log):
    """Two independent renders at the reference spp, their mean and their own
    error (half their difference): (reference, region, exact error, times,
    metric values, metric floor)."""
    from ..values import SpectralImage

    log(f"convergence {p.name}: {p.width} x {p.height}, spp {', '.join(map(str, p.spp_levels))}; "
        f"reference 2 x {p.reference_spp} spp")
    refs, ref_times = [], []
    for i in (1, 2):
        log(f"  reference render {i}/2 ({p.reference_spp} spp, seed {p.seed + i}) ...")
        img, dt, _ = _timed_render(p, p.reference_spp, p.seed + i, 1)
        refs.append(img)
        ref_times.append(dt)
        log(f"    {dt:.1f} s")
    r1, r2 = refs
    wl = np.asarray(r1.wavelengths, dtype=np.float64)
    bands = _band_names(wl)
    ref = SpectralImage(0.5 * (r1.data + r2.data), wl, {**r1.meta, "spp": 2 * p.reference_spp,
                                                         "seed": [p.seed + 1, p.seed + 2]})
    region = uniform_region(_luminance(ref))
    own_img = 0.5 * relative_rms_per_band(r1.data, r2.data) * _mean_ratio(r2.data, ref.data)
    own_reg = 0.5 * relative_rms_per_band(r1.data, r2.data, region) * _mean_ratio(r2.data, ref.data, region)
    for b, e_i, e_r in zip(bands, own_img, own_reg):
        out.add("reference", p.reference_spp, sum(ref_times), f"radiance:{b}", e_i, "relative")
        out.add("reference", p.reference_spp, sum(ref_times), f"uniform:{b}", e_r, "relative")
    exact = _exact_error(p, ref)
    log("  metrics of the reference ...")
    ref_vals, u, _ = chain.evaluate(ref, p.cfa, p.demosaic, p.render_noise, p.seed)
    out.units.update(u)
    half = [chain.evaluate(r, p.cfa, p.demosaic, p.render_noise, p.seed)[0] for r in (r1, r2)]
    metric_floor = {k: 0.5 * abs(half[0][k] - half[1][k]) for k in ref_vals}
    for k, v in ref_vals.items():
        out.add("reference", p.reference_spp, sum(ref_times), k, metric_floor[k], out.units[k], v)
    return ref, region, exact, ref_times, ref_vals, metric_floor


def _levels_step(p, chain, out: _Rows, log, ref, region, ref_vals):
    """Each spp level (and the default spp with other seeds) against the
    reference: (per-level times, the default spp's renders)."""
    bands = _band_names(np.asarray(ref.wavelengths, dtype=np.float64))
    level_times, default_imgs = {}, []
    for n, spp in enumerate(p.spp_levels, 1):
        img, dt, times = _timed_render(p, spp, p.seed, p.repeat)
        level_times[spp] = times
        if spp == p.default_spp:
            default_imgs.append(img)
        e_img = relative_rms_per_band(img.data, ref.data)
        e_reg = relative_rms_per_band(img.data, ref.data, region)
        for b, a, c in zip(bands, e_img, e_reg):
            out.add("render", spp, dt, f"radiance:{b}", a, "relative")
            out.add("render", spp, dt, f"uniform:{b}", c, "relative")
        vals, _, _ = chain.evaluate(img, p.cfa, p.demosaic, p.render_noise, p.seed)
        for k, v in vals.items():
            out.add("render", spp, dt, k, abs(v - ref_vals[k]), out.units[k], v)
        log(f"  render {n}/{len(p.spp_levels)}: {spp} spp, {dt:.2f} s"
            + (f" (runs {', '.join(f'{t:.2f}' for t in times)})" if len(times) > 1 else "")
            + f"; radiance error median band {100 * np.nanmedian(e_img):.3g} %")
    for i in range(p.default_seeds or 0):  # the default spp again with other seeds: its deviation's spread
        s_i = p.seed + 3 + i
        log(f"  default {p.default_spp} spp, seed {s_i} ({i + 1}/{p.default_seeds}) ...")
        img, dt, _ = _timed_render(p, p.default_spp, s_i, 1)
        default_imgs.append(img)
        vals, _, _ = chain.evaluate(img, p.cfa, p.demosaic, p.render_noise, p.seed)
        for k, v in vals.items():
            out.add("render-seeds", p.default_spp, dt, k, abs(v - ref_vals[k]), out.units[k], v)
    return level_times, default_imgs


def _pocs_step(p, chain, out: _Rows, log, ideal, raw) -> dict:
    """POCS iterations on the reference's noisy capture against a converged
    POCS; returns what the default iteration count gives."""
    log(f"  POCS: converged reference ({p.pocs_reference_iterations} iterations) ...")
    pocs_ref, _, pocs_ref_s = chain.metrics(ideal, raw, "pocs", iterations=p.pocs_reference_iterations,
                                            tolerance=0.0)
    for k, v in pocs_ref.items():
        out.add("reference-pocs", p.pocs_reference_iterations, pocs_ref_s, k, 0.0, out.units[k], v)
    for it in p.pocs_iterations:
        times, vals = [], None
        for _ in range(max(p.repeat, 3)):  # cheap, and timing on a shared machine is noisy
            vals, _, dt = chain.metrics(ideal, raw, "pocs", iterations=it, tolerance=0.0)
            times.append(dt)
        for k, v in vals.items():
            out.add("pocs", it, min(times), k, abs(v - pocs_ref[k]), out.units[k], v)
        log(f"  POCS {it} iterations: {min(times):.2f} s")
    info: dict = {}
    default_vals, _, default_s = chain.metrics(ideal, raw, "pocs", info=info)
    return {"iterations_done": info.get("iterations"), "wall_s": default_s,
            "deviation": {k: abs(v - pocs_ref[k]) for k, v in default_vals.items()}, "value": default_vals}


def _context_step(p, chain, out: _Rows, log, oi, ideal, study_seed, ref, ref_vals, default_imgs):
    """Sensor-noise spread and the spread between CFAs (the scale a render
    error is read against): (noise std per metric, CFA values)."""
    from .task_values import task_seed

    noise_std = {}
    if p.noise_seeds:
        log(f"  sensor noise: {p.noise_seeds} seeds ...")
        per_seed = [chain.metrics(ideal, chain.capture(oi, p.cfa, "all", study_seed + i), p.demosaic)[0]
                    for i in range(p.noise_seeds)]
        for k in ref_vals:
            noise_std[k] = float(np.std([s[k] for s in per_seed], ddof=1))
            out.add("sensor-noise", p.noise_seeds, None, k, noise_std[k], out.units[k],
                    float(np.mean([s[k] for s in per_seed])))
    cfa_values: dict[str, dict] = {}
    if not p.compare_cfas:
        return noise_std, cfa_values
    methods = list(dict.fromkeys([p.demosaic, "pocs"]))
    log(f"  CFA spread: {', '.join(p.compare_cfas)} ({', '.join(methods)}) ...")
    for c in p.compare_cfas:
        raw_c = chain.capture(oi, c, "all", task_seed(p.seed, p.name, c, p.luminance_cd_m2))
        for method in methods:
            cfa_values.setdefault(method, {})[c] = chain.metrics(ideal, raw_c, method)[0]
    for method in methods:
        prefix = "" if method == p.demosaic else "pocs-"
        for k in ref_vals:
            v = sorted(cfa_values[method][c][k] for c in p.compare_cfas)
            gap = min((b - a for a, b in zip(v, v[1:])), default=float("nan"))
            out.add(f"{prefix}cfa-spread", len(v), None, k, v[-1] - v[0], out.units[k])
            out.add(f"{prefix}cfa-gap", len(v), None, k, gap, out.units[k])
    if len(p.compare_cfas) >= 2 and default_imgs:
        log(f"  CFA differences at {p.default_spp} spp ({len(default_imgs)} render(s)) vs the reference ...")
        pair, common = _difference_deviation(chain, p, ref, default_imgs, list(ref_vals))
        for k in ref_vals:
            out.add("cfa-pairs", p.default_spp, None, k, pair[k], out.units[k])
            out.add("cfa-common", p.default_spp, None, k, common[k], out.units[k])
    return noise_std, cfa_values


def _steps(p) -> int:
    """How many progress lines :func:`run_convergence` logs for ``p`` (one per unit of work)."""
    return (6 + len(p.spp_levels) + (p.default_seeds or 0) + 1 + len(p.pocs_iterations) + (1 if p.noise_seeds else 0)
            + (2 if p.compare_cfas and len(p.compare_cfas) >= 2 else 1 if p.compare_cfas else 0))


def run_convergence(plan: ConvergencePlan, *, log=None, progress: bool = False) -> ConvergenceResult:
    """Measure error against run time for ``plan`` (module docstring), in
    four steps: the reference, the spp levels, POCS iterations, and the
    context (sensor noise, CFA spread).  ``log``: a callable for progress
    lines (default: stderr); ``progress``: a bar on a terminal, advanced by
    each of those lines."""
    from ..io.progress import progress_bar, stderr_log
    from .task_values import task_seed

    bar = progress_bar(_steps(plan), "convergence", enabled=progress)
    write = log or stderr_log()

    def log(msg):
        write(msg)
        bar.update(1)

    try:
        return _run(plan, log, task_seed)
    finally:
        bar.close()


def _run(plan: ConvergencePlan, log, task_seed) -> ConvergenceResult:
    p = plan
    chain = _Chain(p)
    out = _Rows(p.name)
    t_start = time.perf_counter()
    ref, region, exact, ref_times, ref_vals, metric_floor = _reference_step(p, chain, out, log)
    level_times, default_imgs = _levels_step(p, chain, out, log, ref, region, ref_vals)
    study_seed = task_seed(p.seed, p.name, p.cfa, p.luminance_cd_m2)
    oi = chain.optical(ref)
    ideal = chain.ideal(oi)
    raw = chain.capture(oi, p.cfa, "all", study_seed)
    pocs_default = _pocs_step(p, chain, out, log, ideal, raw)
    noise_std, cfa_values = _context_step(p, chain, out, log, oi, ideal, study_seed, ref, ref_vals, default_imgs)
    del default_imgs
    summary = summarise(p, out.rows, out.units, ref_vals, metric_floor, region, exact, ref_times, level_times,
                        pocs_default, noise_std, cfa_values, time.perf_counter() - t_start)
    return ConvergenceResult(p, out.rows, summary)


def _difference_deviation(chain, p, ref, renders, metrics) -> tuple[dict, dict]:
    """How the default spp's render error moves the differences between CFAs.

    Each CFA in ``p.compare_cfas`` is captured (sensor noise as the render
    stage's, ``p.render_noise``) from the reference and from each default-spp render, processed with ``p.demosaic``, and
    measured.  With d_c = m_c(render) - m_c(reference): returns per metric
    (rms over renders and CFA pairs of d_a - d_b, which is what can reorder
    two CFAs; rms over renders of the mean over CFAs of d_c, a shift common
    to every CFA, which cannot).
    """
    from .task_values import task_seed

    def values(img):
        oi = chain.optical(img)
        ideal = chain.ideal(oi)
        return {c: chain.metrics(ideal, chain.capture(oi, c, p.render_noise,
                                                     task_seed(p.seed, p.name, c, p.luminance_cd_m2)),
                                 p.demosaic)[0] for c in p.compare_cfas}

    at_ref = values(ref)
    pair_sq, common_sq = {k: [] for k in metrics}, {k: [] for k in metrics}
    for img in renders:
        got = values(img)
        for k in metrics:
            d = np.array([got[c][k] - at_ref[c][k] for c in p.compare_cfas])
            common_sq[k].append(float(d.mean()) ** 2)
            pair_sq[k].extend(float(a - b) ** 2 for i, a in enumerate(d) for b in d[i + 1:])
    return ({k: float(np.sqrt(np.mean(v))) for k, v in pair_sq.items()},
            {k: float(np.sqrt(np.mean(v))) for k, v in common_sq.items()})


def _mean_ratio(a, b, region=None):
    """mean(a) / mean(b) per band (turns 'relative to a' into 'relative to b')."""
    if region is not None:
        y0, x0, y1, x1 = region
        a, b = a[y0:y1, x0:x1], b[y0:y1, x0:x1]
    ma = a.reshape(-1, a.shape[-1]).mean(axis=0)
    mb = b.reshape(-1, b.shape[-1]).mean(axis=0)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(mb > 0, ma / mb, np.nan)


def _exact_error(plan: ConvergencePlan, ref) -> dict | None:
    """The reference's error against the exact box integral of a built-in
    chart's pattern (None for other scenes): relative rms per band."""
    from ..render import charts

    name = plan.name
    if plan.is_3d or name not in ("slanted-edge", "chirp", "gray-bar", "macbeth") or Path(plan.scene).suffix:
        return None
    white = np.asarray(ref.meta["white_radiance"], dtype=np.float64)  # at the render's luminance
    if name == "macbeth":
        from .. import spectra

        # A patch's band value is the box mean of D65(l) rho(l) (the product of
        # the interpolated colour-science tables), scaled as the white is.
        wl = np.asarray(ref.wavelengths, dtype=np.float64)
        _, tables = spectra.colorchecker_tables()
        scale = white / spectra.illuminant("D65", wl)
        d65 = spectra.illuminant_table("D65")
        exact = np.broadcast_to(white * charts.SURROUND_REFLECTANCE, ref.data.shape).copy()
        for table, patch in zip(tables, charts.macbeth_layout(plan.width, plan.height)):
            y0, x0, y1, x1 = patch["rect"]
            exact[y0:y1, x0:x1] = scale * spectra.band_average_product([d65, table], wl)
    else:
        pattern = charts.exact_reflectance(name, plan.width, plan.height, plan.oversample)
        exact = pattern[..., None] * white[None, None, :]
    e = relative_rms_per_band(ref.data, exact)
    return {"what": "reference vs the exact box integral of the chart (independent of Mitsuba)",
            "relative_rms_median_band": float(np.nanmedian(e)), "relative_rms_worst_band": float(np.nanmax(e))}


# -------------------------------------------------------------- summaries

