"""MATLAB ``.mat`` cubes: v5 through scipy.io, v7.3 (HDF5 with a 512-byte
user block) through h5py; ISETCam scene files in either.

Variables are named by ``--mat-cube`` and ``--mat-wavelengths`` (dotted for
struct fields: ``scene.data.photons``).  Without them: an ISETCam ``scene``
struct is read as ISETCam stores it (``scene.data.photons`` in
quanta/(s sr m^2 nm), ``scene.spectrum.wave`` in nm, ``scene.wAngular``
the horizontal field of view in degrees, ``scene.distance`` in m,
``scene.illuminant.data.photons`` the light on a perfect reflector);
otherwise the only 3-D numeric variable is the cube and a vector called
``wavelengths``, ``wavelength``, ``wave``, ``wl``, ``lambda`` or ``bands``
gives its wavelengths (one per band, else refused).  A cube is (rows, columns,
bands) as MATLAB indexes it; v7.3 files store it transposed, which is undone.
"""

from __future__ import annotations

__all__ = ["read_mat"]

from pathlib import Path

import numpy as np

from ..errors import CfaMitsubaError, one_line
from .cube import SourceCube, check_memory, check_wavelengths
from .illuminant import Illuminant

_WAVE_NAMES = ("wavelengths", "wavelength", "wave", "wl", "lambda", "bands")


#: Peak memory of scipy's ``loadmat`` per byte of the arrays it returns: it
#: inflates each compressed variable into a buffer, then builds the array
#: from it (measured: 473 MB peak for a 248 MB double cube).
_LOADMAT_PEAK = 2


def _declared(p: Path, where: str):
    """[(name, shape, class, bytes once loaded)] from the v5 headers alone
    (:mod:`.mat5_headers`: nothing inflated), or None for a v4 file."""
    from .guard import decoding, open_regular
    from .mat5_headers import declared_variables

    with open_regular(p, "MATLAB file") as fh, decoding(p, "MATLAB file"):
        return declared_variables(fh)


def _check_loaded_size(declared, where: str) -> None:
    """Refuse a file whose variables, at the shapes and classes their
    headers declare, would not fit in memory once inflated: a 2 MB file of
    compressed zeros holds gigabytes."""
    from . import limits

    values = sum(int(np.prod(shape, dtype=np.float64)) for _, shape, _, _ in declared)
    need = sum(nbytes for *_, nbytes in declared)
    limits.require_memory(_LOADMAT_PEAK * need, f"{where}: loading its {values:,} values (sizes from its headers, "
                                                f"before any is inflated)", "crop or bin it first")


class _V5:
    """Variables of a v5 (or v4) file, loaded by scipy once their declared
    sizes are known to fit (:func:`_check_loaded_size`)."""

    def __init__(self, p: Path, where: str):
        import scipy.io

        declared = _declared(p, where)  # v5: every variable's size, before anything is inflated
        if declared is not None:
            _check_loaded_size(declared, where)
        try:
            # (whosmat inflates whole blocks of a compressed variable: only once the sizes are known to fit)
            self.names = [(n, tuple(s)) for n, s, _ in scipy.io.whosmat(str(p))]
            self.vars = scipy.io.loadmat(str(p), squeeze_me=True, struct_as_record=False)
        except MemoryError:
            raise CfaMitsubaError(f"{where}: too large for memory") from None
        except Exception as exc:  # scipy raises ValueError, TypeError, ... on broken files
            raise CfaMitsubaError(f"{where}: not a readable MATLAB file: {one_line(exc)}") from None

    def get(self, dotted: str):
        parts = dotted.split(".")
        obj = self.vars.get(parts[0])
        for part in parts[1:]:
            obj = getattr(obj, part, None) if obj is not None and hasattr(obj, "_fieldnames") else None
        return obj

    def shape(self, dotted: str):
        v = self.get(dotted)
        return None if v is None or not isinstance(v, np.ndarray) else v.shape

    def array(self, dotted: str):
        return self.get(dotted)

    def candidates(self):
        return [(n, s) for n, s in self.names if not n.startswith("__")]


class _V73:
    """Variables of a v7.3 (HDF5) file, read lazily with h5py; arrays come
    back in MATLAB's index order (the file stores them transposed)."""

    def __init__(self, p: Path, where: str):
        import h5py

        try:
            self.f = h5py.File(str(p), "r")
        except Exception as exc:
            raise CfaMitsubaError(f"{where}: not a readable HDF5 file: {one_line(exc)}") from None

    def _node(self, dotted: str):
        node = self.f
        for part in dotted.split("."):
            if not hasattr(node, "keys") or part not in node:
                return None
            node = node[part]
        return node

    def shape(self, dotted: str):
        node = self._node(dotted)
        return tuple(reversed(node.shape)) if node is not None and hasattr(node, "shape") else None

    def array(self, dotted: str):
        node = self._node(dotted)
        if node is None or not hasattr(node, "shape"):
            return None
        try:
            return np.transpose(node[()])
        except MemoryError:
            raise CfaMitsubaError(f"{self.f.filename!r}: {dotted} is too large for memory") from None

    def get(self, dotted: str):
        return self._node(dotted)

    def candidates(self):
        return [(k, tuple(reversed(v.shape))) for k, v in self.f.items() if hasattr(v, "shape") and not k.startswith("#")]


def _open(p: Path, where: str):
    import h5py

    from .guard import check_regular

    check_regular(p, "MATLAB file")  # not a FIFO or device, before scipy or h5py opens it

    return _V73(p, where) if h5py.is_hdf5(str(p)) else _V5(p, where)


def _scalar(mat, name: str) -> float | None:
    v = mat.array(name)
    try:
        x = float(np.asarray(v, dtype=np.float64).reshape(-1)[0]) if v is not None and np.size(v) == 1 else None
    except (TypeError, ValueError):
        return None
    return x if x is not None and np.isfinite(x) and x > 0 else None


def _vector(mat, name: str, where: str) -> np.ndarray:
    v = mat.array(name)
    if v is None:
        raise CfaMitsubaError(f"{where}: no variable {name!r}")
    try:
        return np.asarray(v, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError):
        raise CfaMitsubaError(f"{where}: variable {name!r} is not numeric") from None


def read_mat(path, *, cube_var: str | None = None, wave_var: str | None = None,
             wavelengths=None) -> tuple[SourceCube, bool]:
    """Read a MATLAB cube (module doc).  Returns ``(cube, quantity_known)``:
    True for an ISETCam scene (photons), False for a plain array."""
    p = Path(path)
    where = f"MATLAB file {str(p)!r}"
    mat = _open(p, where)
    from .guard import decoding

    # h5py raises RuntimeError on a link loop (a dataset that is a soft link to itself), KeyError on a dangling one
    with decoding(p, "MATLAB file", (RuntimeError,)):
        return _read_cube(mat, where, cube_var, wave_var, wavelengths)


def _read_cube(mat, where: str, cube_var, wave_var, wavelengths) -> tuple[SourceCube, bool]:
    isetcam = cube_var is None and mat.shape("scene.data.photons") is not None
    if isetcam:
        cube_var = "scene.data.photons"
        wave_var = wave_var or "scene.spectrum.wave"
    elif cube_var is None:
        cubes = [n for n, s in mat.candidates() if len(s) == 3]
        if len(cubes) != 1:
            listed = ", ".join(f"{n} {'x'.join(map(str, s))}" for n, s in mat.candidates()) or "none"
            raise CfaMitsubaError(f"{where}: pass --mat-cube NAME ({'no' if not cubes else 'several'} 3-D variables; "
                                  f"variables: {listed})")
        cube_var = cubes[0]
    shape = mat.shape(cube_var)
    if shape is None:
        raise CfaMitsubaError(f"{where}: no array variable {cube_var!r} (--mat-cube)")
    if len(shape) != 3:
        raise CfaMitsubaError(f"{where}: {cube_var} is {'x'.join(map(str, shape))}, not a rows x columns x bands cube")
    if wavelengths is None:
        if wave_var is None:
            found = [n for n in _WAVE_NAMES if mat.shape(n) is not None]
            wave_var = found[0] if found else None
        wavelengths = _vector(mat, wave_var, where) if wave_var else None
    wl = check_wavelengths(wavelengths, shape[2], where, "pass --mat-wavelengths NAME or --wavelengths")
    check_memory(shape, where)
    data = mat.array(cube_var)
    if not isinstance(data, np.ndarray) or data.dtype.kind not in "fiu":
        raise CfaMitsubaError(f"{where}: {cube_var} is not a numeric array")
    cube = SourceCube(data, wl, "photons" if isetcam else "radiance", where,
                      notices=[f"{where}: cube {cube_var} ({'x'.join(map(str, shape))}), wavelengths "
                               f"{wl[0]:g}-{wl[-1]:g} nm" + (" (ISETCam scene, photons)" if isetcam else "")])
    if isetcam:
        cube.fov_deg, cube.distance_m = _scalar(mat, "scene.wAngular"), _scalar(mat, "scene.distance")
        if mat.shape("scene.illuminant.data.photons") is not None:
            ill = _vector(mat, "scene.illuminant.data.photons", where)
            ill_wl = (_vector(mat, "scene.illuminant.spectrum.wave", where)
                      if mat.shape("scene.illuminant.spectrum.wave") is not None else wl)
            if ill.size == ill_wl.size and ill.size >= 2 and np.all(np.diff(ill_wl) > 0) and np.all(ill >= 0):
                cube.illuminant = Illuminant(ill_wl, ill, "ISETCam scene.illuminant (photons)", absolute=True)
    return cube, isetcam
