"""Colours, markers, metric labels and number formats shared by every figure
and table of the report, so that a CFA has one colour and one marker
everywhere.

Colours are Paul Tol's colour-blind-safe qualitative schemes (Tol 2021,
"Colour schemes", SRON/EPS/TN/09-002): 'bright' for the demosaicing methods
and 'muted' plus 'light' for the CFAs; the ideal sensor is always a broad
grey line.  Past nine CFAs colour alone no longer separates them for every
reader, so each CFA also has its own marker and, from the tenth on, a
dashed line.
"""

from __future__ import annotations

__all__ = ["MetricInfo", "METRIC_INFO", "metric_info", "cfa_styles", "demosaic_styles", "fmt_value"]

from dataclasses import dataclass

#: Tol 'muted' (9) then three of Tol 'light' (drawn dashed), told apart under the common colour-vision
#: deficiencies together with the markers below.  No black: black is the ideal sensor's.
_CFA_COLOURS = ("#332288", "#CC6677", "#117733", "#DDCC77", "#88CCEE", "#882255", "#44AA99", "#999933",
                "#AA4499", "#EE8866", "#77AADD", "#BBCC33")
_CFA_MARKERS = ("o", "s", "^", "D", "v", "P", "X", "*", "h", "<", ">", "p")
#: Tol 'bright' for the (at most a handful of) demosaicing methods.
_DEMOSAIC_COLOURS = ("#4477AA", "#EE6677", "#228833", "#CCBB44", "#66CCEE", "#AA3377", "#BBBBBB")
_DEMOSAIC_LINES = ("-", "--", "-.", ":", (0, (5, 1, 1, 1)), (0, (3, 1, 1, 1, 1, 1)), (0, (1, 1)))


@dataclass(frozen=True)
class MetricInfo:
    """How a metric is named, shown and read."""

    short: str          # column / axis label
    long: str           # what it measures
    unit: str           # display unit ('' for unitless)
    decimals: int
    higher_better: bool
    paper: str          # the paper's name and section


METRIC_INFO = {
    "delta-e": MetricInfo("ΔE00", "colour error, mean CIEDE2000 over the 24 ColorChecker patches", "ΔE00", 2,
                          False, "ΔE (s. 2.2.1, Fig 8)"),
    "scielab": MetricInfo("S-CIELAB", "colour reproduction error, mean S-CIELAB ΔE00 over the image", "ΔE00", 2,
                          False, "ΔEs (s. 2.2.2, Fig 10)"),
    "ssim": MetricInfo("SSIM", "structural similarity of the 8-bit sRGB luma", "", 3, True,
                       "SSIM (s. 2.2.3, Fig 10)"),
    "mtf": MetricInfo("MTF50", "luminance MTF50 of the slanted edge (ISO 12233)", "cy/mm", 1, True,
                      "MTF50 (s. 2.2.4, Figs 6, 11)"),
    "moire": MetricInfo("MSP", "moiré starting point on the chirp", "cy/deg", 2, True,
                        "MSP (s. 2.2.5, Figs 12-13)"),
    "achromatic": MetricInfo("AR error", "achromatic reproduction error, mean |ΔL*| along the gray bar", "ΔL*", 3,
                             False, "ΔR (s. 2.2.6, Fig 14)"),
    "mdsi": MetricInfo("MDSI", "mean deviation similarity index (0 = identical)", "", 3, False,
                       "MDSI (s. 2.2.7, Fig 15)"),
    "haarpsi": MetricInfo("HaarPSI", "Haar wavelet perceptual similarity (1 = identical)", "", 3, True,
                          "HaarPSI (s. 2.2.8, Fig 15)"),
    "delta-e76": MetricInfo("ΔE*ab", "colour error, mean CIE 1976 ΔE*ab over the 24 patches", "ΔE*ab", 2, False,
                            "—"),
    "delta-l": MetricInfo("ΔL grey", "mean |ΔL*| over the six grey patches (the paper's Table 1 'Mean ΔL')",
                          "ΔL*", 2, False, "Table 1"),
    "scielab-interior": MetricInfo("S-CIELAB interior", "S-CIELAB mean ΔE00 away from the image border",
                                   "ΔE00", 2, False, "—"),
}


def metric_info(name: str) -> MetricInfo:
    """The display info of a metric; an unknown metric gets a plain one."""
    return METRIC_INFO.get(name, MetricInfo(name, name, "", 3, True, "—"))


def fmt_value(metric: str, value) -> str:
    """A metric value with its usual number of decimals ('—' when absent)."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        return "—"
    if v != v:
        return "—"
    return f"{v:.{metric_info(metric).decimals}f}"


def cfa_styles(cfas) -> dict:
    """``{cfa: dict(color, marker, linestyle)}`` in the study's CFA order."""
    out = {}
    for i, c in enumerate(cfas):
        out[c] = dict(color=_CFA_COLOURS[i % len(_CFA_COLOURS)], marker=_CFA_MARKERS[i % len(_CFA_MARKERS)],
                      linestyle="-" if (i // 9) % 2 == 0 else "--")
    return out


def demosaic_styles(demosaics) -> dict:
    """``{demosaic: dict(color, linestyle, marker)}`` in the study's order."""
    marks = ("o", "s", "^", "D", "v", "P", "X")
    return {d: dict(color=_DEMOSAIC_COLOURS[i % len(_DEMOSAIC_COLOURS)],
                    linestyle=_DEMOSAIC_LINES[i % len(_DEMOSAIC_LINES)], marker=marks[i % len(marks)])
            for i, d in enumerate(demosaics)}
