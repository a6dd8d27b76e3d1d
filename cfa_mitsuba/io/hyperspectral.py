"""Measured spectral images: one entry point for every format.

``load_cube(path, ...)`` picks the reader by what ``path`` is:

==========================  =====================================  ====================
path                        format                                 reader
==========================  =====================================  ====================
``X.exr``                   JCGT spectral OpenEXR, any tool        :mod:`.jcgt`
``X.hdr`` (+ data file)     ENVI cube                              :mod:`.envi`
a folder of ``*.png``       one 8/16-bit PNG per band (CAVE)       :mod:`.png_bands`
``X.mat``                   MATLAB v5 (scipy) or v7.3 (h5py),      :mod:`.matlab`
                            ISETCam ``scene`` structs
==========================  =====================================  ====================

and returns a :class:`~cfa_mitsuba.io.cube.SourceCube` (the values as
stored, their wavelengths, what they are).  Formats that cannot say what
their values are (ENVI, PNG, a plain MATLAB array) are reflectance when the
user gives an illuminant or ``quantity="reflectance"``, else relative
radiance, with a notice.
"""

from __future__ import annotations

__all__ = ["MEASURED_SUFFIXES", "is_measured_path", "parse_wavelengths", "load_cube"]

from pathlib import Path

import numpy as np

from ..errors import CfaMitsubaError
from .cube import QUANTITIES, SourceCube

#: File suffixes read as measured images (a folder of PNGs too).
MEASURED_SUFFIXES = (".exr", ".hdr", ".mat")


def is_measured_path(path) -> bool:
    """Whether ``path`` names a measured image: a ``.exr``, ``.hdr`` or
    ``.mat`` file, or an existing folder."""
    if not isinstance(path, (str, Path)):
        return False
    p = Path(path)
    return p.suffix.lower() in MEASURED_SUFFIXES or p.is_dir()


def parse_wavelengths(text) -> np.ndarray | None:
    """Wavelengths in nm from ``"START:STOP:STEP"`` (STOP included), a
    comma-separated list, or a sequence of numbers; None stays None.  Order
    and count are checked against the cube by its reader.

    >>> parse_wavelengths("400:700:100").tolist(), parse_wavelengths("450, 550").tolist()
    ([400.0, 500.0, 600.0, 700.0], [450.0, 550.0])
    """
    if text is None:
        return None
    if not isinstance(text, str):
        try:
            return np.asarray(text, dtype=np.float64).reshape(-1)
        except (TypeError, ValueError):
            raise CfaMitsubaError(f"--wavelengths: not a list of numbers: {text!r}") from None
    if ":" in text:
        try:
            start, stop, step = (float(v) for v in text.split(":"))
        except ValueError:
            raise CfaMitsubaError(f"--wavelengths {text!r}: expected START:STOP:STEP in nm") from None
        if not step > 0 or not stop > start:
            raise CfaMitsubaError(f"--wavelengths {text!r}: STEP must be positive and STOP above START")
        return start + step * np.arange(int(np.floor((stop - start) / step + 1e-9)) + 1)
    try:
        return np.array([float(v) for v in text.replace(";", ",").split(",") if v.strip()])
    except ValueError:
        raise CfaMitsubaError(f"--wavelengths {text!r}: expected numbers separated by commas, or START:STOP:STEP") from None


def _settle_quantity(cube: SourceCube, quantity: str | None, illuminant_given: bool, said_by_file: bool) -> None:
    """Set ``cube.quantity`` from the user's choice, the file, or the rule
    in the module doc (with a notice)."""
    if quantity is not None:
        if quantity not in QUANTITIES:
            raise CfaMitsubaError(f"--quantity {quantity!r}: choose one of {', '.join(QUANTITIES)}")
        if said_by_file and quantity != cube.quantity:
            cube.notices.append(f"--quantity {quantity} overrides the file's {cube.quantity}")
        cube.quantity = quantity
    elif not said_by_file:
        if illuminant_given:
            cube.quantity = "reflectance"
            cube.notices.append("values read as reflectance (an illuminant was given; --quantity overrides)")
        else:
            cube.quantity = "radiance"
            cube.notices.append("values read as relative radiance (the format does not say; for a reflectance "
                                "cube pass --illuminant or --quantity reflectance)")


def load_cube(path, *, wavelengths=None, quantity: str | None = None, mat_cube: str | None = None,
              mat_wavelengths: str | None = None, illuminant_given: bool = False) -> SourceCube:
    """Read a measured spectral image (module doc).

    Parameters
    ----------
    path : a ``.exr``, ``.hdr`` (ENVI header) or ``.mat`` file, or a folder
        of per-band PNGs.
    wavelengths : band centres in nm for formats that lack them or to
        override the file's (``"START:STOP:STEP"``, a comma list or numbers).
    quantity : ``radiance``, ``reflectance`` or ``photons`` (default: the file's
        word, else the rule above).
    mat_cube, mat_wavelengths : MATLAB variable names (dotted for struct
        fields, e.g. ``scene.data.photons``).
    illuminant_given : whether the user named a light (makes an unlabelled
        cube a reflectance cube).
    """
    p = Path(path)
    wl = parse_wavelengths(wavelengths)
    if not p.exists():
        raise CfaMitsubaError(f"no such file or folder: {str(p)!r}")
    suffix = p.suffix.lower()
    if p.is_dir():
        from .png_bands import read_png_folder

        cube, by_file = read_png_folder(p, wl), False
    elif suffix == ".exr":
        from .jcgt import read_exr_cube

        cube, by_file = read_exr_cube(p)[0], True
        if wl is not None:
            raise CfaMitsubaError("--wavelengths does not apply to a spectral EXR: its channel names give them")
    elif suffix == ".hdr":
        from .envi import read_envi

        cube, by_file = read_envi(p, wl), False
    elif suffix == ".mat":
        from .matlab import read_mat

        cube, by_file = read_mat(p, cube_var=mat_cube, wave_var=mat_wavelengths, wavelengths=wl)
    else:
        raise CfaMitsubaError(f"{str(p)!r}: not a measured image (a .exr, .hdr or .mat file, or a folder of PNGs)")
    if (mat_cube or mat_wavelengths) and suffix != ".mat":
        raise CfaMitsubaError("--mat-cube and --mat-wavelengths apply to .mat files only")
    _settle_quantity(cube, quantity, illuminant_given, by_file)
    return cube
