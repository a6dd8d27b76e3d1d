"""Render-stage benchmarks (issue 2, acceptance 3 and 4).  Prints tables.

    python3 benchmarks/bench_render.py [charts] [stock] [noise] [puppy]

(no argument: all four sections).

- charts: the four flat charts at paper size, each in a fresh process
  (``cfa-mitsuba render --no-cache``), and the total; plus the Mitsuba part
  alone (``render_time_s``).
- stock: our 31-band route against Mitsuba's own ``direct`` integrator
  writing a 3-channel XYZ ``hdrfilm`` (and ``path`` at the puppy's depth),
  same scene, spp and size, whole processes, cold (a new Python process
  each; Dr.Jit's on-disk kernel cache warm, as after any first run; the
  very first run of each also shown).
- noise: per-band relative noise against wall time on the research's
  ColorChecker emitter chart with *smooth* spectra (D65 x Ohta reflectance,
  linearly interpolated at 5 nm, so that wavelength sampling matters), for
  our spectral-quadrature route and for one 31-band ``specfilm`` pass.
- puppy: the full 636 x 720 puppy at default settings, two seeds: time and
  median relative luminance noise per pixel.

Wall-clock times depend on what else runs on the machine: the table header
prints the load average; re-run on a quiet machine for numbers to quote.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

CHARTS = ("macbeth", "slanted-edge", "chirp", "gray-bar")


def _load():
    return "load average %.2f %.2f %.2f, %d CPUs" % (*os.getloadavg(), os.cpu_count())


def _run(cmd, env=None) -> tuple[float, subprocess.CompletedProcess]:
    t = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True, cwd=REPO, env=env)
    dt = time.perf_counter() - t
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(map(str, cmd))} failed:\n{proc.stderr}")
    return dt, proc


def _ours(scene, out, extra=()):
    return _run([sys.executable, "-m", "cfa_mitsuba", "render", scene, "--out", str(out), "--no-cache", *map(str, extra)])


# ------------------------------------------------------------------ charts

def bench_charts():
    print(f"\n## Four charts at paper size, one fresh process each ({_load()})\n")
    print("| scene | size (rows x cols) | spp | process wall (s) | Mitsuba render (s) |")
    print("|---|---|---|---|---|")
    total = mitsuba_total = 0.0
    accuracy = []
    with tempfile.TemporaryDirectory() as tmp:
        for name in CHARTS:
            dt, _ = _ours(name, tmp)
            meta = json.loads((Path(tmp) / f"{name}.json").read_text())
            total += dt
            mitsuba_total += meta["render_time_s"]
            print(f"| {name} | {meta['height']} x {meta['width']} | {meta['spp']} | {dt:.1f} | {meta['render_time_s']:.2f} |")
            accuracy.append(_chart_accuracy(name, Path(tmp) / f"{name}.exr"))
    print(f"| **total** | | | **{total:.1f}** | {mitsuba_total:.2f} |")
    print("\nAccuracy of those renders (against colour-science band means and the exact box integrals):\n")
    for line in accuracy:
        print(f"- {line}")


def _chart_accuracy(name, exr):
    from cfa_mitsuba import spectra
    from cfa_mitsuba.io import read_spectral_exr
    from cfa_mitsuba.render import charts

    img = read_spectral_exr(exr)
    white = np.asarray(img.meta["white_radiance"])
    lum = spectra.luminance_cd_m2(img.data).mean()
    if name == "macbeth":
        # The exact band means of D65(l) x rho(l) (each linearly interpolated
        # from colour-science's tables), scaled as the render's white.
        _, tables = spectra.colorchecker_tables()
        d65 = spectra.illuminant_table("D65")
        scale = white / spectra.illuminant("D65", img.wavelengths)
        err = noise = 0.0
        for i, p in enumerate(img.meta["geometry"]["patches"]):
            y0, x0, y1, x1 = p["interior_rect"]
            pix = img.data[y0:y1, x0:x1].reshape(-1, img.data.shape[-1])
            exact = spectra.band_average_product([d65, tables[i]], img.wavelengths) * scale
            err = max(err, float(np.max(np.abs(pix.mean(0) / exact - 1))))
            noise = max(noise, float(np.max(pix.std(0) / pix.mean(0))))
        return (f"macbeth: worst patch-interior band error vs the band means of D65 x Ohta {100 * err:.1e} %, "
                f"worst band relative std in a patch {100 * noise:.1e} %, mean luminance {lum:.4f} cd/m^2")
    exact = charts.exact_reflectance(name, img.meta["width"], img.meta["height"], img.meta["oversample"])
    e = (img.data / white - exact[..., None]) / exact.max()
    hi = e[:, img.meta["width"] // 2:]
    return (f"{name}: anti-aliasing error vs the exact box integral, rms {100 * np.sqrt(np.mean(e ** 2)):.1e} % "
            f"of full scale (right half {100 * np.sqrt(np.mean(hi ** 2)):.1e} %), max {100 * np.abs(e).max():.1e} %, "
            f"mean luminance {lum:.4f} cd/m^2")


# ------------------------------------------------------------------- stock

def _stock_process(scene, integrator, spp, width, height, out):
    """(In a fresh process) render the same scene with a stock Mitsuba
    integrator into a 3-channel XYZ hdrfilm and write it."""
    from cfa_mitsuba.render import engine, variant
    from cfa_mitsuba.render.loading import load_scene

    sc, cfg = engine.resolve_settings(scene, width=width, height=height, spp=spp)
    mi = variant.load(cfg.variant)
    built = sc.build(cfg)
    film = {"type": "hdrfilm", "width": width, "height": height, "rfilter": {"type": "box"},
            "pixel_format": "xyz", "component_format": "float32"}
    sampler = {"type": "stratified", "sample_count": cfg.spp, "jitter": bool(sc.jitter)}
    integ = {"type": integrator}
    if integrator == "path":
        integ["max_depth"] = cfg.max_depth
    start = time.perf_counter()
    scene_obj = load_scene(mi, built, film, sampler, integ)
    img = mi.render(scene_obj, seed=0)
    mi.util.write_bitmap(out, img)
    print(json.dumps({"render_s": time.perf_counter() - start}))


def bench_stock():
    print(f"\n## Our 31-band route vs Mitsuba's stock integrators into an XYZ hdrfilm, whole processes ({_load()})\n")
    print("| scene | size | spp | route | first process (s) | repeat process (s) | ratio to `direct` (repeat) |")
    print("|---|---|---|---|---|---|---|")
    cases = [("macbeth", 720, 636, 16), ("puppy", 720, 636, 100)]
    with tempfile.TemporaryDirectory() as tmp:
        for scene, w, h, spp in cases:
            rows = {}
            routes = [("ours (31 bands)", None), ("Mitsuba direct, XYZ", "direct")]
            if scene == "puppy":
                routes[1:1] = [("ours (31 bands), max_depth 2: direct light, as `direct`", "ours-2")]
                routes.append(("Mitsuba path (same depth as ours), XYZ", "path"))
            for label, integ in routes:
                times = []
                for _ in range(2):
                    if integ is None or integ.startswith("ours"):
                        depth = ["--max-depth", integ.split("-")[1]] if integ else []
                        dt, _ = _ours(scene, tmp, ["--width", w, "--height", h, "--spp", spp, *depth])
                    else:
                        dt, _ = _run([sys.executable, __file__, "_stock", scene, integ, str(spp), str(w), str(h),
                                      str(Path(tmp) / f"{scene}-{integ}.exr")])
                    times.append(dt)
                rows[label] = times
            base = rows["Mitsuba direct, XYZ"][1]
            for label, (first, repeat) in rows.items():
                print(f"| {scene} | {h} x {w} | {spp} | {label} | {first:.1f} | {repeat:.1f} | {repeat / base:.2f} |")


# ------------------------------------------------------------------- noise

def _smooth_chart(mi, wl_edges, res):
    """The research's ColorChecker emitter chart: 24 area emitters with
    radiance D65 x Ohta reflectance as smooth 5-nm spectra (Mitsuba
    interpolates linearly); orthographic view; patch interiors."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        import colour
    d65 = colour.SDS_ILLUMINANTS["D65"]
    cc = colour.characterisation.SDS_COLOURCHECKERS["ColorChecker N Ohta"]
    grid = np.arange(380.0, 781.0, 5.0)
    e = np.interp(grid, d65.wavelengths, d65.values) / 100.0
    T = mi.ScalarTransform4f
    objs = {}
    rects = []
    p = res // 6
    for i, name in enumerate(cc):
        r, c = divmod(i, 6)
        rho = np.interp(grid, cc[name].wavelengths, cc[name].values)
        x0, y0 = c * p, r * p
        cx, cy = (x0 + p / 2) / res * 2 - 1, 1 - (y0 + p / 2) / res * 2
        objs[f"p{i}"] = {"type": "rectangle", "to_world": T().translate([cx, cy, 0]).scale(p / res),
                         "emitter": {"type": "area", "radiance": {"type": "irregular",
                                     "wavelengths": ", ".join(map(str, grid)), "values": ", ".join(map(str, e * rho))}}}
        m = max(2, p // 5)
        rects.append((y0 + m, x0 + m, y0 + p - m, x0 + p - m))
    sensor = {"type": "orthographic", "to_world": T().look_at(origin=[0, 0, 2], target=[0, 0, 0], up=[0, 1, 0])}
    return objs, sensor, rects


def _patch_noise(img, rects):
    rel = []
    for y0, x0, y1, x1 in rects:
        pix = img[y0:y1, x0:x1].reshape(-1, img.shape[-1])
        rel.append(pix.std(axis=0) / np.maximum(pix.mean(axis=0), 1e-12))
    rel = np.mean(rel, axis=0)  # per band, averaged over the 24 patches
    return float(np.median(rel)), float(rel.max())


def bench_noise(res=128):
    from cfa_mitsuba import spectra
    from cfa_mitsuba.render import variant
    from cfa_mitsuba.render.integrator import PLUGIN_NAME
    from cfa_mitsuba.render.light import BAND_INSET

    mi = variant.load(variant.choose_variant())
    import drjit as dr

    edges = spectra.band_edges(spectra.DEFAULT_WAVELENGTHS)
    objs, sensor, rects = _smooth_chart(mi, edges, res)
    print(f"\n## Per-band noise vs wall time, ColorChecker emitter chart with smooth spectra, {res} x {res} ({_load()})\n")
    print("Per-band relative std inside the 24 patch interiors (mean over patches), median and worst of the 31 bands;")
    print("wall time of a warm render (kernel compiled), one process.\n")
    print("| route | spp | wall (s) | median band noise | worst band noise |")
    print("|---|---|---|---|---|")

    def render(film, integ, spp):
        scene = mi.load_dict({"type": "scene", **objs, "integrator": integ,
                              "sensor": {**sensor, "film": film, "sampler": {"type": "stratified", "sample_count": spp}}})
        mi.render(scene, seed=1)  # compile
        t = time.perf_counter()
        img = np.array(mi.render(scene, seed=2))
        dr.sync_thread()
        return time.perf_counter() - t, img

    for spp in (1, 4, 16, 64):
        film = {"type": "hdrfilm", "width": res, "height": res, "rfilter": {"type": "box"}, "pixel_format": "luminance",
                "component_format": "float32"}
        integ = {"type": PLUGIN_NAME, "band_edges": ",".join(map(repr, edges.tolist())), "band_inset": BAND_INSET}
        dt, img = render(film, integ, spp)
        med, worst = _patch_noise(img[..., -31:], rects)
        print(f"| ours: spectral quadrature, 31 AOV bands | {spp} | {dt:.2f} | {100 * med:.3f} % | {100 * worst:.3f} % |")
    bands = {f"band_{i:02d}": {"type": "regular", "wavelength_min": float(lo), "wavelength_max": float(hi),
                               "values": f"{1 / (hi - lo)}, {1 / (hi - lo)}"} for i, (lo, hi) in enumerate(zip(edges[:-1], edges[1:]))}
    for spp in (16, 64, 256, 1024, 4096):
        film = {"type": "specfilm", "width": res, "height": res, "rfilter": {"type": "box"}, "component_format": "float32", **bands}
        dt, img = render(film, {"type": "direct"}, spp)
        med, worst = _patch_noise(img[..., :31], rects)
        print(f"| one 31-band specfilm pass (`direct`) | {spp} | {dt:.2f} | {100 * med:.2f} % | {100 * worst:.2f} % |")


# ------------------------------------------------------------------- puppy

def bench_puppy():
    import cfa_mitsuba as cm
    from cfa_mitsuba import spectra

    print(f"\n## Puppy at default settings, 636 x 720 ({_load()})\n")
    renders = []
    for seed in (1, 2):
        t = time.perf_counter()
        img = cm.render.render("puppy", seed=seed)
        renders.append((time.perf_counter() - t, img))
    a, b = (r[1].data / r[1].meta["scale_from_canonical"] for r in renders)
    ya, yb = spectra.luminance_cd_m2(a), spectra.luminance_cd_m2(b)
    # Pixels black in both renders (truncated paths under the dog, where
    # light needs more bounces than max_depth) have no relative noise.
    lit = (ya > 0) | (yb > 0)
    a, b, ya, yb = a[lit], b[lit], ya[lit], yb[lit]
    lum = np.abs(ya - yb) / (0.5 * (ya + yb))
    with np.errstate(invalid="ignore", divide="ignore"):
        ra, rb = a / a.sum(-1, keepdims=True), b / b.sum(-1, keepdims=True)
        ratio = np.sqrt(np.nanmean(((ra - rb) / (0.5 * (ra + rb))) ** 2, axis=-1))
    m = renders[0][1].meta
    print("| spp | max_depth | wall per render (s) | Mitsuba render (s) | median rel. luminance noise | "
          "median band-ratio difference between seeds (rms over bands) | median luminance difference between seeds |")
    print("|---|---|---|---|---|---|---|")
    print(f"| {m['spp']} | {m['max_depth']} | {renders[0][0]:.0f}, {renders[1][0]:.0f} | {m['render_time_s']:.0f} | "
          f"{100 * np.median(lum) / np.sqrt(2):.2f} % | {100 * np.nanmedian(ratio):.2f} % | {100 * np.median(lum):.2f} % |")
    print(f"\n({int((~lit).sum())} of {lit.size} pixels are black in both renders and left out.)")


def main(argv):
    if argv[:1] == ["_stock"]:
        scene, integ, spp, w, h, out = argv[1:7]
        _stock_process(scene, integ, int(spp), int(w), int(h), out)
        return
    sections = argv or ["charts", "stock", "noise", "puppy"]
    for s in sections:
        {"charts": bench_charts, "stock": bench_stock, "noise": bench_noise, "puppy": bench_puppy}[s]()


if __name__ == "__main__":
    main(sys.argv[1:])
