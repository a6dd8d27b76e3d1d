"""The report's "Units and conventions" list: what each number is, how a
bound, a score and a decision are made (one rule each, the study's: study/censored.py,
study/decisions.py), and where the files are."""

from __future__ import annotations

__all__ = ["convention_items", "practical_items"]

from html import escape


def practical_items() -> list[str]:
    """One line per scored metric: its practical difference and where it comes from (the metric records)."""
    from ..metrics import METRICS

    out = []
    for r in METRICS.values():
        if r.scored and r.practical_difference:
            amounts = ", ".join(f"{v:g} %" if u == "%" else f"{v:g} {u}".rstrip() for u, v in r.practical_difference)
            out.append(f"{escape(r.label)}: {escape(amounts)} ({escape(r.practical_source)})")
    return out


def convention_items(res) -> list[str]:
    """The list's items as HTML strings."""
    from ..study.censored import DEFAULT_CONVENTION

    items = [
        "<b>Ideal sensor</b>: the same optics and pixel with CIE 1931 colour-matching functions at every pixel, "
        "no mosaic and no noise (ISETCam's 'idealxyz'); every metric compares the camera's output with it. "
        "The camera output is mean-matched to the ideal before comparison (its scale factor is in the details).",
        "<b>ΔE00</b>: CIEDE2000; <b>ΔE*ab</b>: CIE 1976; both relative to the scene white. <b>ΔL grey</b>: the "
        "mean |ΔL*| of the six grey patches (the paper's Table 1 'Mean ΔL').",
        "<b>S-CIELAB</b>: Zhang-Wandell spatial filtering, then CIEDE2000 per pixel; the table holds the mean "
        "over the image. <b>SSIM</b>, <b>MDSI</b>, <b>HaarPSI</b>: on the 8-bit sRGB images (MDSI 0 = "
        "identical, the others 1 = identical).",
        "<b>MTF50</b>: the frequency where the ISO 12233 luminance MTF (0.3R + 0.6G + 0.1B) falls to 0.5, in "
        "cycles per millimetre on the sensor (Nyquist = 1 / (2 × pixel pitch)).",
        "<b>MSP</b>: moiré starting point, the chirp frequency in cycles per degree of visual angle where the "
        "block-mean chroma C*ab first exceeds the threshold (25). The paper reports a pixel position under "
        "the name 'cpd'; ours is a true frequency, so its numbers are not the paper's.",
        "<b>Bounds</b> (one rule everywhere): a realisation with no moiré up to the chirp's top frequency "
        "gives a lower bound, not a measurement. metrics.csv's <code>censored_count</code> says how many of a "
        "value's realisations are bounds; with none the value is their mean; with some it is their "
        "Kaplan-Meier median (a measurement while fewer than half are bounds), printed with the count; "
        "only when every realisation is a bound is the value printed as ≥ (<code>censored</code> true). "
        f"In the scores each realisation's bound is scored at the <b>{DEFAULT_CONVENTION}</b> between the best "
        "measured MSP of the study and the range's best end: above every measurement, below the ideal's 1. "
        "Tables, the figures and the decisions use these scores; decisions.csv says whether an answer changes "
        "with a bound scored at the bound itself (1) or at the best measured value.",
        "<b>AR error</b>: mean |ΔL*| along the gray bar's central row, ten columns left out at each end.",
        "<b>Scores</b> (eq. 8): (value − worst) / (best − worst) with the ranges listed above, so 1 is best for "
        "every metric; a CFA's score for a demosaic is the mean of its metric scores (Table 3), 'total' the "
        "mean over demosaics; ranks: 1 = best, ties share the lower rank.",
        "<b>Decisions</b>: a CFA is named best only when its rank interval (paired comparisons over the "
        "realisations) is exactly 1 and its lead over the next is at least the practical difference: for a "
        "mean score, what a practical difference on one of its metrics makes to the mean. Practical differences "
        "(the metric records): " + "; ".join(practical_items()) + "; SNR10: one third of a stop (ISO 12232's "
        "speed steps).",
        "<b>Table marks</b>: a red box marks the best value of a metric for a demosaic (the paper's red boxes); "
        "† a value outside its score range; ≥ an MSP that is a lower bound in every realisation; k/n≥ a value "
        "with k of its n realisations bounds; ↑/↓ higher/lower is better. Hover a cell for its score and rank.",
        "<b>Colours</b>: each CFA keeps one colour and marker in every figure (Paul Tol's colour-blind-safe "
        "schemes; markers and line styles tell CFAs apart where colours are close).",
        "<b>Files</b>: every figure is also in <code>figures/</code> next to this report (PNG and SVG); the "
        "numbers are in <code>metrics.csv</code>, <code>scores.csv</code> and <code>decisions.csv</code>, each "
        "edge's MTF curve in <code>mtf.csv</code>, each patch's error in <code>patches.csv</code>, each gray "
        "step's SNR in <code>steps.csv</code>, the rest of the curves, maps and crops in <code>details/</code>. "
        "Rebuild with <code>cfa-mitsuba report RESULTS_DIR</code>.",
    ]
    from .field_units import unit_items

    items[5:5] = unit_items(res)  # after MTF50 and MSP
    return items
