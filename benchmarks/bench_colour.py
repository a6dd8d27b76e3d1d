"""Colour benchmark: CIEDE2000 of every CFA's colour correction, fitted on
one reflectance set and tested on the other, and of the whole pipeline on a
ColorChecker image against the ideal XYZ sensor.

    python benchmarks/bench_colour.py [--json PATH]

``--json PATH`` also writes both tables' numbers (per CFA) to PATH:
docs/isp.md's colour tables are generated from the committed
docs/data/bench_colour.json (about a minute).

Table 1 is spectral (noise-free camera responses of uniform patches under
D65 at 100 cd/m^2, white-balanced, through the N x 3 matrix): 'train' is
the 190 rawtoaces reflectances, 'chart' the 24 'ColorChecker N Ohta'
patches; the pipeline always fits on 'train'.  Table 2 renders nothing: a
ColorChecker radiance image (24 px patches) goes through the real optics
and sensor (``cm.sensor.capture``, noise off) and ``cm.isp.process``, and
is compared with ``capture(..., 'ideal')`` at the patch centres.
"""

from __future__ import annotations

import os
import time
import warnings

import numpy as np

warnings.simplefilter("ignore")

import cfa_mitsuba as cm  # noqa: E402
from cfa_mitsuba import spectra  # noqa: E402
from cfa_mitsuba.isp.colour_matrix import electrons_per_radiance_of, white_response  # noqa: E402
from cfa_mitsuba.study.chain import CameraChain, ChainSettings  # noqa: E402
from cfa_mitsuba.study.conditions import Condition  # noqa: E402

WL = spectra.DEFAULT_WAVELENGTHS
#: what --json writes: filled by the tables as they print
RESULTS: dict = {"spectral": [], "pipeline": []}
D65 = spectra.illuminant("D65", WL)
WHITE = D65 * (100.0 / spectra.luminance_cd_m2(D65, WL))


def de_on(fit, epr, refl):
    rad = refl * WHITE
    cam = rad @ epr.T / white_response(epr, WHITE)
    return cm.isp.delta_e00(fit.apply(cam), spectra.xyz_from_radiance(rad, WL), fit.white_xyz)


def spectral_table():
    train = spectra.training_reflectances(WL)
    _, chart = spectra.colorchecker(WL)
    print("| CFA | N | fit | cond | noise gain X, Y, Z | fitted on train: train mean/max | -> chart mean/max "
          "| fitted on chart: chart mean/max | -> train mean/max |")
    print("|---|---|---|---|---|---|---|---|---|")
    for name in cm.sensor.list_cfas():
        cfa = cm.sensor.get_cfa(name)
        epr = electrons_per_radiance_of(cfa.sensitivities(WL), WL)
        for wp in (True, False):
            on_train = cm.isp.fit_colour_matrix(epr, WHITE, WL, white_preserving=wp)
            on_chart = cm.isp.fit_colour_matrix(epr, WHITE, WL, white_preserving=wp, reflectances=chart)
            cells = []
            row = {"cfa": name, "channels": len(cfa.channels), "fit": "white-preserving" if wp else "least squares",
                   "condition_number": float(on_train.condition_number),
                   "noise_gain_xyz": [float(g) for g in on_train.noise_gain]}
            for fit, a, b, key in ((on_train, train, chart, "fit_train"), (on_chart, chart, train, "fit_chart")):
                da, db = de_on(fit, epr, a), de_on(fit, epr, b)
                cells += [f"{da.mean():.2f} / {da.max():.2f}", f"**{db.mean():.2f}** / {db.max():.2f}"]
                row[key] = {"own_mean": float(da.mean()), "own_max": float(da.max()),
                            "other_mean": float(db.mean()), "other_max": float(db.max())}
            RESULTS["spectral"].append(row)
            print(f"| {name} | {len(cfa.channels)} | {'white-preserving' if wp else 'least squares'} "
                  f"| {on_train.condition_number:.2f} | {', '.join(f'{g:.2f}' for g in on_train.noise_gain)} | "
                  + " | ".join(cells) + " |")


def pipeline_table():
    names, refl = spectra.colorchecker(WL)
    p = 24
    img = np.zeros((4 * p, 6 * p, WL.size))
    for k in range(24):
        r, c = divmod(k, 6)
        img[r * p:(r + 1) * p, c * p:(c + 1) * p] = refl[k] * WHITE
    scene = cm.SpectralImage(img, WL.copy(), {"white_radiance": WHITE.tolist(), "fov_deg": 5.0})
    # the study's camera chain, noise off, at the chart's own mean luminance
    chain = CameraChain(ChainSettings(noise="off"))
    cond = Condition(luminance=float(spectra.luminance_cd_m2(img, WL).mean()))
    oi = chain.optical(scene, cond)
    ideal = chain.ideal(oi, cond)

    def centres(x):
        m = p // 3
        return np.array([x[r * p + m:(r + 1) * p - m, c * p + m:(c + 1) * p - m].mean(axis=(0, 1))
                         for r in range(4) for c in range(6)])

    ref = centres(ideal.xyz)
    methods = ("bilinear", "laplacian", "adaptive-laplacian", "pocs")
    print("| CFA | " + " | ".join(f"{m} mean / max" for m in methods) + " | grey row (patches 19-24) max, bilinear |")
    print("|---|" + "---|" * len(methods) + "---|")
    for name in cm.sensor.list_cfas():
        raw = chain.capture(oi, name, cond, seed=0)
        cells, grey, row = [], None, {"cfa": name}
        for m in methods:
            de = cm.colorimetry.delta_e00(centres(chain.process(raw, m).xyz), ref, ideal.white_xyz)
            cells.append(f"{de.mean():.2f} / {de.max():.2f}")
            row[m] = {"mean": float(de.mean()), "max": float(de.max())}
            grey = de[18:].max() if grey is None else grey
        row["grey_max_bilinear"] = float(grey)
        RESULTS["pipeline"].append(row)
        print(f"| {name} | " + " | ".join(cells) + f" | {grey:.2f} |")


def main(argv=None):
    import argparse

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", metavar="PATH", help="also write both tables' numbers to PATH (JSON)")
    args = ap.parse_args(argv)
    t = time.perf_counter()
    print(f"# bench_colour ({os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f})\n")
    print("## 1. Colour correction, spectral: CIEDE2000, fitted on one set and tested on the other\n")
    spectral_table()
    print("\n## 2. Whole pipeline on a ColorChecker image vs the ideal sensor (noise off, patch centres)\n")
    pipeline_table()
    print(f"\n{time.perf_counter() - t:.1f} s")
    if args.json:
        import json
        import subprocess
        from datetime import datetime, timezone
        from pathlib import Path

        commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                                cwd=Path(__file__).parent).stdout.strip()
        out = {**RESULTS, "date": datetime.now(timezone.utc).strftime("%Y-%m-%d"), "commit": commit}
        tmp = Path(args.json).with_suffix(".tmp")
        tmp.write_text(json.dumps(out, indent=1) + "\n")
        tmp.replace(args.json)
        print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
