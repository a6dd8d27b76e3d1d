"""Colours, markers, metric labels and number formats shared by every figure
and table of the report, so that a CFA has one colour and one marker
everywhere.

Colours are Paul Tol's colour-blind-safe qualitative schemes (Tol 2021,
"Colour schemes", SRON/EPS/TN/09-002): 'muted' plus 'light' for the CFAs;
the demosaicing methods are greys with line styles and line-only markers,
so a method is never read as a CFA; the ideal sensor is always a broad
grey line.  Past nine CFAs colour alone no longer separates them for every
reader, so each CFA also has its own marker and, from the tenth on, a
dashed line.
"""

from __future__ import annotations

__all__ = ["MetricDisplay", "metric_display", "cfa_styles", "demosaic_styles", "fmt_value"]

from dataclasses import dataclass

#: Tol 'muted' (9) then three of Tol 'light' (drawn dashed), told apart under the common colour-vision
#: deficiencies together with the markers below.  No black: black is the ideal sensor's.
_CFA_COLOURS = ("#332288", "#CC6677", "#117733", "#DDCC77", "#88CCEE", "#882255", "#44AA99", "#999933",
                "#AA4499", "#EE8866", "#77AADD", "#BBCC33")
_CFA_MARKERS = ("o", "s", "^", "D", "v", "P", "X", "*", "h", "<", ">", "p")
#: Demosaicing methods are coded apart from the CFAs: greys (never a CFA's colour), each with its own line
#: style and an unfilled marker shape that no CFA uses.
_DEMOSAIC_COLOURS = ("#1a1a1a", "#5a5a5a", "#8c8c8c", "#b0b0b0", "#3d3d3d", "#737373", "#a0a0a0")
_DEMOSAIC_MARKERS = ("1", "2", "3", "4", "+", "x", "|")
_DEMOSAIC_LINES = ("-", "--", "-.", ":", (0, (5, 1, 1, 1)), (0, (3, 1, 1, 1, 1, 1)), (0, (1, 1)))


@dataclass(frozen=True)
class MetricDisplay:
    """How a metric is named, shown and read: a view of its record
    (:mod:`cfa_mitsuba.metrics.record`) with the unit as typeset."""

    short: str          # column / axis label
    long: str           # what it measures
    unit: str           # display unit ('' for unitless)
    decimals: int
    higher_better: bool
    paper: str          # the paper's name and section


#: Units as the report typesets them.
_DISPLAY_UNITS = {"dE00": "ΔE00", "dEab": "ΔE*ab", "dE76": "ΔE*ab", "L*": "ΔL*"}


def metric_display(name: str) -> MetricDisplay:
    """The display info of a metric, from its record; an unknown metric gets a plain one."""
    from ..metrics import METRICS

    r = METRICS.get(name)
    if r is None:
        return MetricDisplay(name, name, "", 3, True, "—")
    return MetricDisplay(r.label, r.description, _DISPLAY_UNITS.get(r.unit, r.unit), r.decimals, r.higher_is_better,
                      r.paper)


def fmt_value(metric: str, value) -> str:
    """A metric value with its usual number of decimals ('—' when absent)."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        return "—"
    if v != v:
        return "—"
    return f"{v:.{metric_display(metric).decimals}f}"


def cfa_styles(cfas) -> dict:
    """``{cfa: dict(color, marker, linestyle)}`` in the study's CFA order."""
    out = {}
    for i, c in enumerate(cfas):
        out[c] = dict(color=_CFA_COLOURS[i % len(_CFA_COLOURS)], marker=_CFA_MARKERS[i % len(_CFA_MARKERS)],
                      linestyle="-" if (i // 9) % 2 == 0 else "--")
    return out


def demosaic_styles(demosaics) -> dict:
    """``{demosaic: dict(color, linestyle, marker)}`` in the study's order."""
    return {d: dict(color=_DEMOSAIC_COLOURS[i % len(_DEMOSAIC_COLOURS)],
                    linestyle=_DEMOSAIC_LINES[i % len(_DEMOSAIC_LINES)],
                    marker=_DEMOSAIC_MARKERS[i % len(_DEMOSAIC_MARKERS)])
            for i, d in enumerate(demosaics)}
