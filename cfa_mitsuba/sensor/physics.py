"""Pixel physics a CFA comparison needs: crosstalk, the IR-cut filter, and
per-channel full wells and gains (:class:`~.params.SensorParams` fields;
their defaults change nothing).

Crosstalk.  Light that passes one pixel's filter, or the carriers it frees
deep in the silicon, can end up in a neighbour's photodiode (optical and
electrical crosstalk; Agranov, Berezin and Tsai, IEEE Trans. Electron
Devices 50(1) 2003, measured both growing with wavelength as silicon's
absorption depth does).  The model: a fraction k(lambda) of each pixel's
filtered photo-electrons moves to its four nearest neighbours, a quarter
to each, before the charge is counted (so before shot noise):

    e'(i, j) = sum_b [(1 - k_b) s_b(i, j) + k_b / 4 sum_{4 neighbours} s_b(i', j')]

with s_b the electrons a pixel's own filter passes in band b, and k_b
linear in wavelength from ``crosstalk`` at 400 nm to ``crosstalk_700nm``
(or constant).  At the array's border the charge that would leave is kept
(mirror neighbours), so the total is conserved.  The image processor is
not told: its colour fit uses the filters' nominal curves, as a camera
whose matrix was computed from filter data (a matrix calibrated on the
sensor itself would absorb the uniform-field part of the mixing where it
is a fixed mix of channels, as on Bayer; not the loss of detail).

IR-cut filter.  Every spectra set carries one common IR-cut filter (the
Largan K098 of ISETCam's imx363, :func:`.spectra_sets.ir_cut`) on the
letters whose source curve lacks one.  ``ir_cut = "none"`` removes it,
``ir_cut = "FILE.csv"`` (``wavelength_nm, transmittance``, one header line)
puts that filter in its place: curve x T_new / T_common, exact on the
curve's own grid.  Curves that carry a camera's own IR cut (``camera``
curves: nikon-d5100, pbrt-*, isetcam-rgbw's R G B) are refused.

Per-channel well and gain.  ``channel_well_e`` clips each channel's charge
at its own full well; ``channel_gain`` multiplies ``analog_gain`` for that
channel before the ADC (codes clip at the top code).  The raw file records
both; the image processor divides each channel by its own DN per electron.
"""

from __future__ import annotations

__all__ = ["crosstalk_fractions", "neighbour_exchange", "with_ir_cut", "channel_map"]

from dataclasses import replace
from pathlib import Path

import numpy as np

from ..errors import CfaMitsubaError, require
from .params import SensorParams


def crosstalk_fractions(sensor: SensorParams, wavelengths_nm) -> np.ndarray:
    """(B,) fraction k_b of each band's electrons that moves to the neighbours."""
    wl = np.asarray(wavelengths_nm, dtype=np.float64)
    k0 = float(sensor.crosstalk)
    k1 = k0 if sensor.crosstalk_700nm is None else float(sensor.crosstalk_700nm)
    return k0 + (k1 - k0) * (wl - 400.0) / 300.0


def neighbour_exchange(x: np.ndarray) -> np.ndarray:
    """(H, W): a quarter of the four nearest neighbours' values minus the
    pixel's own, the change that a crosstalk fraction of 1 would make
    (mirror neighbours at the border, so its sum over the array is 0)."""
    p = np.pad(x, 1, mode="symmetric")
    return 0.25 * (p[:-2, 1:-1] + p[2:, 1:-1] + p[1:-1, :-2] + p[1:-1, 2:]) - x


def apply_crosstalk(photo: np.ndarray, photo_by_wavelength: np.ndarray | None, k0: float, dk: float) -> np.ndarray:
    """The mean photo-electrons after crosstalk.  ``photo`` is sum_b s_b;
    ``photo_by_wavelength`` is sum_b t_b s_b with t_b = (lambda_b - 400) / 300
    (needed when the fraction varies, ``dk`` = k(700) - k(400) != 0)."""
    out = photo + k0 * neighbour_exchange(photo)
    if dk:
        out += dk * neighbour_exchange(photo_by_wavelength)
    return np.maximum(out, 0.0, out=out)


def with_ir_cut(cfa, choice: str, base: Path | None = None):
    """``cfa`` with another IR-cut filter in place of the common one (module doc)."""
    from .spectra_sets import _product, _ratio, common_ir_letters, ir_cut, read_curve_csv

    if not choice:
        return cfa
    require(bool(cfa.spectra), f"ir_cut applies to CFAs built from a spectra set; {cfa.name!r} has its own curves")
    carry = common_ir_letters(cfa.spectra)
    lacking = [c for c in cfa.channels if c not in carry]
    if lacking:
        raise CfaMitsubaError(f"ir_cut: channel {lacking[0]!r} of spectra set {cfa.spectra!r} is a whole-camera "
                              "curve with the camera's own IR-cut filter; choose a set whose curves lack one "
                              "(isetcam-rgb, isetcam-cmy, isetcam-ryyb, mt9v024-*)")
    common = ir_cut()
    if choice == "none":
        new = None
    else:
        path = Path(choice) if base is None else Path(base) / choice
        cols = read_curve_csv(path, where=f"ir_cut {choice!r}")
        new = next(iter(cols.values()))
        require(float(np.max(new[1])) <= 1.0 + 1e-9, f"ir_cut {choice!r}: a transmittance above 1")
    curves = {}
    for c in cfa.channels:
        bare = _ratio(cfa.curves[c], common)
        curves[c] = bare if new is None else _product(bare, new)
    return replace(cfa, curves=curves, description=f"{cfa.description} (IR cut: {choice})".strip())


def channel_map(cfa, shape, values: dict) -> np.ndarray:
    """(H, W) float: each pixel's value of its channel from ``values``
    ({channel: number}, every channel given)."""
    idx = cfa.channel_index(shape)
    lut = np.array([float(values[c]) for c in cfa.channels])
    return lut[idx]
