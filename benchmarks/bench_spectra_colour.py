"""Colour error of the paper's 12 CFAs with their family spectra sets and
with the one-camera Nikon set: mean dE00 on the rendered Macbeth chart,
bilinear, 100 cd/m^2, mean-matched to the ideal XYZ sensor.

    python benchmarks/bench_spectra_colour.py

Noise 'all' is the mean over seeds 0, 1, 2; 'off' is one noise-free capture.
With the Nikon set every 3-colour CFA spans the same colour space, so 11 of
the 12 land within a few percent (issue 12); with the family sets the
filters decide (docs/sensor.md s. 5.2).
"""

from __future__ import annotations

import warnings

import numpy as np

warnings.simplefilter("ignore")

import cfa_mitsuba as cm  # noqa: E402

CFAS = ["bayer", "rgb1", "rgb2", "rgb3", "rgb4", "rgb5", "cmy1", "cmy2", "cmy3", "rgbw1", "rgbw2", "rgbw3"]


def mean_de(oi, ideal, geo, cfa, noise, seeds):
    vals = []
    for seed in seeds:
        raw = cm.sensor.capture(oi, cfa, luminance_cd_m2=100, seed=seed, noise=noise)
        cam = cm.metrics.mean_match(cm.isp.process(raw, "bilinear").xyz, ideal.xyz)
        vals.append(float(cm.metrics.delta_e(ideal.xyz, cam, ideal.white_xyz, patches=geo["patches"])))
    return float(np.mean(vals))


def main():
    scene = cm.render.render("macbeth")
    oi = cm.optics.compute_optics(scene)
    ideal = cm.isp.process(cm.sensor.capture_ideal(oi, luminance_cd_m2=100))
    geo = cm.metrics.scene_geometry(scene.meta, ideal.xyz.shape)
    print("| CFA | family set | dE00 family | dE00 nikon-d5100 | dE00 family, noise off | dE00 nikon, noise off |")
    print("|---|---|---|---|---|---|")
    res = {}
    for name in CFAS:
        fam, nik = cm.sensor.get_cfa(name), cm.sensor.get_cfa(name, spectra="nikon-d5100")
        row = [mean_de(oi, ideal, geo, c, noise, seeds) for noise, seeds in (("all", (0, 1, 2)), ("off", (0,)))
               for c in (fam, nik)]
        res[name] = row
        print(f"| {name} | {fam.spectra} | " + " | ".join(f"{v:.3f}" for v in row) + " |", flush=True)
    for k, label in ((0, "family sets"), (1, "nikon-d5100")):
        v = np.array([res[n][k] for n in CFAS if n != "cmy2"])
        print(f"\n{label}, the 11 CFAs other than cmy2: {v.min():.3f} .. {v.max():.3f} dE00, "
              f"spread {100 * (v.max() / v.min() - 1):.1f} %")


if __name__ == "__main__":
    main()
