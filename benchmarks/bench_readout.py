"""quad-bayer read full, remosaic and binned (charge and digital) at low light:
achromatic error and SNR on the gray bar, MTF50 on the slanted edge, each
the mean of noise realisations with its 95 % t interval, and the binning's
noise argument checked on the raw mosaic.

    python benchmarks/bench_readout.py [--luminance 3] [--seeds 5] [--demosaic bilinear]

The noise argument (cfa_mitsuba/sensor/readout.py): a binned pixel holds
the charge of n^2 = 4 photodiodes, so against one photodiode of S
electrons its SNR is 4S / sqrt(4 (S + r^2)) = 2 SNR (digital binning: read
noise r, quantisation included, once per photodiode) and
4S / sqrt(4S + r^2) (charge binning: once per binned pixel), i.e. sqrt(4)
in the shot-noise limit and more than that when read noise counts.
"""

from __future__ import annotations

import argparse

import numpy as np
from scipy.stats import t as student_t

import cfa_mitsuba as cm
from cfa_mitsuba.study.chain import CameraChain, ChainSettings
from cfa_mitsuba.study.conditions import Condition

MODES = (("full", "charge"), ("remosaic", "charge"), ("bin", "charge"), ("bin", "digital"))


def interval(values) -> tuple[float, float, float]:
    v = np.asarray(values, dtype=float)
    half = student_t.ppf(0.975, v.size - 1) * v.std(ddof=1) / np.sqrt(v.size)
    return float(v.mean()), float(v.mean() - half), float(v.mean() + half)


def output_snr(xyz: np.ndarray, steps, border: int = 6) -> float:
    """Median over the gray steps of mean(Y) / std(Y) down each column of
    the step's interior (the bar is uniform vertically)."""
    h = xyz.shape[0]
    vals = []
    for s in steps:
        y = xyz[border:h - border, s["x0"] + border:s["x1"] - border, 1]
        if y.shape[1] > 0:
            vals.append(np.median(y.mean(axis=0) / y.std(axis=0, ddof=1)))
    return float(np.median(vals))


def raw_snr(raw, steps, n_block: int, border: int = 6) -> tuple[float, float]:
    """(median SNR of the G samples over the step interiors, median mean
    electrons of a photodiode there) of a raw mosaic (binned or not)."""
    e = (raw.raw - raw.black_level_dn) / raw.dn_per_electron
    k = n_block if raw.meta["readout"]["mode"] == "bin" else 1
    g = np.asarray(raw.pattern) == "G"
    th, tw = g.shape
    gm = g[np.arange(e.shape[0])[:, None] % th, np.arange(e.shape[1])[None, :] % tw]
    snr, mean_e = [], []
    for s in steps:
        x0, x1 = (s["x0"] + border) // k, (s["x1"] - border) // k
        sub, m = e[border // k: e.shape[0] - border // k, x0:x1], gm[border // k: e.shape[0] - border // k, x0:x1]
        v = sub[m]
        if v.size > 10:
            snr.append(v.mean() / v.std(ddof=1))
            mean_e.append(v.mean() / (k * k))
    return float(np.median(snr)), float(np.median(mean_e))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--luminance", type=float, default=3.0)
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--demosaic", default="bilinear")
    args = ap.parse_args()
    from cfa_mitsuba import render
    from cfa_mitsuba.render.charts import gray_steps

    bar = render.render_cached("gray-bar", width=500, height=240)
    edge = render.render_cached("slanted-edge", width=640, height=576)
    steps = gray_steps(bar.data.shape[1] // int(bar.meta.get("oversample") or 1))
    per_seed = {}
    for mode, binning in MODES:
        sensor = cm.sensor.SensorParams(readout=mode, binning=binning)
        chain = CameraChain(ChainSettings(sensor=sensor))
        cond = Condition(luminance=args.luminance, readout=mode)
        got = {"achromatic": [], "mtf": [], "snr_out": [], "snr_raw": [], "e_raw": []}
        for seed in range(args.seeds):
            for scene, image, metric in (("bar", bar, "achromatic"), ("edge", edge, "mtf")):
                for raw, ideal, _, ev in chain.evaluate(image, "quad-bayer", [args.demosaic], [metric], cond, seed,
                                                        scene_key=scene):
                    got[metric].append(float(ev.results[metric]))
                    if scene == "bar":
                        got["snr_out"].append(output_snr(ev.processed.xyz, steps))
                        s, e = raw_snr(raw, steps, 2)
                        got["snr_raw"].append(s)
                        got["e_raw"].append(e)
        per_seed[(mode, binning)] = {k: np.asarray(v) for k, v in got.items()}
    r = cm.sensor.SensorParams()
    q2 = 1.0 / (12 * r.dn_per_electron ** 2)  # quantisation variance of one code, e-^2
    print(f"quad-bayer at {args.luminance:g} cd/m^2, {args.demosaic}, {args.seeds} realisations (mean [95 % t interval])")
    print(f"{'readout':<16} {'achromatic dL*':>24} {'MTF50 cy/mm':>24} {'SNR gray bar (output Y)':>24} "
          f"{'SNR raw G':>24}")
    for (mode, binning), v in per_seed.items():
        name = mode if mode != "bin" else f"bin ({binning})"
        print(f"{name:<16} " + " ".join("{:8.3f} [{:7.3f}, {:7.3f}]".format(*interval(v[m]))
                                        for m in ("achromatic", "mtf", "snr_out", "snr_raw")))
    full = per_seed[("full", "charge")]
    s_e = float(np.mean(full["e_raw"]))
    r2 = r.read_noise_e ** 2
    pred_full = s_e / np.sqrt(s_e + r2 + q2)
    pred = {"charge": 4 * s_e / np.sqrt(4 * s_e + r2 + 16 * q2), "digital": 4 * s_e / np.sqrt(4 * (s_e + r2 + q2))}
    print(f"\nG photodiode signal (median over the steps): {s_e:.1f} e-; read noise {r.read_noise_e:g} e-, "
          f"quantisation {np.sqrt(q2):.2f} e- rms; predicted raw SNR full {pred_full:.3f}")
    for binning in ("charge", "digital"):
        b = per_seed[("bin", binning)]
        fmt = "{:.3f} [{:.3f}, {:.3f}]"
        print(f"bin ({binning}): raw SNR predicted {pred[binning]:.3f}; ratio to full: raw SNR "
              + fmt.format(*interval(b["snr_raw"] / full["snr_raw"])) + f" (predicted {pred[binning] / pred_full:.3f}, "
              "sqrt(4) = 2 in the shot limit); output SNR " + fmt.format(*interval(b["snr_out"] / full["snr_out"]))
              + "; achromatic full/bin " + fmt.format(*interval(full["achromatic"] / b["achromatic"]))
              + "; MTF50 bin/full " + fmt.format(*interval(b["mtf"] / full["mtf"])))

if __name__ == "__main__":
    main()
