"""Dead-leaves texture MTF with the noise power subtracted (Cao et al. 2010).

    MTF_tex(f) = sqrt(max(P_cam(f) - P_noise(f), 0) / P_ideal(f))

with the ring-averaged power spectra of the camera's luminance contrast
over the chart's texture square (P_cam), of the chart itself (P_ideal,
known exactly: the chart's own pattern before optics) and of the noise on
its flat patch (P_noise); :mod:`._texture` has the definitions.  Where the
processing is linear and shift-invariant and noise-free, this is the
system's MTF (optics, pixel, demosaic), the slanted edge's; a denoiser that
keeps edges and wipes out low-contrast detail lowers it below the edge's.
The headline is the texture MTF at half Nyquist (0.25 cycles per pixel).

References
----------
F. Cao, F. Guichard, H. Hornung, "Dead leaves model for measuring texture
quality on a digital camera", Proc. SPIE 7537, Digital Photography VI
(2010) 75370E, s. 3-4 (the texture MTF as the ratio of power spectra; the
noise spectrum measured on a uniform patch and subtracted).
"""

from __future__ import annotations

__all__ = ["RECORDS", "texture_mtf"]

import numpy as np

from ._result import MetricResult
from ._texture import HALF_NYQUIST, TEXTURE_SCENES, texture_spectra
from .record import MetricRecord


def texture_mtf(reference_xyz, test_xyz, white_xyz, *, texture_roi, flat_roi, dead_leaves,
                subtract_noise: bool = True) -> MetricResult:
    """Texture MTF of a camera image of the dead-leaves chart (module doc).

    Parameters
    ----------
    reference_xyz : the ideal sensor's XYZ (not used: the chart's own
        pattern is the reference; kept for the common signature).
    test_xyz : (H, W, 3) camera XYZ (any scale).
    white_xyz : the scene white (not used: the MTF is a ratio of contrasts).
    texture_roi, flat_roi, dead_leaves : the chart's geometry (sidecar).
    subtract_noise : subtract the flat patch's noise power (default True;
        False gives the plain power-spectrum ratio, raised by noise).

    Returns
    -------
    MetricResult
        Headline: the texture MTF at 0.25 cy/px (half Nyquist), unitless.
        Details: ``freq_cy_px``, ``mtf`` (0 to Nyquist), ``mtf_no_noise_subtraction``,
        ``noise_to_texture`` (P_noise / P_cam per ring), ``analysis_px``, ``noise_tile_px``.

    Examples
    --------
    >>> from cfa_mitsuba.render.dead_leaves import camera_example
    >>> y, geometry = camera_example()          # box pixels, no optics, no noise
    >>> round(float(texture_mtf(None, y, None, **geometry)), 2)   # the pixel's sinc(0.25) = 0.90
    0.9
    """
    s = texture_spectra(test_xyz, texture_roi=texture_roi, flat_roi=flat_roi, dead_leaves=dead_leaves)
    f, p_ideal = s["freq_cy_px"], s["p_ideal"]
    noise = s["p_noise"] if subtract_noise else 0.0
    with np.errstate(divide="ignore", invalid="ignore"):
        m = np.sqrt(np.maximum(s["p_cam"] - noise, 0.0) / p_ideal)
        plain = np.sqrt(s["p_cam"] / p_ideal)
        ratio = s["p_noise"] / s["p_cam"]
    m[0], plain[0] = 1.0, 1.0  # zero frequency: the contrast's mean is 0 by construction, the MTF 1 by definition
    value = float(np.interp(HALF_NYQUIST, f, m))
    details = {"freq_cy_px": f, "mtf": m, "mtf_no_noise_subtraction": plain, "noise_to_texture": ratio,
               "analysis_px": s["n"], "noise_tile_px": s["noise_tile_px"], "oversample": s["oversample"],
               "noise_subtracted": bool(subtract_noise)}
    return MetricResult(value, name="texture-mtf", unit="", details=details)


#: This module's metric records (collected by :mod:`.registry`).
RECORDS = (MetricRecord(
    name="texture-mtf", function=texture_mtf, scenes=TEXTURE_SCENES, inputs="xyz", unit="", higher_is_better=True,
    scored=False, label="texture MTF (0.25 cy/px)", order=60, decimals=3,
    description="dead-leaves texture MTF at half Nyquist: camera over chart power spectrum, flat-patch noise power "
                "subtracted (Cao et al. 2010)"),)
