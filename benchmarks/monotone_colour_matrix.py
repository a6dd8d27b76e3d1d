"""The colour matrix's regularisation against light (issue 22, docs/isp.md).

Before: the Tikhonov weights came from each capture's own noise, so the
matrix sharpened (and its noise gain rose) as the light rose.  After: from
the sensor's noise with the scene white at the full well, one matrix per
sensor and CFA.  This prints, for a few CFAs on a small puppy, S-CIELAB and
SSIM (bilinear, mean over realisations) and the matrix's condition number
at each luminance under both rules, and the exposure policy given.

    python3 benchmarks/monotone_colour_matrix.py [--policy reference|program] [--seeds 3]
"""

from __future__ import annotations

import argparse

import numpy as np

import cfa_mitsuba as cm
from cfa_mitsuba.isp import colour_matrix, pipeline
from cfa_mitsuba.sensor import ExposureProgram
from cfa_mitsuba.study.chain import CameraChain, ChainSettings


def _capture_rule(raw, epr, white):
    """The rule before issue 22: the capture's own noise at an 18 % grey."""
    if (raw.settings or {}).get("noise") == "off":
        return None
    read = float((raw.settings.get("sensor") or {}).get("read_noise_e") or 0.0)
    return colour_matrix.channel_noise(epr @ white, read_noise_e=read)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--policy", default="reference", choices=("reference", "program"))
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--cfas", default="cmy2,rgbw2,rgbw3,bayer")
    ap.add_argument("--luminances", default="12,50,100")
    args = ap.parse_args()
    img = cm.render.render_cached("puppy", width=120, height=106, spp=8)
    chain = CameraChain(ChainSettings(exposure_program=ExposureProgram(args.policy)))
    lums = [float(v) for v in args.luminances.split(",")]
    new_rule = pipeline._fit_noise
    print(f"policy {args.policy}; puppy 120 x 106, 8 spp; bilinear; {args.seeds} realisations")
    print("rule     cfa     " + "  ".join(f"L={L:g}: S-CIELAB  SSIM   cond" for L in lums))
    for rule, fn in (("capture", _capture_rule), ("sensor", new_rule)):
        pipeline._fit_noise = fn
        try:
            for cfa in args.cfas.split(","):
                cells = []
                for L in lums:
                    cond = chain.settings.base_condition(luminance=L)
                    oi = chain.optical(img, cond, "puppy")
                    ideal = chain.ideal(oi, cond, "puppy")
                    vals, cond_n = [], 0.0
                    for seed in range(args.seeds):
                        raw = chain.capture(oi, cfa, cond, seed)
                        out = chain.process(raw, "bilinear", cond)
                        res, _, _ = chain.measure(ideal, out, ["scielab", "ssim"], cond)
                        vals.append((float(res["scielab"]), float(res["ssim"])))
                        cond_n = out.meta["isp"]["condition_number"]
                    s, q = np.mean(vals, axis=0)
                    cells.append(f"{s:8.3f} {q:6.3f} {cond_n:6.2f}")
                print(f"{rule:8s} {cfa:7s} " + "  ".join(f"      {c}" for c in cells))
        finally:
            pipeline._fit_noise = new_rule


if __name__ == "__main__":
    main()
