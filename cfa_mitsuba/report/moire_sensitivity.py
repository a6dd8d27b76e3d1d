"""How the moire starting point depends on the threshold: the MSP at 20, 25
(the paper's) and 30 C*ab, from each camera's stored block-mean chroma curve
(details/chirp/..., the first noise realisation), by the metric's own rule
(:func:`cfa_mitsuba.metrics.moire.msp_column`).  A ranking that turns on
the threshold shows here: a value that moves by more than a tenth between
20 and 30 is marked, and a bound (no moire up to the chirp's top frequency)
is written ≥ top.
"""

from __future__ import annotations

__all__ = ["THRESHOLDS", "msp_by_threshold", "sensitivity_table"]

import html

import numpy as np

#: C*ab thresholds shown: the paper's 25 and one step either side.
THRESHOLDS = (20.0, 25.0, 30.0)


def msp_by_threshold(detail: dict, thresholds=THRESHOLDS) -> list[tuple[float, bool]] | None:
    """[(MSP cy/deg, passed)] per threshold from one moire detail record, or None."""
    from ..metrics.moire import msp_column

    try:
        freq = np.asarray(detail["frequency_cy_per_deg"], dtype=float)
        bm = np.asarray(detail["block_mean_test"], dtype=float)
        block = int(detail.get("block", 15))
    except (KeyError, TypeError, ValueError):
        return None
    out = []
    for t in thresholds:
        col, passed = msp_column(freq, bm, t, block)
        out.append((float(freq[col]), passed))
    return out


def sensitivity_table(res) -> str | None:
    """HTML: per demosaic and CFA, the MSP at each threshold and the peak block-mean chroma."""
    lum = res.primary_luminance
    if lum is None:
        return None
    scene, pairs = res.detail_pairs("moire", lum)
    if scene is None or not pairs:
        return None
    head = "".join(f"<th>MSP at C*ab {t:g}{' (paper)' if t == 25 else ''}</th>" for t in THRESHOLDS)
    out = [f'<table class="data"><thead><tr><th>demosaic</th><th>CFA</th>{head}<th>peak block-mean C*ab</th>'
           "</tr></thead><tbody>"]
    for cfa, dem, det in pairs:
        got = msp_by_threshold(det)
        if got is None:
            continue
        vals = [v for v, _ in got]
        moved = abs(vals[0] - vals[-1]) > 0.1 * max(abs(vals[1]), 1e-9)
        cells = "".join(f"<td>{'' if ok else '≥'}{v:.2f}</td>" for v, ok in got)
        peak = float(np.nanmax(np.asarray(det["block_mean_test"], dtype=float)))
        flag = ' class="warn"' if moved else ""
        out.append(f"<tr{flag}><td>{html.escape(dem)}</td><th>{html.escape(cfa)}</th>{cells}<td>{peak:.1f}</td></tr>")
    out.append("</tbody></table>")
    return "".join(out)
