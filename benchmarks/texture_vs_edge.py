"""The dead-leaves texture MTF against the slanted-edge MTF of the same
chain, and what each denoiser takes from one and the other: the numbers
docs/metrics.md ("Texture") quotes, generated from the JSON this writes.

    PYTHONPATH=$PWD nice -n 5 python3 benchmarks/texture_vs_edge.py --json docs/data/texture_vs_edge.json

The charts of tests/metrics/test_texture.py (dead-leaves 640 x 512 EXR,
120 x 120 analysed camera pixels; edges 640 x 576 and 320 x 288 EXR),
bilinear demosaicing, f/4, 2.2 um pixels:

- ``linear``: noise off, no denoising; per CFA (``mono``: no mosaic,
  ``bayer``), edge and texture metric, the largest |texture / edge - 1|
  over the rings below 0.2 cy/px and up to and including 0.25, and its
  value at 0.25; plus the analytic MTF (diffraction weighted by D65 x
  ybar, times the pixel box) at 0.25 against mono's texture MTF;
- ``denoised``: Bayer, noise on (seed 4), the mean over 0.1-0.25 cy/px of
  the cross-correlation texture MTF over the edge MTF, both through the
  same denoiser, per (method, scale, luminance).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

import cfa_mitsuba as cm
from cfa_mitsuba.metrics import evaluate
from cfa_mitsuba.metrics.geometry import scene_geometry
from cfa_mitsuba.metrics.inputs import MetricInputs

DENOISED = (("nl-means", 1.0, 3.0), ("nl-means", 1.0, 10.0), ("nl-means", 1.0, 30.0), ("wavelet", 1.0, 3.0),
            ("wavelet-ti", 1.0, 3.0), ("wavelet-ti", 2.0, 30.0))


def _inputs(img, cfa="bayer", lum=100.0, noise="off", denoise="none", scale=1.0, seed=0):
    raw = cm.sensor.capture(img, cfa, luminance_cd_m2=lum, noise=noise, seed=seed)
    ideal = cm.sensor.capture(img, "ideal", luminance_cd_m2=lum)
    out = cm.isp.process(raw, "bilinear", denoise=denoise, denoise_options={} if denoise == "none" else {"scale": scale})
    return MetricInputs(ideal.raw, out.xyz, out.white_xyz, geometry=scene_geometry(img.meta, out.xyz.shape),
                        pixel_pitch_um=2.2)


def _edge(img, **kw):
    rec = evaluate("mtf", _inputs(img, **kw)).details["records"]["lum"]
    return lambda f: np.interp(f, rec["freq_cy_px"], rec["mtf"])


def _analytic(f_cy_px: float) -> float:
    """Diffraction MTF at f/4 (weighted by D65 x ybar, 400-700 nm) x the 2.2 um pixel's box."""
    import colour

    from cfa_mitsuba.optics.diffraction import diffraction_mtf

    wl = np.arange(400, 701, 10)
    ybar = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    d65 = colour.SDS_ILLUMINANTS["D65"]
    w = np.array([ybar[v][1] * d65[v] for v in wl])
    d = sum(wi * float(diffraction_mtf(f_cy_px / 2.2e-3, v, 4.0)) for wi, v in zip(w / w.sum(), wl))
    return float(d * np.sinc(f_cy_px))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", type=Path, help="write the numbers here")
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    chart = cm.render.render_cached("dead-leaves", width=640, height=512)
    edges = {"640x576": cm.render.render_cached("slanted-edge", width=640, height=576),
             "320x288": cm.render.render_cached("slanted-edge", width=320, height=288)}
    linear = {}
    for cfa in ("mono", "bayer"):
        for ename, eimg in edges.items():
            edge = _edge(eimg, cfa=cfa)
            for metric in ("texture-mtf", "texture-mtf-cross"):
                d = evaluate(metric, _inputs(chart, cfa=cfa)).details
                f = d["freq_cy_px"]
                sel = (f > 0) & (f <= 0.25 + 1e-9)
                err = d["mtf"][sel] / edge(f[sel]) - 1.0
                row = {"max_below_0.2_pct": 100 * float(np.abs(err[f[sel] < 0.2]).max()),
                       "max_to_0.25_pct": 100 * float(np.abs(err).max()),
                       "at_0.25_pct": 100 * float(np.interp(0.25, f[sel], err)),
                       "texture_at_0.25": float(np.interp(0.25, f, d["mtf"])), "edge_at_0.25": float(edge(0.25))}
                linear[f"{cfa}/{ename}/{metric}"] = row
                print(f"{cfa:5s} edge {ename} {metric:17s} " + "  ".join(f"{k} {v:.3f}" for k, v in row.items()))
    denoised = {}
    for name, scale, lum in DENOISED:
        kw = dict(lum=lum, noise="all", denoise=name, scale=scale, seed=4)
        d = evaluate("texture-mtf-cross", _inputs(chart, **kw)).details
        f = d["freq_cy_px"]
        mid = (f >= 0.1) & (f < 0.25)
        ratio = float(np.mean(d["mtf"][mid] / _edge(edges["640x576"], **kw)(f[mid])))
        denoised[f"{name}@{scale:g}/L{lum:g}"] = ratio
        print(f"{name} x{scale:g} at {lum:g} cd/m^2: texture / edge over 0.1-0.25 cy/px {ratio:.3f}")
    out = {"linear": linear, "denoised": denoised, "analytic_at_0.25": _analytic(0.25),
           "seconds": time.perf_counter() - t0}
    print(f"analytic MTF at 0.25 cy/px {out['analytic_at_0.25']:.3f}; {out['seconds']:.0f} s")
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(out, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
