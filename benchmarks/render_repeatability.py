"""Is a render with the same seed the same bit for bit?  Renders a scene
twice with identical settings (no cache) in one process and writes how many
spectral samples differ and by how much.

    PYTHONPATH=$PWD python3 benchmarks/render_repeatability.py [--scene puppy] [--width 360 --height 318]
                                                               [--spp N] [--seed 1] [--json FILE]

Found while measuring issue 49: two trees' puppy renders of the same seed
differed in their last bits.  The charts are closed-form and identical; a
path-traced scene at a low sample count is identical too, but at its default
count (hundreds of samples a pixel) Mitsuba's LLVM variant adds a pixel's
samples from several threads in an order that changes between runs, so
float32 sums differ in their last bits.  The render cache keeps one render
per key, so a study is reproducible from its cache; two renders made apart
are equal only to this precision.  With one render thread
(``CFA_MITSUBA_THREADS=1`` in the environment, recorded in the JSON as
``threads``) the two are identical.  docs/scenes.md quotes the JSON.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))


def compare(scene: str, **settings) -> dict:
    """Two renders of ``scene`` with ``settings``: the count of samples
    (pixels x bands) that differ, the largest absolute difference in
    W/(m^2 sr nm) and the largest relative to the render's own value."""
    import cfa_mitsuba as cm

    t0 = time.perf_counter()
    a = cm.render.render(scene, **settings)
    b = cm.render.render(scene, **settings)
    wall = time.perf_counter() - t0
    x, y = np.asarray(a.data, dtype=np.float64), np.asarray(b.data, dtype=np.float64)
    differ = x != y
    rel = np.abs(x - y)[differ] / np.maximum(np.abs(x[differ]), np.finfo(np.float32).tiny)
    return {"scene": scene, "settings": {k: v for k, v in settings.items() if v is not None},
            "spp": a.meta.get("spp"), "variant": a.meta.get("variant"), "shape": list(x.shape),
            "threads": os.environ.get("CFA_MITSUBA_THREADS"), "samples": int(x.size), "differing_samples": int(differ.sum()),
            "differing_share": float(differ.mean()),
            "max_abs_difference": float(np.abs(x - y).max()) if x.size else 0.0,
            "max_rel_difference": float(rel.max()) if rel.size else 0.0,
            "wall_s_both": wall}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default="puppy")
    ap.add_argument("--width", type=int, default=360)
    ap.add_argument("--height", type=int, default=318)
    ap.add_argument("--spp", type=int, help="samples per pixel (default: the scene's)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--json", help="also write the record here")
    args = ap.parse_args(argv)
    got = compare(args.scene, width=args.width, height=args.height, spp=args.spp, seed=args.seed)
    print(f"{got['scene']} {got['shape'][1]} x {got['shape'][0]} x {got['shape'][2]} bands, {got['spp']} spp, "
          f"{got['variant']}: {got['differing_samples']:,} of {got['samples']:,} samples differ "
          f"({100 * got['differing_share']:.3f} %), at most {got['max_abs_difference']:.3g} W/(m^2 sr nm), "
          f"{got['max_rel_difference']:.3g} of the value")
    if args.json:
        Path(args.json).write_text(json.dumps(got, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
