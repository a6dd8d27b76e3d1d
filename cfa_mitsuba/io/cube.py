"""A measured spectral cube and its conversion to scene radiance on the band grid.

Every loader of a measured image (spectral EXR, ENVI, a folder of PNGs,
MATLAB, ISETCam) returns a :class:`SourceCube`: the values as stored, the
wavelength of each stored band, what they are (radiance, reflectance or
photon radiance) and what the file says about the scene (field of view,
distance, illuminant).  :func:`cube_to_radiance` puts it on the band grid:
each band is the exact mean over its box of the source spectrum linearly
interpolated between its tabulated wavelengths (DESIGN.md, Conventions),
times the illuminant's interpolant for a reflectance cube (the box mean of
the product, :func:`~cfa_mitsuba.spectra.band_average_product`); a cube
whose samples already sit on the band centres holds band values and passes
through unchanged (times the light's band means; :func:`on_grid`).  All are
linear in the stored values, so the conversion is one (B, N) weight matrix
applied to every pixel.

Bad input is refused in one line before anything is written: band counts
that disagree with the wavelengths, missing or unsorted wavelengths, NaN,
infinite or negative values, a cube larger than the memory can hold.
"""

from __future__ import annotations

__all__ = ["QUANTITIES", "ReadNotice", "SourceCube", "choose_illuminant", "white_radiance", "check_wavelengths", "check_memory", "check_values", "cube_to_radiance",
           "on_grid", "ON_GRID_TOLERANCE_NM"]

import os
from dataclasses import dataclass, field

import numpy as np

from .. import spectra
from ..errors import CfaMitsubaError
from .illuminant import Illuminant, default_illuminant

#: What a cube's values are: spectral radiance (W/(m^2 sr nm) once
#: multiplied by ``scale``), reflectance (0..1 once multiplied by ``scale``)
#: or photon radiance (quanta/(s sr m^2 nm), ISETCam's ``photons``).
QUANTITIES = ("radiance", "reflectance", "photons")


class ReadNotice(UserWarning):
    """How a file was read (units, illuminant, cropped bands): a notice,
    printed by the commands, never an error."""


@dataclass
class SourceCube:
    """A spectral cube as a file stores it.

    Attributes
    ----------
    data : (H, W, N) values (any float or integer dtype, possibly a memory map).
    wavelengths : (N,) nm, strictly ascending.
    quantity : one of :data:`QUANTITIES`.
    scale : factor to the quantity's unit (W/(m^2 sr nm); reflectance 0..1;
        quanta/(s sr m^2 nm)).
    source : what was read, for messages (``"ENVI cube 'x.hdr'"``).
    fov_deg, distance_m : the scene's horizontal field of view (degrees) and
        distance (m) where the file says them, else None.
    illuminant : the scene's light where the file says it, else None.
    notices : how the file was read, one line each (printed by the caller).
    illuminant_unreadable : what the file says of its light when that cannot
        be read (an EXR's unparseable 'illuminant' attribute), else ''.
    """

    data: np.ndarray
    wavelengths: np.ndarray
    quantity: str
    source: str
    scale: float = 1.0
    fov_deg: float | None = None
    distance_m: float | None = None
    illuminant: Illuminant | None = None
    notices: list[str] = field(default_factory=list)
    illuminant_unreadable: str = ""


def check_wavelengths(wavelengths, n_bands: int, where: str, hint: str = "pass --wavelengths") -> np.ndarray:
    """Refuse missing, non-finite, unsorted wavelengths or a count other than
    the cube's bands; returns them as float64 nm."""
    if wavelengths is None:
        raise CfaMitsubaError(f"{where}: no wavelengths for its {n_bands} bands ({hint})")
    try:
        wl = np.asarray(wavelengths, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError):
        raise CfaMitsubaError(f"{where}: wavelengths are not numbers") from None
    if wl.size != n_bands:
        raise CfaMitsubaError(f"{where}: {n_bands} bands but {wl.size} wavelengths")
    if n_bands < 2:
        raise CfaMitsubaError(f"{where}: needs at least 2 bands, has {n_bands}")
    if not np.all(np.isfinite(wl)) or np.any(wl <= 0):
        raise CfaMitsubaError(f"{where}: wavelengths must be finite and positive")
    if not np.all(np.diff(wl) > 0):
        raise CfaMitsubaError(f"{where}: wavelengths are not strictly ascending (unsorted or repeated)")
    return wl


def _available_bytes() -> int:
    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):  # pragma: no cover
        return 1 << 34


def check_memory(shape, where: str, out_bands: int = 31) -> None:
    """Refuse a cube whose conversion would not fit in the memory the
    project may use (:func:`.limits.require_memory`: ``$CFA_MITSUBA_MEMORY_LIMIT``,
    the cgroup, the machine) or in half the memory now available: the
    source as float64 plus the result on the grid."""
    from . import limits

    h, w, n = (int(s) for s in shape)
    need = h * w * (n + 2 * out_bands) * 8
    avail = _available_bytes()
    if need > avail // 2:
        raise CfaMitsubaError(f"{where}: a {h} x {w} x {n} cube needs about {need / 2**30:.3g} GiB to convert, "
                              f"too large for memory ({avail / 2**30:.3g} GiB available); crop or bin it first")
    limits.require_memory(need, f"{where}: converting a {h} x {w} x {n} cube", "crop or bin it first")


def check_values(data: np.ndarray, where: str) -> None:
    """Refuse NaN, infinite or negative values, naming their count."""
    finite = np.isfinite(data)
    bad = int(data.size - np.count_nonzero(finite))
    if bad:
        raise CfaMitsubaError(f"{where}: {bad} NaN or infinite value(s)")
    neg = int(np.count_nonzero(data < 0))
    if neg:
        raise CfaMitsubaError(f"{where}: {neg} negative value(s) (min {float(data.min()):.4g}); "
                              "radiance and reflectance cannot be negative")


def _energy_scale(cube: SourceCube, wl: np.ndarray) -> np.ndarray:
    """Per stored band, the factor to W/(m^2 sr nm) (or to reflectance)."""
    if cube.quantity == "photons":  # quanta -> joules at each tabulated wavelength (ISETCam Quanta2Energy)
        return cube.scale / spectra.photons_per_joule(wl)
    return np.full(wl.size, float(cube.scale))


#: Largest distance (nm) of a source sample from a band centre for the
#: sample to count as sitting on it (:func:`on_grid`).
ON_GRID_TOLERANCE_NM = 1e-6


def on_grid(src_wl: np.ndarray, grid: np.ndarray) -> np.ndarray | None:
    """Where a cube's samples already are the grid's band values: the index
    of the source sample at each band centre, or None.

    A measured image whose samples inside the grid's span sit exactly on the
    band centres (one per band, no others) holds band values (DESIGN.md,
    Conventions): it passes through unchanged instead of being integrated as
    the points of a piecewise-linear curve, which would smooth it (up to 8 %
    in the 400 nm band of a steep ColorChecker patch).  Samples outside the
    span are cropped as usual.
    """
    edges = spectra.band_edges(grid)
    inside = np.flatnonzero((src_wl >= edges[0]) & (src_wl <= edges[-1]))
    if inside.size != grid.size or not np.all(np.abs(src_wl[inside] - grid) <= ON_GRID_TOLERANCE_NM):
        return None
    return inside


def _weights(src_wl: np.ndarray, grid: np.ndarray, light: Illuminant | None) -> np.ndarray:
    """(B, N): band b of the result is sum_n W[b, n] x value_n, the box mean
    of the interpolant (times the light's) of a spectrum with one 1 at n.

    Computed for all N hat functions at once (no (N, N) identity, no loop
    over N: a 10,000-band file takes milliseconds): between consecutive
    breakpoints (box edges, the source's and the light's wavelengths) a hat
    function times the light's interpolant is a polynomial of degree 2,
    which 2-point Gauss-Legendre quadrature integrates exactly; each node
    adds its weight to the two hat functions it lies between.  Outside the
    source's range the end hat functions are held at 1, as
    :func:`~cfa_mitsuba.spectra.band_average` holds end values.  Written by
    hand: no library gives the box-mean operator of an interpolant as a
    matrix.  On-grid cubes (:func:`on_grid`) get the diagonal: each band's
    own sample, times the light's band mean.
    """
    n = src_wl.size
    idx = on_grid(src_wl, grid)
    if idx is not None:
        w = np.zeros((grid.size, n))
        w[np.arange(grid.size), idx] = 1.0 if light is None else spectra.band_average(
            light.wavelengths, light.values, grid)
        return w
    edges = spectra.band_edges(grid)
    parts = [edges, src_wl] + ([] if light is None else [np.asarray(light.wavelengths, dtype=np.float64)])
    breaks = np.unique(np.concatenate(parts))
    breaks = breaks[(breaks >= edges[0]) & (breaks <= edges[-1])]
    a, c = breaks[:-1], breaks[1:]
    nodes, node_w = np.polynomial.legendre.leggauss(2)
    xq = (0.5 * (c - a)[:, None] * nodes[None, :] + 0.5 * (c + a)[:, None]).ravel()
    wq = (0.5 * (c - a)[:, None] * node_w[None, :]).ravel()
    band = np.clip(np.searchsorted(edges, xq, side="right") - 1, 0, grid.size - 1)
    wq = wq / np.diff(edges)[band]
    if light is not None:
        wq = wq * np.interp(xq, light.wavelengths, light.values)
    left = np.clip(np.searchsorted(src_wl, xq, side="right") - 1, 0, n - 2)
    t = np.clip((xq - src_wl[left]) / (src_wl[left + 1] - src_wl[left]), 0.0, 1.0)
    w = np.zeros((grid.size, n))
    np.add.at(w, (band, left), wq * (1.0 - t))
    np.add.at(w, (band, left + 1), wq * t)
    return w


def _coverage_notices(src_wl: np.ndarray, grid: np.ndarray) -> list[str]:
    edges = spectra.band_edges(grid)
    lo, hi = float(edges[0]), float(edges[-1])
    if src_wl[-1] <= lo or src_wl[0] >= hi:
        raise CfaMitsubaError(f"the source's {src_wl[0]:g}-{src_wl[-1]:g} nm do not overlap the band grid's "
                              f"{lo:g}-{hi:g} nm (--bands)")
    notes = []
    below, above = src_wl[src_wl < lo], src_wl[src_wl > hi]
    cropped = [f"{part[0]:g}-{part[-1]:g} nm" for part in (below, above) if part.size]
    if cropped:
        notes.append(f"source bands at {' and '.join(cropped)} lie outside the band grid's {lo:g}-{hi:g} nm: cropped")
    if src_wl[0] > grid[0] or src_wl[-1] < grid[-1]:
        notes.append(f"the source's {src_wl[0]:g}-{src_wl[-1]:g} nm do not reach every band centre of the grid "
                     f"({grid[0]:g}-{grid[-1]:g} nm): its end values are held beyond them")
    return notes


def choose_illuminant(cube: SourceCube, illuminant: Illuminant | None, source: str = "") -> tuple[Illuminant, str]:
    """The light of a cube: the caller's (a flag), else the file's, else D65;
    with a notice saying which and what it does."""
    if illuminant is not None:
        light, said = illuminant, f"illuminant {illuminant.label} (from {source or 'the caller'})"
    elif cube.illuminant is not None:
        light, said = cube.illuminant, f"illuminant from the file: {cube.illuminant.label}"
    else:
        why = (f"the file's {cube.illuminant_unreadable} is unparseable" if cube.illuminant_unreadable
               else "the file names none")
        light, said = default_illuminant(), f"illuminant D65 assumed ({why}; pass --illuminant)"
    return light, said + (" lights the reflectance" if cube.quantity == "reflectance" else " sets the white reference")


def white_radiance(light: Illuminant, cube: SourceCube, radiance: np.ndarray, grid) -> tuple[np.ndarray, str | None]:
    """(B,) radiance of a perfect white diffuser under ``light`` at the scale of
    ``radiance`` (H, W, B) on ``grid``, and a notice when it had to be assumed.

    A reflectance cube's white is the light itself; a light the file gives
    absolutely (ISETCam) is used as it is; otherwise the light is scaled to
    the luminance of the brightest pixel (as the optics stage does)."""
    if light.absolute:  # the file's own white (ISETCam: photons of a perfect reflector, like the cube)
        power = light.values / spectra.photons_per_joule(light.wavelengths) if cube.quantity == "photons" \
            else light.values
        return spectra.band_average(light.wavelengths, power * float(cube.scale), grid), None
    bands = spectra.band_average(light.wavelengths, light.values, grid)
    if cube.quantity == "reflectance":
        return bands, None
    lum = spectra.luminance_cd_m2(radiance.reshape(-1, len(grid)), grid)
    peak = float(lum.max()) if lum.size else 0.0
    white = bands * ((peak if peak > 0 else 1.0) / float(spectra.luminance_cd_m2(bands, grid)))
    return white, "white reference: the illuminant scaled to the brightest pixel's luminance"


def cube_to_radiance(cube: SourceCube, grid=spectra.DEFAULT_WAVELENGTHS, illuminant: Illuminant | None = None,
                     illuminant_source: str = "") -> tuple[np.ndarray, np.ndarray, str, list[str]]:
    """Band-mean spectral radiance of a cube on the band grid.

    Parameters
    ----------
    cube : the stored cube (:class:`SourceCube`).
    grid : band centres (nm) of the result.
    illuminant : the light, from the user (a flag); else the file's; else D65
        (said in a notice).  A reflectance cube is lit by it; for radiance
        it only sets the white reference.
    illuminant_source : how the user gave it (``"--illuminant"``).

    Returns
    -------
    ``(radiance, white, label, notices)``: radiance (H, W, B) float64 in
    W/(m^2 sr nm) (relative where the file has no absolute unit); white
    (B,) the radiance of a perfect white diffuser under the light at the
    same scale (for a reflectance cube the light itself; for radiance, the
    light scaled to the brightest pixel's luminance unless the file gives it
    absolutely); the illuminant's label; the notices.
    """
    grid = spectra.validate_wavelengths(grid)
    src_wl = check_wavelengths(cube.wavelengths, cube.data.shape[-1], cube.source)
    notices = list(cube.notices) + _coverage_notices(src_wl, grid)
    check_memory(cube.data.shape, cube.source, grid.size)
    light, said = choose_illuminant(cube, illuminant, illuminant_source)
    notices.append(said)

    h, w, n = cube.data.shape
    flat = np.asarray(cube.data).reshape(h * w, n)
    values = flat.astype(np.float64, copy=False) if flat.dtype.kind == "f" else flat.astype(np.float64)
    check_values(values, cube.source)
    per_band = _energy_scale(cube, src_wl)
    if cube.quantity == "reflectance":
        weights = _weights(src_wl, grid, light) * per_band[None, :]
        top = float(values.max()) * float(per_band.max()) if values.size else 0.0
        if top > 1.5:
            notices.append(f"reflectance up to {top:.3g} (above 1): fluorescent, or a scale the file does not state")
    else:
        weights = _weights(src_wl, grid, None) * per_band[None, :]
    radiance = (values @ weights.T).reshape(h, w, grid.size)

    white, note = white_radiance(light, cube, radiance, grid)
    if note:
        notices.append(note)
    return radiance, np.asarray(white, dtype=np.float64), light.label, notices
