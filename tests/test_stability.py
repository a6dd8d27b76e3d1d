"""Numerical stability on stiff and extreme cases (issue 7): the matrix of
docs/stability.md, one parametrised test per row.

Every row asserts its documented outcome: a finite result within a stated
bound, or a one-line :class:`CfaMitsubaError` naming the problem (for the
command line: exit 2, one line, no traceback); never a silent NaN or a
traceback.  Inputs are small: synthetic spectral images built in numpy and
chart renders of a few thousand pixels (closed-form charts; one 2-pixel
path-traced puppy).

``python tests/test_stability.py`` runs every row and prints its measured
outcome: the numbers in docs/stability.md come from there.
"""


from __future__ import annotations

import pytest

import stability_rows_images  # noqa: F401  (each row module registers its rows in CASES)
import stability_rows_inputs  # noqa: F401
import stability_rows_light  # noqa: F401
from stability_common import CASES

# ------------------------------------------------------------------ the test

@pytest.mark.parametrize("row", list(CASES), ids=list(CASES))
def test_stability(row):
    CASES[row]()


if __name__ == "__main__":  # the measured outcomes for docs/stability.md
    import time

    for row, fn in CASES.items():
        t = time.perf_counter()
        out = fn()
        print(f"| {row} | {out} | {time.perf_counter() - t:.2f} s |", flush=True)
