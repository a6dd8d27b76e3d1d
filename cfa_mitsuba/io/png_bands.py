"""A folder of per-band PNGs (8 or 16 bit, one grey image per band), read
with Pillow.

Wavelengths, first match wins:

1. ``--wavelengths`` (one per file, in the files' order);
2. every name holds a wavelength in nm (``scene_550nm.png``);
3. the CAVE layout: ``NAME_ms_01.png`` ... ``NAME_ms_31.png`` are 400 ...
   700 nm in 10-nm steps (Yasuma et al., CAVE multispectral image
   database), band indices taken from the names' last number.

A missing index (``..._ms_05.png``) is refused, as are images of different
sizes or bit depths and colour PNGs whose channels differ.  Values are the
codes over the full scale (65535 or 255).
"""

from __future__ import annotations

__all__ = ["CAVE_FIRST_NM", "CAVE_STEP_NM", "CAVE_BANDS", "read_png_folder"]

import re
from pathlib import Path

import numpy as np

from ..errors import CfaMitsubaError, one_line
from . import guard
from .cube import SourceCube, check_memory, check_wavelengths

#: CAVE: 31 bands, 400 nm to 700 nm in 10-nm steps, numbered 01..31.
CAVE_FIRST_NM, CAVE_STEP_NM, CAVE_BANDS = 400.0, 10.0, 31

_NM = re.compile(r"(\d+(?:\.\d+)?)\s*nm", re.IGNORECASE)
_INDEX = re.compile(r"(\d+)\D*$")


def _order(files: list[Path], wavelengths, where: str) -> tuple[list[Path], np.ndarray, str]:
    stems = [f.stem for f in files]
    nm = [_NM.findall(s) for s in stems]
    if wavelengths is None and all(nm):
        wl = np.array([float(m[-1]) for m in nm])
        order = np.argsort(wl, kind="stable")
        return [files[i] for i in order], wl[order], "from the file names"
    idx = [_INDEX.search(s) for s in stems]
    if not all(idx):
        bad = next(f.name for f, m in zip(files, idx) if m is None)
        raise CfaMitsubaError(f"{where}: {bad!r} has no band number or wavelength in its name "
                              "(NAME_ms_01.png ... or NAME_550nm.png)")
    num = [int(m[1]) for m in idx]
    if len(set(num)) != len(num):
        raise CfaMitsubaError(f"{where}: two files share a band number")
    order = np.argsort(num, kind="stable")
    files, num = [files[i] for i in order], sorted(num)
    first = 0 if num[0] == 0 else 1
    last = num[-1] if wavelengths is not None else first + CAVE_BANDS - 1
    if num[-1] > last:
        raise CfaMitsubaError(f"{where}: bands numbered up to {num[-1]}: not CAVE's 31 (01..31); pass --wavelengths")
    missing = sorted(set(range(first, last + 1)) - set(num))
    if missing:
        m = idx[order[0]]
        stem, digits = m.string[:m.start(1)], len(m[1])
        names = ", ".join(f"{stem}{i:0{digits}d}.png" for i in missing[:5]) + (" ..." if len(missing) > 5 else "")
        raise CfaMitsubaError(f"{where}: band(s) missing: {names} (found {len(num)} of {last - first + 1})")
    if wavelengths is not None:
        return files, np.asarray(wavelengths, dtype=np.float64), "from --wavelengths"
    return files, CAVE_FIRST_NM + CAVE_STEP_NM * np.arange(CAVE_BANDS), "CAVE layout: 01..31 = 400..700 nm"


def _read_png(path: Path, where: str) -> tuple[np.ndarray, int]:
    from PIL import Image

    try:
        with guard.open_regular(path, "PNG") as fh, Image.open(fh) as im:
            mode = im.mode
            arr = np.asarray(im)
    except CfaMitsubaError as exc:
        raise CfaMitsubaError(f"{where}: {exc}") from None
    except Exception as exc:  # Pillow raises several types on broken files
        raise CfaMitsubaError(f"{where}: cannot read {path.name!r}: {one_line(exc)}") from None
    if arr.ndim == 3:
        if arr.shape[2] in (2, 4):  # grey + alpha, RGBA: drop alpha
            arr = arr[..., :-1]
        if arr.shape[2] == 3 and not (np.array_equal(arr[..., 0], arr[..., 1]) and np.array_equal(arr[..., 0], arr[..., 2])):
            raise CfaMitsubaError(f"{where}: {path.name!r} is a colour image (mode {mode}): one grey image per band expected")
        arr = arr[..., 0]
    bits = 16 if arr.dtype.itemsize >= 2 or mode.startswith("I") else 8
    return arr, bits


def read_png_folder(folder, wavelengths=None) -> SourceCube:
    """Read a folder of per-band PNGs (module doc)."""
    from PIL import Image

    d = Path(folder)
    where = f"PNG folder {str(d)!r}"
    files = sorted(f for f in d.iterdir() if f.suffix.lower() == ".png" and f.is_file())
    if not files:
        raise CfaMitsubaError(f"{where}: no .png files")
    files, wl, how = _order(files, wavelengths, where)
    wl = check_wavelengths(wl, len(files), where)
    sizes = set()
    for f in files:
        try:
            with guard.open_regular(f, "PNG") as fh, Image.open(fh) as im:
                sizes.add(im.size)
        except CfaMitsubaError as exc:
            raise CfaMitsubaError(f"{where}: {exc}") from None
        except Exception as exc:
            raise CfaMitsubaError(f"{where}: cannot read {f.name!r}: {one_line(exc)}") from None
    if len(sizes) != 1:
        raise CfaMitsubaError(f"{where}: the band images differ in size ({', '.join(f'{w}x{h}' for w, h in sorted(sizes))})")
    w, h = sizes.pop()
    check_memory((h, w, len(files)), where)
    planes, depths = [], set()
    for f in files:
        arr, bits = _read_png(f, where)
        planes.append(arr)
        depths.add(bits)
    if len(depths) != 1:
        raise CfaMitsubaError(f"{where}: the band images mix 8- and 16-bit PNGs")
    bits = depths.pop()
    data = np.stack(planes, axis=-1)
    notes = [f"{where}: {len(files)} bands, {wl[0]:g}-{wl[-1]:g} nm ({how}), {bits}-bit codes / {2**bits - 1}"]
    return SourceCube(data, wl, "radiance", where, scale=1.0 / (2**bits - 1), notices=notes)
