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
  value at 0.25, the edge's luminance being the texture's (CIE Y: the Y
  row of linear sRGB's matrix as the edge metric's ``weights``), and the
  edge at 0.25 with the metric's default luminance (the paper's 0.3 R +
  0.6 G + 0.1 B); plus the analytic MTF (diffraction weighted by D65 x
  ybar, times the pixel box) at 0.25 against mono's texture MTF, and
  Bayer bilinear's in-band response at 0.25 (tests/bayer_in_band.py);
- ``denoised``: Bayer, noise on (seed 4), the mean over 0.1-0.25 cy/px of
  the cross-correlation texture MTF over the edge MTF, both through the
  same denoiser, per (method, scale, luminance); for the wavelet methods
  at 3 cd/m^2, where both curves are near zero above 0.1 cy/px, also the
  spread of that ratio over seeds 4-6 (``denoised_seed_spread``).
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


def _y_weights() -> tuple:
    """CIE Y from linear sRGB (the Y row of its RGB-to-XYZ matrix): the edge
    metric's ``weights`` that give the texture metrics' luminance."""
    import colour

    return tuple(float(v) for v in colour.models.RGB_COLOURSPACE_sRGB.matrix_RGB_to_XYZ[1])


def _edge(img, weights=None, **kw):
    extra = {} if weights is None else {"weights": weights}
    rec = evaluate("mtf", _inputs(img, **kw), **extra).details["records"]["lum"]
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
    y_weights = _y_weights()
    for cfa in ("mono", "bayer"):
        for ename, eimg in edges.items():
            edge = _edge(eimg, y_weights, cfa=cfa)
            paper_edge = _edge(eimg, cfa=cfa)
            for metric in ("texture-mtf", "texture-mtf-cross"):
                d = evaluate(metric, _inputs(chart, cfa=cfa)).details
                f = d["freq_cy_px"]
                sel = (f > 0) & (f <= 0.25 + 1e-9)
                err = d["mtf"][sel] / edge(f[sel]) - 1.0
                row = {"max_below_0.2_pct": 100 * float(np.abs(err[f[sel] < 0.2]).max()),
                       "max_to_0.25_pct": 100 * float(np.abs(err).max()),
                       "at_0.25_pct": 100 * float(np.interp(0.25, f[sel], err)),
                       "texture_at_0.25": float(np.interp(0.25, f, d["mtf"])), "edge_at_0.25": float(edge(0.25)),
                       "edge_paper_luminance_at_0.25": float(paper_edge(0.25))}
                linear[f"{cfa}/{ename}/{metric}"] = row
                print(f"{cfa:5s} edge {ename} {metric:17s} " + "  ".join(f"{k} {v:.3f}" for k, v in row.items()))
    denoised, spread = {}, {}
    for name, scale, lum in DENOISED:
        ratios, edge_at_02 = [], []
        for seed in (4, 5, 6) if name.startswith("wavelet") and lum <= 3.0 else (4,):
            kw = dict(lum=lum, noise="all", denoise=name, scale=scale, seed=seed)
            d = evaluate("texture-mtf-cross", _inputs(chart, **kw)).details
            f = d["freq_cy_px"]
            mid = (f >= 0.1) & (f < 0.25)
            edge = _edge(edges["640x576"], y_weights, **kw)
            ratios.append(float(np.mean(d["mtf"][mid] / edge(f[mid]))))
            edge_at_02.append(float(edge(0.2)))
        key = f"{name}@{scale:g}/L{lum:g}"
        denoised[key] = ratios[0]
        if len(ratios) > 1:  # where both curves are near zero the ratio is a ratio of noise: its spread over seeds
            spread[key] = {"seeds": [4, 5, 6], "min": min(ratios), "max": max(ratios),
                           "edge_at_0.2_max": max(edge_at_02)}
        print(f"{name} x{scale:g} at {lum:g} cd/m^2: texture / edge over 0.1-0.25 cy/px "
              + ", ".join(f"{r:.3f}" for r in ratios) + f" (edge at 0.2 cy/px {max(edge_at_02):.3f} at most)")
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))  # the test's own reference
    from bayer_in_band import in_band as bayer_in_band, ring_mean, y_of_channels

    weights = y_of_channels(edges["640x576"])
    in_band = {"along_x": bayer_in_band(weights, 0.25, 0.0), "ring": ring_mean(weights, 0.25)}
    mono_edge = linear["mono/640x576/texture-mtf"]["edge_at_0.25"]
    in_band["times_mono_edge_along_x"] = in_band["along_x"] * mono_edge
    in_band["times_mono_texture_ring"] = in_band["ring"] * linear["mono/640x576/texture-mtf-cross"]["texture_at_0.25"]
    print("Bayer bilinear in-band response at 0.25 cy/px: " + "  ".join(f"{k} {v:.4f}" for k, v in in_band.items()))
    out = {"linear": linear, "denoised": denoised, "analytic_at_0.25": _analytic(0.25),
           "bayer_bilinear_in_band_at_0.25": in_band, "denoised_seed_spread": spread,
           "seconds": time.perf_counter() - t0}
    print(f"analytic MTF at 0.25 cy/px {out['analytic_at_0.25']:.3f}; {out['seconds']:.0f} s")
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(out, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
