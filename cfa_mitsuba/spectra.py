"""The wavelength grid, band averaging and the spectral data every stage uses.

A spectral image here is a stack of *bands*.  Band ``b`` is centred on
``wavelengths[b]`` (nm, ascending) and covers the box between the midpoints to
its neighbours (the outer bands extend half a step outwards), so the default
grid 400, 410, ..., 700 nm has 31 boxes of 10 nm from 395 to 705 nm.  A band's
value is the exact average over its box of the source spectrum linearly
interpolated between its tabulated points: not a point sample at the centre
and not a Sprague resample (DESIGN.md, Conventions).

Spectral data come from colour-science (illuminants, CIE 1931 colour-matching
functions, the 'ColorChecker N Ohta' reflectances, the 190 rawtoaces training
reflectances, the 'Nikon 5100 (NPL)' camera sensitivities) and are put on the
grid with :func:`band_average`; nothing is hand-typed.

Photometry follows CIE 015: luminance L_v = K_m * integral L(l) ybar(l) dl with
K_m = 683 lm/W; on the grid the integral is the sum over bands of the band
means times the band widths.
"""

from __future__ import annotations

__all__ = [
    "DEFAULT_WAVELENGTHS",
    "PLANCK_J_S",
    "LIGHT_SPEED_M_S",
    "KM_LM_W",
    "validate_wavelengths",
    "parse_band_grid",
    "band_edges",
    "band_widths",
    "band_average",
    "band_average_product",
    "illuminant_table",
    "colorchecker_tables",
    "illuminant",
    "cmfs_xyz",
    "colorchecker",
    "training_reflectances",
    "camera_rgb",
    "xyz_from_radiance",
    "luminance_cd_m2",
    "photons_per_joule",
]

import functools

import numpy as np

from .colour_science import colour_science as _colour  # colour-science, imported on first call
from .errors import CfaMitsubaError

#: The default band centres (nm): 400, 410, ..., 700, i.e. 31 bands of 10 nm.
DEFAULT_WAVELENGTHS = np.arange(400.0, 701.0, 10.0)
DEFAULT_WAVELENGTHS.flags.writeable = False

#: Planck constant (J s) and speed of light (m/s), CODATA 2018 exact values.
PLANCK_J_S = 6.62607015e-34
LIGHT_SPEED_M_S = 299792458.0
#: Maximum luminous efficacy for photopic vision (lm/W), CIE 015.
KM_LM_W = 683.0

#: Wavelength range (nm) over which all bundled data are defined.
_MIN_NM, _MAX_NM = 360.0, 830.0


def validate_wavelengths(wavelengths) -> np.ndarray:
    """Check a band grid and return it as a read-only float64 array (nm).

    A grid needs at least two bands, strictly ascending finite centres, and
    its boxes (see :func:`band_edges`) inside 360..830 nm, where the CIE
    colour-matching functions are defined.
    """
    try:
        wl = np.array(wavelengths, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError):
        raise CfaMitsubaError(f"invalid band grid {wavelengths!r}: not a list of numbers") from None
    if wl.size < 2:
        raise CfaMitsubaError(f"invalid band grid: needs at least 2 bands, got {wl.size}")
    if not np.all(np.isfinite(wl)):
        raise CfaMitsubaError("invalid band grid: contains NaN or infinite wavelengths")
    if not np.all(np.diff(wl) > 0):
        raise CfaMitsubaError("invalid band grid: wavelengths must be strictly ascending")
    edges = _edges(wl)
    if edges[0] < _MIN_NM or edges[-1] > _MAX_NM:
        raise CfaMitsubaError(
            f"invalid band grid: bands span {edges[0]:g}..{edges[-1]:g} nm, "
            f"outside {_MIN_NM:g}..{_MAX_NM:g} nm"
        )
    wl.flags.writeable = False
    return wl


def parse_band_grid(text: str) -> np.ndarray:
    """Parse ``"START:STOP:STEP"`` (nm, STOP included) into a band grid.

    >>> parse_band_grid("400:700:10").size
    31
    """
    parts = str(text).split(":")
    if len(parts) != 3:
        raise CfaMitsubaError(f"invalid band grid {text!r}: expected START:STOP:STEP in nm")
    try:
        start, stop, step = (float(p) for p in parts)
    except ValueError:
        raise CfaMitsubaError(f"invalid band grid {text!r}: START, STOP and STEP must be numbers") from None
    if not step > 0:
        raise CfaMitsubaError(f"invalid band grid {text!r}: STEP must be positive")
    if not stop > start:
        raise CfaMitsubaError(f"invalid band grid {text!r}: STOP must exceed START")
    n = int(np.floor((stop - start) / step + 1e-9)) + 1
    if abs(start + step * (n - 1) - stop) > 1e-6 * step:  # never a grid that silently stops short of STOP
        raise CfaMitsubaError(f"invalid band grid {text!r}: STEP {step:g} does not divide STOP - START = "
                              f"{stop - start:g} nm (the last band would be {start + step * (n - 1):g} nm, not "
                              f"{stop:g}); pick STOP = START + a multiple of STEP")
    return validate_wavelengths(start + step * np.arange(n))


def _edges(wl: np.ndarray) -> np.ndarray:
    mid = 0.5 * (wl[1:] + wl[:-1])
    return np.concatenate(([wl[0] - (mid[0] - wl[0])], mid, [wl[-1] + (wl[-1] - mid[-1])]))


def band_edges(wavelengths) -> np.ndarray:
    """Box edges (nm), shape (B + 1,): midpoints between centres, the outer
    boxes as wide as their inner halves doubled."""
    return _edges(np.asarray(wavelengths, dtype=np.float64))


def band_widths(wavelengths) -> np.ndarray:
    """Box widths (nm), shape (B,)."""
    return np.diff(band_edges(wavelengths))


def band_average(source_wavelengths, source_values, wavelengths) -> np.ndarray:
    """Exact box averages of a linearly interpolated tabulated spectrum.

    Parameters
    ----------
    source_wavelengths : (N,) ascending nm.
    source_values : (N,) or (N, K) values at those wavelengths (any unit).
    wavelengths : (B,) band centres (nm); the boxes are :func:`band_edges`.

    Returns
    -------
    (B,) or (B, K): for each band the integral of the piecewise-linear
    interpolant over its box divided by the box width, in the unit of
    ``source_values``.  Outside the tabulated range the spectrum is held at
    its end value (colour-science's default constant extrapolation).

    The integral is computed exactly: the interpolant is evaluated at the box
    edges and at every tabulated point inside the box and integrated with the
    trapezoid rule, which is exact for a piecewise-linear function.

    Examples
    --------
    A ramp's box average is its value at the box centre:

    >>> band_average([390, 720], [390, 720], [400, 410, 420]).round(12).tolist()
    [400.0, 410.0, 420.0]
    """
    x = np.asarray(source_wavelengths, dtype=np.float64)
    y = np.asarray(source_values, dtype=np.float64)
    squeeze = y.ndim == 1
    if squeeze:
        y = y[:, None]
    if x.ndim != 1 or y.shape[0] != x.size or x.size < 2 or not np.all(np.diff(x) > 0):
        raise CfaMitsubaError("band_average: source wavelengths must be 1-D, strictly ascending, one per value")
    edges = band_edges(validate_wavelengths(wavelengths))
    out = np.empty((edges.size - 1, y.shape[1]))
    for b in range(edges.size - 1):
        lo, hi = edges[b], edges[b + 1]
        inner = x[(x > lo) & (x < hi)]
        pts = np.concatenate(([lo], inner, [hi]))
        vals = np.stack([np.interp(pts, x, y[:, k]) for k in range(y.shape[1])], axis=1)
        out[b] = np.trapezoid(vals, pts, axis=0) / (hi - lo)
    return out[:, 0] if squeeze else out


def band_average_product(sources, wavelengths) -> np.ndarray:
    """Exact box averages of a product of linearly interpolated spectra.

    The radiance of a surface is the product of spectra tabulated on their
    own grids (an illuminant times a reflectance, ...).  Its band value is
    the box mean of the product of the linear interpolants, which is not the
    product of the factors' box means (up to 1 % apart at 400 nm for D65
    times a ColorChecker patch).

    Parameters
    ----------
    sources : sequence of ``(wavelengths_nm, values)`` pairs, each ascending
        with values of shape (N,); held at their end values outside their
        range, as :func:`band_average`.
    wavelengths : (B,) band centres (nm).

    Returns
    -------
    (B,) box means of the product, in the product of the factors' units.

    Between consecutive breakpoints (every factor's tabulated points and the
    box edges) the product of k linear pieces is a polynomial of degree k;
    Gauss-Legendre quadrature with ceil((k + 1) / 2) nodes per piece
    integrates it exactly.

    Examples
    --------
    >>> band_average_product([([390, 720], [1, 1]), ([390, 720], [390, 720])], [400, 410]).round(9).tolist()
    [400.0, 410.0]
    """
    factors = []
    for x, y in sources:
        x = np.asarray(x, dtype=np.float64)
        y = np.asarray(y, dtype=np.float64)
        if x.ndim != 1 or y.shape != x.shape or x.size < 2 or not np.all(np.diff(x) > 0):
            raise CfaMitsubaError("band_average_product: each source needs 1-D ascending wavelengths, one per value")
        factors.append((x, y))
    if not factors:
        raise CfaMitsubaError("band_average_product: no spectra given")
    edges = band_edges(validate_wavelengths(wavelengths))
    nodes, weights = np.polynomial.legendre.leggauss(int(np.ceil((len(factors) + 1) / 2)))
    breaks = np.unique(np.concatenate([edges] + [x for x, _ in factors]))
    out = np.empty(edges.size - 1)
    for b in range(edges.size - 1):
        lo, hi = edges[b], edges[b + 1]
        pts = breaks[(breaks >= lo) & (breaks <= hi)]
        a, c = pts[:-1, None], pts[1:, None]
        xq = 0.5 * (c - a) * nodes[None, :] + 0.5 * (c + a)
        prod = np.ones_like(xq)
        for x, y in factors:
            prod *= np.interp(xq, x, y)
        out[b] = float(np.sum(0.5 * (c - a) * prod * weights[None, :])) / (hi - lo)
    return out


def illuminant_table(name: str = "D65") -> tuple[np.ndarray, np.ndarray]:
    """A CIE illuminant as colour-science tabulates it: ``(wavelengths_nm,
    relative power)`` (D65 is 100 at 560 nm)."""
    colour = _colour()
    if name not in colour.SDS_ILLUMINANTS:
        raise CfaMitsubaError(f"unknown illuminant {name!r}")
    sd = colour.SDS_ILLUMINANTS[name]
    return np.asarray(sd.wavelengths, dtype=np.float64), np.asarray(sd.values, dtype=np.float64)


def colorchecker_tables() -> tuple[tuple[str, ...], list[tuple[np.ndarray, np.ndarray]]]:
    """The 24 'ColorChecker N Ohta' reflectances as colour-science tabulates
    them: ``(names, [(wavelengths_nm, reflectance), ...])`` in reading order."""
    colour = _colour()
    sds = colour.characterisation.SDS_COLOURCHECKERS["ColorChecker N Ohta"]
    names = tuple(sds)
    return names, [(np.asarray(sds[n].wavelengths, float), np.asarray(sds[n].values, float)) for n in names]


def _grid_key(wavelengths) -> tuple:
    return tuple(float(v) for v in validate_wavelengths(wavelengths))


def _frozen(a: np.ndarray) -> np.ndarray:
    a = np.array(a, dtype=np.float64)
    a.flags.writeable = False
    return a


@functools.lru_cache(maxsize=64)
def _illuminant(name: str, key: tuple) -> np.ndarray:
    colour = _colour()
    if name not in colour.SDS_ILLUMINANTS:
        known = ", ".join(sorted(colour.SDS_ILLUMINANTS)[:12])
        raise CfaMitsubaError(f"unknown illuminant {name!r} (colour-science names, e.g. {known}, ...)")
    sd = colour.SDS_ILLUMINANTS[name]
    return _frozen(band_average(sd.wavelengths, sd.values, key))


def illuminant(name: str = "D65", wavelengths=DEFAULT_WAVELENGTHS) -> np.ndarray:
    """Relative spectral power of a CIE illuminant on the grid, shape (B,).

    The colour-science table as published (D65 is 100 at 560 nm), unitless;
    scenes scale it to absolute radiance.
    """
    return _illuminant(str(name), _grid_key(wavelengths))


@functools.lru_cache(maxsize=16)
def _cmfs(key: tuple) -> np.ndarray:
    colour = _colour()
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    return _frozen(band_average(cmfs.wavelengths, cmfs.values, key))


def cmfs_xyz(wavelengths=DEFAULT_WAVELENGTHS) -> np.ndarray:
    """CIE 1931 2-degree colour-matching functions xbar, ybar, zbar on the
    grid, shape (B, 3), unitless (ybar peaks at 1 at 555 nm)."""
    return _cmfs(_grid_key(wavelengths))


@functools.lru_cache(maxsize=16)
def _colorchecker(key: tuple):
    colour = _colour()
    sds = colour.characterisation.SDS_COLOURCHECKERS["ColorChecker N Ohta"]
    names = tuple(sds)
    values = np.stack([band_average(sds[n].wavelengths, sds[n].values, key) for n in names])
    return names, _frozen(values)


def colorchecker(wavelengths=DEFAULT_WAVELENGTHS) -> tuple[tuple[str, ...], np.ndarray]:
    """The 24 'ColorChecker N Ohta' reflectances (colour-science).

    Returns ``(names, reflectance)`` with reflectance of shape (24, B) in
    0..1, in the chart's reading order (dark skin ... black), i.e. row by
    row of the standard 4 x 6 layout.
    """
    return _colorchecker(_grid_key(wavelengths))


@functools.lru_cache(maxsize=16)
def _training(key: tuple) -> np.ndarray:
    colour = _colour()
    msds = colour.characterisation.read_training_data_rawtoaces_v1()
    return _frozen(band_average(msds.wavelengths, msds.values, key).T)


def training_reflectances(wavelengths=DEFAULT_WAVELENGTHS) -> np.ndarray:
    """The 190 rawtoaces training reflectances (colour-science), shape
    (190, B), 0..1.  Used to fit colour-correction matrices; never the test
    chart."""
    return _training(_grid_key(wavelengths))


#: Peak quantum efficiency given to the panchromatic sum W = R + G + B of the
#: measured camera: the NPL data are peak-normalised per channel, so their
#: absolute scale is ours to choose.  0.6 is a typical peak QE of a modern
#: CMOS pixel (EMVA 1288 datasheets of back-side-illuminated sensors quote
#: 0.6 to 0.8); the resulting R, G, B peaks (0.35 to 0.42) are close to
#: ISETCam's default RGB filters (0.29 to 0.40).
CAMERA_PEAK_QE = 0.6


@functools.lru_cache(maxsize=16)
def _camera_rgb(key: tuple) -> np.ndarray:
    colour = _colour()
    msds = colour.MSDS_CAMERA_SENSITIVITIES["Nikon 5100 (NPL)"]
    fine = msds.values
    scale = CAMERA_PEAK_QE / fine.sum(axis=1).max()
    return _frozen(band_average(msds.wavelengths, fine * scale, key))


def camera_rgb(wavelengths=DEFAULT_WAVELENGTHS) -> np.ndarray:
    """R, G, B quantum efficiencies of colour-science's 'Nikon 5100 (NPL)'
    (Darrodi et al., JOSA A 32(3):381, 2015), shape (B, 3), electrons per
    photon, scaled so that R + G + B peaks at :data:`CAMERA_PEAK_QE`."""
    return _camera_rgb(_grid_key(wavelengths))


def xyz_from_radiance(radiance, wavelengths=DEFAULT_WAVELENGTHS) -> np.ndarray:
    """CIE 1931 XYZ of spectral radiance, in cd/m^2 (Y is the luminance).

    ``radiance`` is (..., B) band-mean spectral radiance in W/(m^2 sr nm);
    returns (..., 3) = K_m * sum_b L_b cmf_b width_b.
    """
    wl = validate_wavelengths(wavelengths)
    w = cmfs_xyz(wl) * band_widths(wl)[:, None] * KM_LM_W
    return np.asarray(radiance, dtype=np.float64) @ w


def luminance_cd_m2(radiance, wavelengths=DEFAULT_WAVELENGTHS) -> np.ndarray:
    """Luminance (cd/m^2) of band-mean spectral radiance (..., B) in
    W/(m^2 sr nm): K_m * sum_b L_b ybar_b width_b."""
    wl = validate_wavelengths(wavelengths)
    w = cmfs_xyz(wl)[:, 1] * band_widths(wl) * KM_LM_W
    return np.asarray(radiance, dtype=np.float64) @ w


def photons_per_joule(wavelengths) -> np.ndarray:
    """Photons per joule at each wavelength (nm): lambda / (h c)."""
    return np.asarray(wavelengths, dtype=np.float64) * 1e-9 / (PLANCK_J_S * LIGHT_SPEED_M_S)
