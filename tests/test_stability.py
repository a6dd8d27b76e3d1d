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
    import json
    import re
    import sys
    from datetime import datetime, timezone
    from pathlib import Path

    # ``--json PATH``: also write {rows, date, outcomes: {row: text}} to PATH (docs/data/stability.json,
    # from which docs_numbers fills docs/stability.md's "measured" cells; Markdown pipes escaped)
    out_path = Path(sys.argv[sys.argv.index("--json") + 1]) if "--json" in sys.argv else None
    outcomes = {}
    for row, fn in CASES.items():
        out = fn()
        # temporary folders differ per run: "…/" in their place
        outcomes[row] = re.sub(r"(?:/[\w.-]+)*/tmp\w{6,}/", "…/", str(out)).replace("|", "\\|")
        print(f"| {row} | {out} |", flush=True)
    if out_path:
        data = {"rows": len(CASES), "date": datetime.now(timezone.utc).strftime("%Y-%m-%d"), "outcomes": outcomes}
        tmp = out_path.with_suffix(".tmp")
        tmp.write_text(json.dumps(data, indent=1, ensure_ascii=False) + "\n")
        tmp.replace(out_path)
