"""Dead-leaves texture MTF by cross-correlation with the chart (Kirk et al.
2014, Artmann 2015): immune to noise.

    MTF_cross(f) = |P_cross(f)| / P_ideal(f),   P_cross = <F_cam conj(F_ideal)>

the ring-averaged cross-power spectrum of the camera's luminance contrast
with the chart's own pattern over the chart's power spectrum
(:mod:`._texture`).  Noise that does not correlate with the chart averages
out of P_cross instead of adding power, so no noise estimate is needed;
the chart must be registered with the image to a fraction of a pixel,
which it is here by construction (the same pixel grid).  The modulus, not
the real part, after Sumner et al. (2017), so that a residual shift does
not swing the curve.  Headline: the value at half Nyquist (0.25 cy/px).

References
----------
L. Kirk, P. Herzer, U. Artmann, D. Kunz, "Description of texture loss
using the dead leaves target: current issues and a new intrinsic
approach", Proc. SPIE 9023 (2014) 90230C.  U. Artmann, "Image quality
assessment using the dead leaves target: experience with the latest
approach and further investigations", Proc. SPIE 9404, Digital Photography
XI (2015) 94040J.  R. C. Sumner, R. Burada, N. Kram, "The effects of
misregistration on the dead leaves crosscorrelation texture blur
analysis", IS&T Electronic Imaging 2017, IQSP-257.
"""

from __future__ import annotations

__all__ = ["RECORDS", "texture_mtf_cross"]

import numpy as np

from ._result import MetricResult
from ._texture import HALF_NYQUIST, TEXTURE_SCENES, texture_spectra
from .record import MetricRecord


def texture_mtf_cross(reference_xyz, test_xyz, white_xyz, *, texture_roi, flat_roi, dead_leaves) -> MetricResult:
    """Cross-correlation texture MTF of a camera image of the dead-leaves chart.

    Parameters as :func:`~cfa_mitsuba.metrics.texture_mtf.texture_mtf`.

    Returns
    -------
    MetricResult
        Headline: the cross-correlation texture MTF at 0.25 cy/px, unitless.
        Details: ``freq_cy_px``, ``mtf`` (0 to Nyquist), ``phase_rad`` (of
        the cross power: near 0 when the image is registered with the chart).

    Examples
    --------
    >>> from cfa_mitsuba.render.dead_leaves import camera_example
    >>> y, geometry = camera_example()
    >>> noisy = y + 0.02 * np.random.default_rng(0).standard_normal(y.shape)
    >>> round(float(texture_mtf_cross(None, noisy, None, **geometry)), 2)   # noise averages out: still 0.89
    0.89
    """
    s = texture_spectra(test_xyz, texture_roi=texture_roi, flat_roi=flat_roi, dead_leaves=dead_leaves)
    f = s["freq_cy_px"]
    with np.errstate(divide="ignore", invalid="ignore"):
        m = np.abs(s["p_cross"]) / s["p_ideal"]
    m[0] = 1.0
    details = {"freq_cy_px": f, "mtf": m, "phase_rad": np.angle(s["p_cross"]), "analysis_px": s["n"],
               "oversample": s["oversample"]}
    return MetricResult(float(np.interp(HALF_NYQUIST, f, m)), name="texture-mtf-cross", unit="", details=details)


#: This module's metric records (collected by :mod:`.registry`).
RECORDS = (MetricRecord(
    name="texture-mtf-cross", function=texture_mtf_cross, scenes=TEXTURE_SCENES, inputs="xyz", unit="",
    higher_is_better=True, scored=False, label="texture MTF, cross (0.25 cy/px)", order=61, decimals=3,
    description="dead-leaves texture MTF at half Nyquist by cross-correlation with the chart, immune to noise "
                "(Kirk et al. 2014, Artmann 2015)"),)
