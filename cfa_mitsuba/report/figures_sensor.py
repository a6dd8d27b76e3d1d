"""The compared sensors' spectra: each CFA's channel QE curves as the study
captured them (``sensor_curves.csv``, written by the study runner), and a
note when the compared CFAs use different spectra sets (then a score
difference mixes the layout's effect with the dyes')."""

from __future__ import annotations

__all__ = ["read_sensor_curves", "spectra_note", "sensor_curves"]

from .figure import Absent, ReportFigure, new_figure

#: Line colours of the usual filter letters (others cycle through the rest).
_LETTER_COLOURS = {"R": "#CC3311", "G": "#228833", "B": "#4477AA", "C": "#33BBEE", "M": "#AA3377",
                   "Y": "#CCBB44", "W": "#555555"}
_OTHER = ("#EE7733", "#009988", "#BBBBBB", "#000000")


def read_sensor_curves(res):
    """The ``sensor_curves.csv`` table of a results directory, or None."""
    from ..io.guard import read_csv

    path = res.root / "sensor_curves.csv"
    if not path.is_file():
        return None
    try:
        t = read_csv(path, dtype={"cfa": str, "spectra": str, "sensor": str, "channel": str})
    except (OSError, ValueError):
        return None
    need = {"cfa", "spectra", "channel", "wavelength_nm", "qe"}
    return t if need <= set(t.columns) and len(t) else None


def spectra_note(res) -> str | None:
    """One sentence when the compared CFAs (those of metrics.csv) use
    different spectra sets."""
    t = read_sensor_curves(res)
    if t is None or not len(res.metrics):
        return None
    t = t[t["cfa"].isin(set(res.metrics["cfa"].astype(str)))]
    sets = t.drop_duplicates("cfa").set_index("cfa")["spectra"]
    if sets.nunique() < 2:
        return None
    listing = "; ".join(f"{s}: {', '.join(sets.index[sets == s])}" for s in dict.fromkeys(sets))
    return (f"The compared CFAs use {sets.nunique()} different spectra sets ({listing}): their scores differ "
            "by their layouts and by their filters' curves together.")


def sensor_curves(res):
    """One panel per CFA: its channels' QE against wavelength."""
    t = read_sensor_curves(res)
    if t is None:
        return Absent("sensor", "Sensor spectra", "sensor_curves.csv is absent (results written before the "
                                                  "study recorded its sensors' curves)")
    measured = set(res.metrics["cfa"].astype(str)) if len(res.metrics) else set()
    order = [c for c in res.cfas if c in measured] + sorted(measured - set(res.cfas))
    order = [c for c in order if c in set(t["cfa"])]  # the CFAs of metrics.csv whose curves were recorded
    if not order:
        return Absent("sensor", "Sensor spectra", "no CFA of metrics.csv has curves in sensor_curves.csv")
    t = t[t["cfa"].isin(order)]
    n = len(order)
    cols = min(4, n)
    rows = (n + cols - 1) // cols
    fig = new_figure(3.2 * cols, 2.4 * rows + 0.3)
    axes = fig.subplots(rows, cols, squeeze=False, sharex=True, sharey=True)
    top = float(t["qe"].max()) * 1.08 or 1.0
    for k, cfa in enumerate(order):
        ax = axes[k // cols][k % cols]
        g = t[t["cfa"] == cfa]
        other = iter(_OTHER * 4)
        for ch, gc in g.groupby("channel", sort=False):
            ax.plot(gc["wavelength_nm"], gc["qe"], color=_LETTER_COLOURS.get(ch) or next(other), label=ch, lw=1.4)
        ax.set_title(f"{cfa} ({g['spectra'].iloc[0]})", fontsize=9)
        ax.set_ylim(0, top)
        ax.legend(fontsize=7, ncol=len(g["channel"].unique()), loc="upper right", frameon=False)
        if k % cols == 0:
            ax.set_ylabel("QE (e-/photon)")
        if k // cols == rows - 1:
            ax.set_xlabel("wavelength (nm)")
    for k in range(n, rows * cols):
        axes[k // cols][k % cols].set_visible(False)
    fig.tight_layout()
    sensor = ", ".join(dict.fromkeys(t["sensor"].astype(str))) if "sensor" in t.columns else "default"
    caption = (f"Quantum efficiency of each channel as captured (band means on the render grid, IR-cut filter "
               f"included), pixel: {sensor}. Title: the CFA and its spectra set ('own': curves the CFA or sensor "
               "file gives itself).")
    note = spectra_note(res)
    if note:
        caption += " " + note
    return ReportFigure("sensor-curves", "sensor", "Spectra of the compared sensors", caption, fig)
