"""Benchmark of cfa-mitsuba design: the exhaustive pass over every distinct
4x4 layout of three letters (3^16 = 43 M raw tiles, translations and
mirrors folded: enumeration + vectorised proxy), the proxy's throughput
in candidates per second, and the full chain's time per candidate (from a
small design run through the study runner).

    python benchmarks/bench_design.py              # everything (minutes)
    python benchmarks/bench_design.py --no-fullchain

Target (issue 17): the 4x4 exhaustive pass in under 10 min on 2 cores.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))


def exhaustive_4x4() -> None:
    from cfa_mitsuba.design import layouts as L
    from cfa_mitsuba.design import proxy as P
    from cfa_mitsuba.design.search import fixed_models
    from cfa_mitsuba.design.spectra import letter_curves

    h = w = 4
    k = 3
    models = fixed_models(letter_curves("RGB", "isetcam-rgb"), "RGB")
    lo, hi = np.ones(k, int), np.full(k, h * w)
    t_enum = t_proxy = 0.0
    n = 0
    best = (np.inf, None)
    for i in range(L.n_chunks(h, w, k)):
        t = time.perf_counter()
        lay = L.enumerate_chunk(i, h, w, k, lo, hi)
        t_enum += time.perf_counter() - t
        t = time.perf_counter()
        got = P.evaluate_layouts(lay, h, w, models, P.ProxySettings(luminance_ratio=0.12))
        t_proxy += time.perf_counter() - t
        n += len(lay)
        if not len(lay):
            continue
        j = int(np.argmin(got["aliasing"]))
        if got["aliasing"][j] < best[0]:
            best = (float(got["aliasing"][j]), L.tile_text(lay[j], h, w, "RGB"))
    total = t_enum + t_proxy
    print(f"4x4, 3 letters: {L.raw_count(h, w, k):,} raw layouts -> {n:,} distinct (every letter present)")
    print(f"  enumeration + folding {t_enum:.1f} s, proxy {t_proxy:.1f} s: total {total:.1f} s "
          f"(target 600 s: {'met' if total < 600 else 'MISSED'})")
    print(f"  proxy throughput: {n / t_proxy:,.0f} candidates/s; end to end {n / total:,.0f} candidates/s")
    print(f"  least aliasing: {best[1]} ({best[0]:.4f})")


def fullchain() -> None:
    from cfa_mitsuba.design.config import load_design
    from cfa_mitsuba.design.run import run_design

    cfg = load_design(Path(__file__).resolve().parents[1] / "configs" / "design-quick.toml")
    with tempfile.TemporaryDirectory() as d:
        cached = "CFA_MITSUBA_CACHE" in os.environ
        os.environ.setdefault("CFA_MITSUBA_CACHE", str(Path(d) / "cache"))
        res = run_design(cfg, Path(d) / "out", progress=False, log=lambda m: None)
        n = len(res.fullchain)
        print(f"full chain (design-quick: {n} CFAs x {cfg.study.seeds} realisations, 3 scenes, renders "
              f"{'from $CFA_MITSUBA_CACHE' if cached else 'made fresh'}): {res.timing['fullchain_s']:.1f} s, "
              f"{res.timing['fullchain_s'] / n:.2f} s per CFA; search {res.timing['search_s']:.1f} s for "
              f"{len(res.candidates):,} candidates; total {res.timing['total_s']:.1f} s")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--no-fullchain", action="store_true")
    ap.add_argument("--no-exhaustive", action="store_true")
    args = ap.parse_args()
    print(f"{os.cpu_count()} CPU(s), load average {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    if not args.no_exhaustive:
        exhaustive_4x4()
    if not args.no_fullchain:
        fullchain()


if __name__ == "__main__":
    main()
