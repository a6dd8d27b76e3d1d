"""Spectra handed to Mitsuba, and the canonical radiometric scale.

Built-in scenes are *band-constant*: every reflectance and emission is given
to Mitsuba as its band means (colour-science data through
spectra.band_average), so a patch of reflectance rho under D65 renders
exactly D65_b * rho_b in band b, the product of the band means that ISETCam
and the rest of this pipeline (white balance, colour-correction fit, ideal
sensor) compute with.  (The box mean of the product D65(l) rho(l) differs
from that by up to 1 % in the 400 nm band, where D65 and the Ohta
reflectances both change fast; elsewhere by < 0.2 %.)

How Mitsuba gets them exactly, and cheaply:

- JIT variants: the spectral-quadrature integrator evaluates band-constant
  scenes at each band's box centre (:data:`CENTRE_INSET`), and the spectra
  are sampled there: a ``regular`` spectrum on a uniform grid (an index
  computation per lookup, 1.5x faster overall on the puppy than a searched
  ``irregular`` one), an ``irregular`` one at the box centres otherwise.
- scalar_spectral: each band is a ``specfilm`` box from which Mitsuba draws
  wavelengths itself, so the spectra are steps, constant across each box
  (``irregular``, ramping to the next band's value over the top
  :data:`RAMP_FRACTION` of a box, which is never sampled: the box is
  narrowed by :data:`BAND_INSET` at each end).  Mitsuba treats spectra as
  zero outside their range; the steps cover the whole box range.

Users' scenes have continuous spectra: there the integrator jitters each
band's wavelength across its box (minus :data:`BAND_INSET` at each end, a
relative change of a smooth spectrum's box mean of order 1e-6).

Renders are made at a canonical scale (a white diffuser in the scene's main
light has luminance :data:`CANONICAL_WHITE_CD_M2`) and rescaled afterwards
to the requested mean luminance, which is therefore never a re-render.
"""

from __future__ import annotations

__all__ = [
    "CANONICAL_WHITE_CD_M2",
    "BAND_INSET",
    "CENTRE_INSET",
    "RAMP_FRACTION",
    "d65_white_radiance",
    "band_spectrum",
    "band_step_spectrum",
]

import numpy as np

from .. import spectra

#: Luminance (cd/m^2) of a perfect white diffuser at the canonical render scale.
CANONICAL_WHITE_CD_M2 = 100.0
#: Fraction of a band's width left unsampled at each end of its box.
BAND_INSET = 1e-3
#: The inset that leaves only the box centre: band-constant scenes.
CENTRE_INSET = 0.5
#: Fraction of a band's width over which a step spectrum ramps to the next
#: band's value (inside the unsampled inset).
RAMP_FRACTION = 2.5e-4


def d65_white_radiance(wavelengths) -> np.ndarray:
    """Band-mean radiance (W/(m^2 sr nm)) of a perfect white diffuser lit
    by D65, scaled to :data:`CANONICAL_WHITE_CD_M2`."""
    wl = spectra.validate_wavelengths(wavelengths)
    d65 = spectra.illuminant("D65", wl)
    return d65 * (CANONICAL_WHITE_CD_M2 / float(spectra.luminance_cd_m2(d65, wl)))


def _values(wl: np.ndarray, values) -> np.ndarray:
    v = np.asarray(values, dtype=np.float64).reshape(-1)
    if v.size != wl.size or not np.all(np.isfinite(v)):
        raise ValueError("a band spectrum needs one finite value per band")
    return v


def band_step_spectrum(wavelengths, values) -> dict:
    """A Mitsuba ``irregular`` spectrum equal to ``values[b]`` across band
    b's box (see module docstring), covering the grid's full box range."""
    wl = spectra.validate_wavelengths(wavelengths)
    v = _values(wl, values)
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


def band_spectrum(config, values) -> dict:
    """``values`` (one per band of ``config.wavelengths``) as the Mitsuba
    spectrum that ``config.variant``'s route evaluates exactly (module
    docstring): sampled at the box centres for JIT variants, steps for
    scalar_spectral."""
    wl = spectra.validate_wavelengths(config.wavelengths)
    v = _values(wl, values)
    if config.variant.startswith("scalar"):
        return band_step_spectrum(wl, v)
    edges = spectra.band_edges(wl)
    centres = 0.5 * (edges[:-1] + edges[1:])
    step = np.diff(centres)
    if np.allclose(step, step[0], rtol=0, atol=1e-9):
        return {"type": "regular", "wavelength_min": float(centres[0]), "wavelength_max": float(centres[-1]),
                "values": ", ".join(repr(float(y)) for y in v)}
    return {"type": "irregular", "wavelengths": ", ".join(repr(float(c)) for c in centres),
            "values": ", ".join(repr(float(y)) for y in v)}
