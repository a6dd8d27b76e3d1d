"""``mtf.csv``: each slanted-edge capture's whole MTF curve, not only its
MTF50 (the e-SFR of :func:`cfa_mitsuba.metrics.mtf`).

One row per (scene, CFA, demosaic, condition, frequency): ``frequency_cy_px``
(cycles per pixel, normal to the edge), ``frequency_cy_mm`` (on the
sensor: cy/px x 1000 / pitch in um), ``mtf`` (the luminance record,
0.3 R + 0.6 G + 0.1 B, whose MTF50 is the scored value) and ``mtf_r``,
``mtf_g``, ``mtf_b`` (each colour channel of the camera output; empty where
a channel has no edge), up to 1 cy/px (twice Nyquist, the range of
ISETCam's aliasing percentage).  The ideal sensor's curve is there too
(``cfa`` 'ideal', ``demosaic`` 'none').  One realisation per capture: the
first, whose details the study keeps (:mod:`.detail_index`).
"""

from __future__ import annotations

__all__ = ["mtf_rows", "write_mtf_csv", "MTF_COLUMNS"]

from pathlib import Path

from .detail_index import KEY_COLUMNS, detail_entries, write_table

MTF_COLUMNS = [*KEY_COLUMNS, "frequency_cy_px", "frequency_cy_mm", "mtf", "mtf_r", "mtf_g", "mtf_b"]
#: The highest frequency kept, cy/px.
MAX_CY_PX = 1.0


def _curve(rec: dict | None):
    if not isinstance(rec, dict) or rec.get("mtf") is None or rec.get("freq_cy_px") is None:
        return None
    return [None if v is None else float(v) for v in rec["freq_cy_px"]], \
        [None if v is None else float(v) for v in rec["mtf"]]


def mtf_rows(entries) -> list[dict]:
    """The rows of :data:`MTF_COLUMNS` for the detail entries that hold an ``mtf`` result."""
    rows = []
    for e in entries:
        res = e.data.get("mtf")
        if not isinstance(res, dict) or not isinstance(res.get("records"), dict):
            continue
        recs = res["records"]
        main = _curve(recs.get("lum")) or _curve(recs.get("gray"))
        if main is None:
            continue
        freq, lum = main
        pitch = res.get("pixel_pitch_um")
        per_mm = 1000.0 / float(pitch) if pitch else None
        channels = {}
        for ch in ("R", "G", "B"):
            c = _curve(recs.get(ch))
            channels[ch] = c[1] if c is not None and len(c[1]) == len(lum) else [None] * len(lum)
        for i, f in enumerate(freq):
            if f is None or f > MAX_CY_PX + 1e-12:
                continue
            rows.append({**e.key(), "frequency_cy_px": f, "frequency_cy_mm": f * per_mm if per_mm else None,
                         "mtf": lum[i], "mtf_r": channels["R"][i], "mtf_g": channels["G"][i],
                         "mtf_b": channels["B"][i]})
    return rows


def write_mtf_csv(out_dir: Path, tasks, details_dir) -> Path | None:
    """Write ``out_dir/mtf.csv`` from the study's details (no MTF measured: no file)."""
    return write_table(Path(out_dir) / "mtf.csv", mtf_rows(detail_entries(tasks, details_dir)), MTF_COLUMNS)
