"""Speed of the eight metrics at the paper's size (636 x 720; chirp and gray
bar 500 x 500), and of the whole set for one (CFA, demosaic).

    python benchmarks/bench_metrics.py [--repeat N] [--json PATH]

``--json PATH`` also writes the times, budgets, load average and date to
PATH; docs/metrics.md's "Speed" table is generated from the committed
docs/data/bench_metrics.json.

Prints a table: median wall time per metric over N runs, and the budget it
must meet (issue 5: S-CIELAB < 1 s, MDSI and HaarPSI < 0.3 s each, the whole
set < 3 s).  Inputs are synthetic but realistic: a smooth random scene in
absolute XYZ (white 100 cd/m^2) and a 'camera' copy with blur, noise and a
colour shift; a blurred slanted edge; a chirp with aliasing colour.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time

import numpy as np
from scipy.ndimage import gaussian_filter
from scipy.special import erf

sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))

import cfa_mitsuba.metrics as cm  # noqa: E402
from cfa_mitsuba.metrics import colourspace as mc  # noqa: E402

H, W = 636, 720
WHITE = np.array([95.05, 100.0, 108.9])


def scene():
    rng = np.random.default_rng(0)
    lin = gaussian_filter(rng.random((H, W, 3)), (6, 6, 0)) * 1.6 - 0.3
    lin = np.clip(lin, 0.01, 0.95)
    ideal = mc.linear_to_xyz(lin)
    camera = mc.linear_to_xyz(np.clip(gaussian_filter(lin, (0.8, 0.8, 0)) * [1.03, 1.0, 0.96]
                                      + rng.normal(0, 0.01, lin.shape), 0, 1))
    return ideal, camera


def edge():
    y, x = np.mgrid[0:H, 0:W].astype(float)
    t = np.radians(5.0)
    d = (x - W / 2) * np.cos(t) - (y - H / 2) * np.sin(t)
    v = 0.2 + 0.6 * 0.5 * (1 + erf(d / (np.sqrt(2) * 1.2)))
    return np.repeat(v[..., None], 3, axis=2)


def chirp(n=500):
    x = np.arange(n, dtype=float)
    f = 1.0 * x / n  # cy/px, 0 .. 2 x Nyquist
    y = 0.5 + 0.45 * np.sin(2 * np.pi * np.cumsum(f))
    ideal = mc.linear_to_xyz(np.repeat(np.repeat(y[None, :, None], n, 0), 3, 2))
    cam_lin = np.repeat(np.repeat(y[None, :, None], n, 0), 3, 2) * (1 + 0.3 * f[None, :, None] * [1, -1, 0.5])
    return ideal, mc.linear_to_xyz(np.clip(cam_lin, 0, 1)), f * n / 10.0


def gray_bar(n=500):
    steps = np.repeat(np.linspace(0.9, 0.03, 10), n // 10)
    ideal = mc.linear_to_xyz(np.repeat(np.repeat(steps[None, :, None], n, 0), 3, 2))
    noise = np.random.default_rng(1).normal(0, 0.005, ideal.shape)
    return ideal, ideal * (1 + noise)


def timeit(fn, repeat):
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--json", metavar="PATH", help="also write the measured times to PATH (JSON)")
    args = ap.parse_args(argv)
    ideal, camera = scene()
    e = edge()
    c_ideal, c_cam, c_freq = chirp()
    g_ideal, g_cam = gray_bar()
    rects = [(r * 100 + 30, c * 110 + 30, r * 100 + 80, c * 110 + 90) for r in range(4) for c in range(6)]
    spd = W / 10.0

    def srgb_pair():
        return mc.xyz_to_srgb8(ideal, WHITE), mc.xyz_to_srgb8(camera, WHITE)

    a8, b8 = srgb_pair()
    cases = [
        ("delta-e (24 patches)", lambda: cm.delta_e(ideal, camera, WHITE, patches=rects), None),
        ("delta-e (per pixel)", lambda: cm.delta_e(ideal, camera, WHITE), None),
        ("scielab (spd 72)", lambda: cm.scielab(ideal, camera, WHITE, samples_per_degree=spd), 1.0),
        ("ssim", lambda: cm.ssim(a8, b8), None),
        ("mtf (auto ROI)", lambda: cm.mtf(e), None),
        ("moire (500 x 500)", lambda: cm.moire(c_ideal, c_cam, WHITE, frequency_cy_per_deg=c_freq), None),
        ("achromatic (500 x 500)", lambda: cm.achromatic(g_ideal, g_cam, WHITE), None),
        ("mdsi", lambda: cm.mdsi(a8, b8), 0.3),
        ("haarpsi", lambda: cm.haarpsi(a8, b8), 0.3),
        ("xyz -> sRGB8 (both)", srgb_pair, None),
        ("mean_match", lambda: cm.mean_match(camera, ideal), None),
    ]

    def whole_set():
        cam = cm.mean_match(camera, ideal)
        x8, y8 = mc.xyz_to_srgb8(ideal, WHITE), mc.xyz_to_srgb8(cam, WHITE)
        cm.delta_e(ideal, cam, WHITE, patches=rects)
        cm.scielab(ideal, cam, WHITE, samples_per_degree=spd)
        cm.ssim(x8, y8)
        cm.mtf(e)
        cm.moire(c_ideal, cm.mean_match(c_cam, c_ideal), WHITE, frequency_cy_per_deg=c_freq)
        cm.achromatic(g_ideal, cm.mean_match(g_cam, g_ideal), WHITE)
        cm.mdsi(x8, y8)
        cm.haarpsi(x8, y8)

    cases.append(("whole set, one (CFA, demosaic)", whole_set, 3.0))
    whole_set()  # warm-up: imports (colour-science, scikit-image)
    print(f"metrics at {H} x {W} (chirp, gray bar 500 x 500); median of {args.repeat}; {os.cpu_count()} CPU(s)")
    print(f"{'metric':<32} {'time (s)':>9} {'budget (s)':>11}  ok")
    failed, rows = False, []
    for name, fn, budget in cases:
        t = timeit(fn, args.repeat)
        ok = "" if budget is None else ("yes" if t < budget else "NO")
        failed |= ok == "NO"
        rows.append({"metric": name, "time_s": t, "budget_s": budget})
        print(f"{name:<32} {t:9.3f} {'' if budget is None else f'{budget:.1f}':>11}  {ok}")
    if args.json:
        import json
        from datetime import datetime, timezone
        from pathlib import Path

        load = os.getloadavg()[0] if hasattr(os, "getloadavg") else None
        out = {"rows": rows, "repeat": args.repeat, "size": [H, W], "cpus": os.cpu_count(), "load_average_end": load,
               "date": datetime.now(timezone.utc).strftime("%Y-%m-%d")}
        tmp = Path(args.json).with_suffix(".tmp")
        tmp.write_text(json.dumps(out, indent=1) + "\n")
        tmp.replace(args.json)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
