"""Texture MTF50: where the noise-subtracted dead-leaves texture MTF
(:mod:`.texture_mtf`, Cao et al. 2010) first falls below 0.5, linearly
interpolated between the two rings around it (as the slanted edge's MTF50,
:mod:`.mtf`), in cycles per mm on the sensor when the pixel pitch is known.

References
----------
F. Cao, F. Guichard, H. Hornung, "Dead leaves model for measuring texture
quality on a digital camera", Proc. SPIE 7537 (2010) 75370E; ISO
12233:2014 (MTF50 as the summary of an SFR).
"""

from __future__ import annotations

__all__ = ["RECORDS", "texture_mtf50"]

from ._result import MetricResult
from ._texture import TEXTURE_SCENES, mtf50_of
from .record import MetricRecord
from .texture_mtf import texture_mtf


def texture_mtf50(reference_xyz, test_xyz, white_xyz, *, texture_roi, flat_roi, dead_leaves,
                  pixel_pitch_um: float | None = None) -> MetricResult:
    """Texture MTF50 of a camera image of the dead-leaves chart.

    Parameters as :func:`~cfa_mitsuba.metrics.texture_mtf.texture_mtf`, and
    ``pixel_pitch_um`` (um): the headline in cy/mm when given, else cy/px.

    Returns
    -------
    MetricResult
        Headline: texture MTF50 (cy/mm or cy/px).  Details: ``mtf50_cy_px``,
        ``mtf50_cy_mm``, ``mtf50_found`` (False: the MTF stays above 0.5 up
        to Nyquist, which is then reported).

    Examples
    --------
    >>> from cfa_mitsuba.render.dead_leaves import camera_example
    >>> y, geometry = camera_example()          # box pixels alone: above 0.5 up to Nyquist
    >>> r = texture_mtf50(None, y, None, **geometry, pixel_pitch_um=2.2)
    >>> round(float(r), 1), r.details["mtf50_found"]
    (227.3, False)
    """
    curve = texture_mtf(reference_xyz, test_xyz, white_xyz, texture_roi=texture_roi, flat_roi=flat_roi,
                        dead_leaves=dead_leaves).details
    f50, found = mtf50_of(curve["freq_cy_px"], curve["mtf"])
    per_mm = 1e3 / pixel_pitch_um if pixel_pitch_um else None
    details = {"mtf50_cy_px": f50, "mtf50_cy_mm": f50 * per_mm if per_mm else None, "mtf50_found": found}
    if per_mm:
        return MetricResult(f50 * per_mm, name="texture-mtf50", unit="cy/mm", details=details)
    return MetricResult(f50, name="texture-mtf50", unit="cy/px", details=details)


#: This module's metric records (collected by :mod:`.registry`).
RECORDS = (MetricRecord(
    name="texture-mtf50", function=texture_mtf50, scenes=TEXTURE_SCENES, inputs="xyz", unit="cy/mm",
    higher_is_better=True, scored=False, label="texture MTF50", order=62, decimals=1,
    description="where the dead-leaves texture MTF (noise subtracted) first falls below 0.5"),)
