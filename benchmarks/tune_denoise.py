"""Choose each denoiser's one tuning constant by the rule of
``cfa_mitsuba/isp/denoise/_tuning.py`` and write the data.

    PYTHONPATH=$PWD nice -n 5 python3 benchmarks/tune_denoise.py [--out cfa_mitsuba/data/denoise_tuning.csv]

For every method, every strength of the grid and every capture (three
scikit-image photographs x three light levels, Bayer, the default
sensor's noise): the mean squared error (electrons^2) of the raw-domain
denoised mosaic against the noise-free mosaic.  Writes one row per
(method, strength) with the nine errors and their sum, and prints each
method's winner (the constant to type into its record).
"""

from __future__ import annotations

import argparse
import csv
import sys
import time
from pathlib import Path

import numpy as np

GRID = (0.25, 0.5, 0.75, 1.0, 1.25, 1.5, 1.75, 2.0, 2.5, 3.0)
IMAGES = ("astronaut", "coffee", "chelsea")
LEVELS_E = (10.0, 50.0, 250.0)
CROP = 192
READ_E = 6.2
SEED = 20240


def _linear(name: str) -> np.ndarray:
    from skimage import data

    img = getattr(data, name)()[..., :3].astype(np.float64) / 255.0
    h, w = img.shape[:2]
    y0, x0 = (h - CROP) // 2, (w - CROP) // 2
    img = img[y0:y0 + CROP, x0:x0 + CROP]
    return np.where(img <= 0.04045, img / 12.92, ((img + 0.055) / 1.055) ** 2.4)  # IEC 61966-2-1 decoding


def captures():
    """[(label, clean mosaic e-, noisy mosaic e-, profile)]: Poisson + read + 12-bit ADC."""
    from cfa_mitsuba.isp.mosaic import geometry
    from cfa_mitsuba.isp.noise_profile import NoiseProfile
    from cfa_mitsuba.isp.synthetic import mosaic_image
    from cfa_mitsuba.sensor import SensorParams, get_cfa

    cfa = get_cfa("bayer")
    step = 1.0 / SensorParams().dn_per_electron  # electrons per DN at gain 1
    rng = np.random.default_rng(SEED)
    out = []
    for name in IMAGES:
        lin = mosaic_image(_linear(name), cfa)
        for level in LEVELS_E:
            clean = lin * (level / lin.mean())
            noisy = rng.poisson(clean) + READ_E * rng.standard_normal(clean.shape)
            noisy = np.round(noisy / step) * step
            profile = NoiseProfile(("R", "G", "B"), np.ones(3), np.full(3, READ_E**2 + step**2 / 12), {})
            out.append((f"{name}@{level:g}e", clean, noisy, profile))
    return geometry(cfa).index, out


def main(argv=None) -> int:
    from cfa_mitsuba.isp.denoise import denoise_mosaic, list_denoisers
    from cfa_mitsuba.isp.denoise import _REGISTRY  # the records, for the methods to tune

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default=str(Path(__file__).resolve().parents[1] / "cfa_mitsuba" / "data" /
                                         "denoise_tuning.csv"))
    args = ap.parse_args(argv)
    index, caps = captures()
    labels = [c[0] for c in caps]
    rows = []
    for name, _ in list_denoisers():
        rec = _REGISTRY[name]
        if rec.function is None:
            continue
        start = time.perf_counter()
        for k in GRID:
            errs = []
            for _, clean, noisy, profile in caps:
                # the record's own constant scaled to k: the strength applied is k
                out, _ = denoise_mosaic(noisy, index, profile, name, {"scale": k / rec.strength})
                errs.append(float(np.mean((out - clean) ** 2)))
            rows.append({"method": name, "strength": k, "total_mse": sum(errs), **dict(zip(labels, errs))})
        best = min((r for r in rows if r["method"] == name), key=lambda r: r["total_mse"])
        noisy_mse = sum(float(np.mean((c[2] - c[1]) ** 2)) for c in caps)
        print(f"{name:<11} best strength {best['strength']:g}: summed MSE {best['total_mse']:.2f} e-^2 "
              f"(noisy {noisy_mse:.2f}); {time.perf_counter() - start:.1f} s", file=sys.stderr)
    with open(args.out, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=["method", "strength", "total_mse", *labels])
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in r.items()})
    print(f"wrote {args.out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
