"""CPIQ texture acutance: the dead-leaves texture MTF weighted by the
contrast sensitivity function at a stated viewing condition (IEEE 1858).

    A = int_0^fN MTF_tex(v) S(v) dv / int_0^fN S(v) dv,   S(v) = 75 v^0.8 exp(-0.2 v) / 34.05

with v in cycles per degree at the eye, fN the camera's Nyquist frequency
there, and MTF_tex the noise-subtracted texture MTF (:mod:`.texture_mtf`).
The viewing condition maps the image's cycles per pixel to cycles per
degree: the image shown at 100 % (one image pixel per display pixel) on a
display of ``display_ppi`` pixels per inch seen from ``viewing_distance_m``;
ours by default is CPIQ's computer-monitor kind of view, a 100 ppi display
at 0.6 m (41 pixels per degree: the camera's Nyquist at 20.6 cy/deg, past
the CSF's peak at 4 cy/deg).  The integral stops at Nyquist (ISETCam's
``ISOAcutance`` integrates whatever range it is given; its header warns of
going past Nyquist), trapezoidal over the texture MTF's rings.  A perfect
texture MTF of 1 up to Nyquist gives 1; a sharpened image can exceed it.

References
----------
IEEE 1858-2016, Standard for Camera Phone Image Quality (CPIQ), texture
blur (acutance).  D. Baxter, F. Cao, H. Eliasson, J. Phillips,
"Development of the I3A CPIQ spatial metrics", Proc. SPIE 8293, Image
Quality and System Performance IX (2012) 829302 (the CSF and the viewing
conditions).  F. Cao, F. Guichard, H. Hornung, Proc. SPIE 7537 (2010)
75370E (the texture MTF).
"""

from __future__ import annotations

__all__ = ["RECORDS", "texture_acutance", "pixels_per_degree"]

import math

import numpy as np

from ..errors import require
from ._result import MetricResult
from ._texture import TEXTURE_SCENES, cpiq_csf
from .record import MetricRecord
from .texture_mtf import texture_mtf


def pixels_per_degree(display_ppi: float, viewing_distance_m: float) -> float:
    """Image pixels per degree of visual angle at the centre of a display of
    ``display_ppi`` viewed from ``viewing_distance_m`` at 100 %:
    d tan(1 deg) / pitch.

    >>> round(pixels_per_degree(100.0, 0.6), 2)
    41.23
    """
    pitch_m = 0.0254 / float(display_ppi)
    return float(viewing_distance_m) * math.tan(math.radians(1.0)) / pitch_m


def texture_acutance(reference_xyz, test_xyz, white_xyz, *, texture_roi, flat_roi, dead_leaves,
                     display_ppi: float = 100.0, viewing_distance_m: float = 0.6) -> MetricResult:
    """CPIQ texture acutance of a camera image of the dead-leaves chart (module doc).

    Parameters as :func:`~cfa_mitsuba.metrics.texture_mtf.texture_mtf`, and
    the viewing condition: ``display_ppi`` (pixels per inch of the display,
    the image at 100 %) and ``viewing_distance_m`` (metres).

    Returns
    -------
    MetricResult
        Headline: the acutance (unitless, 1 for a perfect texture MTF).
        Details: ``pixels_per_degree``, ``nyquist_cy_deg``, ``display_ppi``,
        ``viewing_distance_m``.

    Examples
    --------
    >>> from cfa_mitsuba.render.dead_leaves import camera_example
    >>> y, geometry = camera_example()
    >>> round(float(texture_acutance(None, y, None, **geometry)), 2)
    0.93
    """
    for name, v in (("display_ppi", display_ppi), ("viewing_distance_m", viewing_distance_m)):
        require(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) and v > 0,
                f"texture acutance: {name} must be a positive number, got {v!r}")
    curve = texture_mtf(reference_xyz, test_xyz, white_xyz, texture_roi=texture_roi, flat_roi=flat_roi,
                        dead_leaves=dead_leaves).details
    ppd = pixels_per_degree(display_ppi, viewing_distance_m)
    v = np.asarray(curve["freq_cy_px"]) * ppd
    s = cpiq_csf(v)
    value = float(np.trapezoid(curve["mtf"] * s, v) / np.trapezoid(s, v))
    details = {"pixels_per_degree": ppd, "nyquist_cy_deg": 0.5 * ppd, "display_ppi": float(display_ppi),
               "viewing_distance_m": float(viewing_distance_m)}
    return MetricResult(value, name="texture-acutance", unit="", details=details)


#: This module's metric records (collected by :mod:`.registry`).
RECORDS = (MetricRecord(
    name="texture-acutance", function=texture_acutance, scenes=TEXTURE_SCENES, inputs="xyz", unit="",
    higher_is_better=True, scored=False, label="texture acutance", order=63, decimals=3,
    practical_difference=(("%", 5.0),),
    practical_source="5 % of the acutance: our choice, as the MTF50's; CPIQ turns acutance into quality loss in "
                     "just noticeable differences through a viewing condition, so no one threshold holds for the "
                     "acutance alone (IEEE 1858-2016)",
    description="CPIQ texture acutance: the dead-leaves texture MTF weighted by the CPIQ CSF, image at 100 % on a "
                "100 ppi display at 0.6 m (IEEE 1858)"),)
