"""Spectra handed to Mitsuba, and the canonical radiometric scale.

Built-in scenes give Mitsuba spectra that are *constant inside each band*,
at the band means of the colour-science data (spectra.band_average): so a
patch of reflectance rho under D65 renders exactly D65_b * rho_b in band b,
the product of the band means that ISETCam and the rest of this pipeline
(white balance, colour-correction fit, ideal sensor) compute with.  Mitsuba
interpolates its ``irregular`` spectra linearly and treats them as zero
outside their range; the steps below cover the whole box range (e.g. 395 to
705 nm) and ramp between neighbouring bands over the top
:data:`RAMP_FRACTION` of each band only.  The renderer never samples there:
it draws each band's wavelengths from the box minus :data:`BAND_INSET` of
its width at each end (a float32 wavelength near the top edge could
otherwise round onto the next band's value).  For a smooth spectrum the
inset changes a box mean by a relative amount of order 1e-6.

Renders are made at a canonical scale (a white diffuser in the scene's main
light has luminance :data:`CANONICAL_WHITE_CD_M2`) and rescaled afterwards to
the requested mean luminance, which is therefore never a re-render.
"""

from __future__ import annotations

__all__ = ["CANONICAL_WHITE_CD_M2", "BAND_INSET", "RAMP_FRACTION", "d65_white_radiance", "band_step_spectrum", "flat_spectrum"]

import numpy as np

from .. import spectra

#: Luminance (cd/m^2) of a perfect white diffuser at the canonical render scale.
CANONICAL_WHITE_CD_M2 = 100.0
#: Fraction of a band's width left unsampled at each end of its box.
BAND_INSET = 1e-3
#: Fraction of a band's width over which a step spectrum ramps to the next
#: band's value (inside the unsampled inset).
RAMP_FRACTION = 2.5e-4


def d65_white_radiance(wavelengths) -> np.ndarray:
    """Band-mean radiance (W/(m^2 sr nm)) of a perfect white diffuser lit
    by D65, scaled to :data:`CANONICAL_WHITE_CD_M2`."""
    wl = spectra.validate_wavelengths(wavelengths)
    d65 = spectra.illuminant("D65", wl)
    return d65 * (CANONICAL_WHITE_CD_M2 / float(spectra.luminance_cd_m2(d65, wl)))


def band_step_spectrum(wavelengths, values) -> dict:
    """A Mitsuba ``irregular`` spectrum equal to ``values[b]`` everywhere in
    band b's box (see module docstring), covering the grid's full box range."""
    wl = spectra.validate_wavelengths(wavelengths)
    v = np.asarray(values, dtype=np.float64).reshape(-1)
    if v.size != wl.size or not np.all(np.isfinite(v)):
        raise ValueError("band_step_spectrum: one finite value per band expected")
    edges = spectra.band_edges(wl)
    xs, ys = [edges[0]], [v[0]]
    for b in range(wl.size):
        xs.append(edges[b + 1] - RAMP_FRACTION * (edges[b + 1] - edges[b]))
        ys.append(v[b])
        if b + 1 < wl.size:
            xs.append(edges[b + 1])
            ys.append(v[b + 1])
    xs[-1] = edges[-1]  # the last band's value holds right up to the top edge
    return {
        "type": "irregular",
        "wavelengths": ", ".join(f"{x:.6f}" for x in xs),
        "values": ", ".join(repr(float(y)) for y in ys),
    }


def flat_spectrum(value: float) -> dict:
    """A spectrally flat Mitsuba spectrum (used for achromatic patterns,
    where the value is the pattern level, not a radiance)."""
    return {"type": "uniform", "value": float(value)}
