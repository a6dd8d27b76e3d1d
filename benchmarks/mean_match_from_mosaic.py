"""Research for issue 49's open decision: the mean-matching scale as the
study computes it (the ideal image's interior mean over the demosaiced
camera output's, one scalar for X, Y and Z, 10 px border) against the same
scale estimated without demosaicing, from the white-balanced mosaic's
per-channel interior means through the colour matrix.  With the estimate,
mean matching would no longer need the whole output, and the regions of
interest (study/roi.py) could stay on with it; this prints how far the two
scales are apart on the quick study's charts and CFAs, every demosaic,
noise on, 100 cd/m^2.

    PYTHONPATH=$PWD python3 benchmarks/mean_match_from_mosaic.py
"""

from __future__ import annotations

import sys
import tomllib
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

import cfa_mitsuba as cm  # noqa: E402
from cfa_mitsuba.isp.pipeline import prepare, process_prepared  # noqa: E402
from cfa_mitsuba.metrics.preprocess import reference_interior_mean  # noqa: E402

BORDER = 10  # mean_match's default


def _mosaic_mean_xyz(p) -> float:
    """Mean of X, Y, Z over the interior from the balanced mosaic alone."""
    h, w = p.balanced.shape
    th, tw = p.cfa.pattern.shape
    ys, xs = np.mgrid[0:h, 0:w]
    inner = (ys >= BORDER) & (ys < h - BORDER) & (xs >= BORDER) & (xs < w - BORDER)
    names = p.cfa.pattern[ys % th, xs % tw]
    means = np.array([p.balanced[inner & (names == c)].mean() for c in p.cfa.channels])
    return float((means @ p.fit.matrix).mean())


def main() -> int:
    quick = tomllib.loads((REPO / "configs" / "quick.toml").read_text())
    diffs = []
    print(f"{'scene':13s} {'cfa':6s} {'demosaic':19s} estimate / exact - 1")
    for scene in quick["scenes"]:
        img = cm.render.render_cached(scene, **quick.get("render", {}).get(scene, {}))
        ideal = cm.isp.process(cm.sensor.capture(img, "ideal", luminance_cd_m2=100.0))
        ref_mean = reference_interior_mean(ideal.xyz)
        for cfa in quick["cfas"]:
            p = prepare(cm.sensor.capture(img, cfa, luminance_cd_m2=100.0, noise="all", seed=3))
            estimate = ref_mean / _mosaic_mean_xyz(p)
            h, w = p.balanced.shape
            for method in quick["demosaics"]:
                out = process_prepared(p, method)
                exact = ref_mean / float(out.xyz[BORDER:h - BORDER, BORDER:w - BORDER].mean())
                diffs.append(estimate / exact - 1.0)
                print(f"{scene:13s} {cfa:6s} {method:19s} {100 * diffs[-1]:+.4f} %", flush=True)
    d = np.abs(diffs)
    print(f"largest {100 * d.max():.4f} %, median {100 * np.median(d):.4f} % over {d.size} camera outputs")
    return 0


if __name__ == "__main__":
    sys.exit(main())
