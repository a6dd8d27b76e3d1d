"""Plain (non-spectral) images in and out: PNG (8 and 16 bit), OpenEXR, NPY
and NPZ.

Reading returns the stored numbers unchanged (code values for PNG, floats for
EXR/NPY), with what the file said about them; interpreting them (sRGB code
values, linear, XYZ) is the caller's business.  16-bit PNGs are decoded with
pypng, because Pillow silently reduces 16-bit RGB PNGs to 8 bit (the
reference RGB edge in tests/data/reference/ is kept as .npy beside its PNG
for that reason).
"""

from __future__ import annotations

__all__ = ["ImageFile", "read_image", "write_image", "IMAGE_SUFFIXES"]

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import CfaMitsubaError, one_line
from .atomic import atomic_output
from .sidecar import json_default

IMAGE_SUFFIXES = (".png", ".exr", ".npy", ".npz")

#: NPZ arrays read by default, in order; arrays never taken as the image by default.
_NPZ_KEYS = ("xyz", "image")
_NPZ_NOT_IMAGE = ("srgb", "raw", "white_xyz")

#: Channel orders recognised in EXR files, in order of preference.
_EXR_LAYOUTS = (("X", "Y", "Z"), ("R", "G", "B"), ("Y",), ("L",))


@dataclass
class ImageFile:
    """An image as read from disk.

    Attributes
    ----------
    data : (H, W) or (H, W, C) float64, the stored values (PNG code values
        0..255 or 0..65535; EXR/NPY floats as stored).
    format : 'png', 'exr', 'npy' or 'npz'.
    bit_depth : 8 or 16 for PNG, else None.
    channels : channel names where the file names them (EXR), else None.
    meta : JSON metadata stored by :func:`write_image`, if any.
    alpha : (H, W) float64, the alpha channel the file declares (a PNG's,
        an EXR's ``A``) scaled so that 1 is opaque, kept apart from
        ``data``; None when it has none.
    """

    data: np.ndarray
    format: str
    bit_depth: int | None = None
    channels: tuple[str, ...] | None = None
    meta: dict = field(default_factory=dict)
    alpha: np.ndarray | None = None


#: Values per pixel of each PNG colour type once decoded (a palette is expanded to RGB(A)).
_PNG_PLANES = {0: 1, 2: 3, 3: 4, 4: 2, 6: 4}




def _read_png(path: Path) -> ImageFile:
    import png

    from . import guard

    data = guard.read_bytes(path, "PNG")  # a regular file, bounded
    w, h, _, colour = guard.png_header(data, path, "PNG")
    guard.require_pixels(path, h, w, _PNG_PLANES[colour], 4, "PNG")  # before a pixel is decoded
    with guard.decoding(path, "PNG", (png.Error,)):  # zlib errors, a header that lies about the rows
        width, height, rows, info = png.Reader(bytes=data).asDirect()
        planes = int(info["planes"])
        arr = np.vstack([np.asarray(r, dtype=np.uint32) for r in rows]).reshape(height, width, planes)
    alpha = None
    if planes in (2, 4):  # the alpha apart from the colour, 1 = opaque
        arr, alpha = arr[..., :-1], arr[..., -1] / float((1 << int(info["bitdepth"])) - 1)
    if arr.shape[2] == 1:
        arr = arr[..., 0]
    return ImageFile(arr.astype(np.float64), "png", int(info["bitdepth"]), alpha=alpha)


def _read_exr(path: Path) -> ImageFile:
    import OpenEXR

    from .guard import check_regular, require_pixels

    check_regular(path, "OpenEXR file")
    try:  # the decoded size, from the header, before any pixel is read
        with OpenEXR.File(str(path), header_only=True) as f:
            (x0, y0), (x1, y1) = (tuple(int(v) for v in c) for c in f.header()["dataWindow"])
            n_channels = max(1, len(f.header().get("channels", ())))
    except Exception as exc:  # OpenEXR raises plain Exceptions on bad files
        raise CfaMitsubaError(f"{str(path)!r} is not a readable OpenEXR file: {exc}") from None
    require_pixels(path, y1 - y0 + 1, x1 - x0 + 1, n_channels, 4, "OpenEXR file")
    try:
        with OpenEXR.File(str(path)) as f:
            header = dict(f.header().items())
            chans = {name: np.asarray(c.pixels, dtype=np.float64) for name, c in f.channels().items()}
    except Exception as exc:  # OpenEXR raises plain Exceptions on bad files
        raise CfaMitsubaError(f"{str(path)!r} is not a readable OpenEXR file: {exc}") from None
    if "spectralLayoutVersion" in header or any(k.startswith("S0.") for k in chans):
        raise CfaMitsubaError(
            f"{str(path)!r} is a spectral EXR (radiance); capture and process it first, "
            "or pass a camera output image"
        )
    # Multi-part or RGB-interleaved reads come back as one (H, W, C) channel.
    if len(chans) == 1:
        (name, arr), = chans.items()
        names = tuple(name) if arr.ndim == 3 and len(name) == arr.shape[2] else None
        alpha = None
        if names and names[-1] == "A" and len(names) in (2, 4):  # RGBA / YA read as one: the alpha apart
            arr, alpha, names = arr[..., :-1], arr[..., -1], names[:-1]
        return ImageFile(arr, "exr", None, names, _meta_from(header), alpha=alpha)
    for layout in _EXR_LAYOUTS:
        if all(c in chans for c in layout):
            data = np.stack([chans[c] for c in layout], axis=-1)
            return ImageFile(data[..., 0] if len(layout) == 1 else data, "exr", None, layout, _meta_from(header),
                             alpha=chans.get("A"))
    raise CfaMitsubaError(
        f"{str(path)!r}: EXR channels {sorted(chans)} are none of X,Y,Z / R,G,B / Y"
    )


def _meta_from(header: dict) -> dict:
    raw = header.get("cfaMitsuba")
    if isinstance(raw, bytes):
        raw = raw.decode()
    from .validate import load_json_text

    try:  # informational only: a broken record is dropped, but parsed within the size and depth bounds
        meta = load_json_text(raw, "the EXR's cfaMitsuba attribute") if isinstance(raw, str) else {}
    except CfaMitsubaError:
        return {}
    return meta if isinstance(meta, dict) else {}


def read_image(path, *, key: str | None = None) -> ImageFile:
    """Read a PNG, EXR, NPY or NPZ image (see module docstring).

    ``key`` picks the array of an NPZ; by default ``xyz`` (a ``process``
    output), else ``image`` (:func:`write_image`), else its only array
    unless that is ``srgb`` or ``raw``: anything else is refused, never
    guessed.  NPY and NPZ are checked by content (:mod:`.validate`).
    """
    p = Path(path)
    if not p.exists():
        raise CfaMitsubaError(f"no such file: {str(p)!r}")
    if p.is_dir():
        raise CfaMitsubaError(f"{str(p)!r} is a directory, not an image")
    suffix = p.suffix.lower()
    if suffix == ".png":
        return _read_png(p)
    if suffix == ".exr":
        return _read_exr(p)
    if suffix in (".npy", ".npz"):
        from .validate import load_json_text, numpy_arrays

        names = [n for n in numpy_arrays(p, suffix[1:]) if n != "meta"]  # by content; no pickles; fits memory
        if suffix == ".npz" and key is None:
            key = next((k for k in _NPZ_KEYS if k in names), None)
            if key is None and len(names) == 1 and names[0] not in _NPZ_NOT_IMAGE:
                key = names[0]
            if key is None:  # never a guess: 'srgb' read as XYZ gave wrong metrics
                raise CfaMitsubaError(f"{str(p)!r} has no {' or '.join(map(repr, _NPZ_KEYS))} array (arrays: "
                                      f"{', '.join(names) or 'none'})")
        from .guard import open_regular

        with open_regular(p, "numpy file") as fh:  # the file numpy_arrays checked, not one swapped in since
            try:
                loaded = np.load(fh, allow_pickle=False)
            except (ValueError, OSError, EOFError) as exc:
                raise CfaMitsubaError(f"{str(p)!r} is not a readable numpy file: {one_line(exc)}") from None
            if suffix == ".npy":
                arr = loaded
                meta = {}
            else:
                with loaded:
                    if key not in names:
                        raise CfaMitsubaError(f"{str(p)!r}: no array {key!r} (arrays: {', '.join(names)})")
                    arr = loaded[key]
                    meta = load_json_text(str(loaded["meta"]), f"{str(p)!r}'s meta") if "meta" in loaded.files \
                        else {}
                    meta = meta if isinstance(meta, dict) else {}
        if arr.dtype.kind not in "biuf":
            raise CfaMitsubaError(f"{str(p)!r}: array of type {arr.dtype} is not numeric")
        return ImageFile(np.asarray(arr, dtype=np.float64), suffix[1:], None, None, meta)
    raise CfaMitsubaError(f"{str(p)!r}: unsupported image type (expected {', '.join(IMAGE_SUFFIXES)})")


def _png_bytes_writer(tmp: Path, codes: np.ndarray, bit_depth: int) -> None:
    """Write ``codes`` (H, W[, 1-4] uint8 or uint16) as a PNG with pypng:
    its rows handed over as array rows (not Python lists) and zlib at level
    1, which halves a study's thumbnail (7 -> 3-4 ms for 240 x 212 RGB; the
    file within 1 % of level 6's size, as pypng does not filter rows).
    Pillow, tried, took longer (14 ms at its defaults: it filters each row)."""
    import png

    h, w = codes.shape[:2]
    planes = 1 if codes.ndim == 2 else codes.shape[2]
    greyscale = planes in (1, 2)  # grey, or grey + alpha
    writer = png.Writer(width=w, height=h, bitdepth=bit_depth, greyscale=greyscale, alpha=planes in (2, 4),
                        compression=1)
    with open(tmp, "wb") as fh:
        writer.write(fh, np.ascontiguousarray(codes).reshape(h, w * planes))


def write_image(path, data, *, channels=None, meta: dict | None = None, bit_depth: int = 8, arrays=None) -> Path:
    """Write an image atomically; the format follows the suffix.

    - ``.png``: ``data`` in 0..1 (already display-encoded, e.g. sRGB), gray
      or RGB, quantised to ``bit_depth`` (8 or 16) with rounding; values
      outside 0..1 are clipped.
    - ``.exr``: float32 channels named by ``channels`` (default X, Y, Z for
      3-channel data, Y for 2-D); ``meta`` stored as a JSON string attribute.
    - ``.npy``: the array as float64.
    - ``.npz``: ``data`` as ``image`` plus any extra ``arrays`` and ``meta``.
    """
    p = Path(path)
    suffix = p.suffix.lower()
    arr = np.asarray(data, dtype=np.float64)
    if arr.ndim not in (2, 3):
        raise CfaMitsubaError(f"cannot write an image of shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise CfaMitsubaError(f"refusing to write {str(p)!r}: image contains NaN or infinite values")
    if suffix == ".png":
        if bit_depth not in (8, 16):
            raise CfaMitsubaError("PNG bit depth must be 8 or 16")
        if arr.ndim == 3 and arr.shape[2] not in (1, 2, 3, 4):
            raise CfaMitsubaError(f"a PNG holds 1 to 4 channels (grey, grey + alpha, RGB, RGBA), not {arr.shape[2]}")
        top = (1 << bit_depth) - 1
        codes = np.rint(np.clip(arr, 0.0, 1.0) * top).astype(np.uint16 if bit_depth == 16 else np.uint8)
        with atomic_output(p) as tmp:
            _png_bytes_writer(tmp, codes, bit_depth)
    elif suffix == ".exr":
        import OpenEXR

        if channels is None:
            channels = ("Y",) if arr.ndim == 2 else ("X", "Y", "Z") if arr.shape[2] == 3 else tuple(f"C{i}" for i in range(arr.shape[2]))
        planes = [arr] if arr.ndim == 2 else [arr[..., i] for i in range(arr.shape[2])]
        if len(planes) != len(channels):
            raise CfaMitsubaError(f"{len(channels)} channel names for {len(planes)} channels")
        header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
        if meta:
            header["cfaMitsuba"] = json.dumps(meta, default=json_default)
        chans = {c: np.ascontiguousarray(pl, dtype=np.float32) for c, pl in zip(channels, planes)}
        with atomic_output(p) as tmp:
            with OpenEXR.File(header, chans) as f:
                f.write(str(tmp))
    elif suffix == ".npy":
        with atomic_output(p) as tmp:
            with open(tmp, "wb") as fh:
                np.save(fh, arr)
    elif suffix == ".npz":
        payload = {"image": arr, **{k: np.asarray(v) for k, v in (arrays or {}).items()}}
        payload["meta"] = np.array(json.dumps(meta or {}, default=json_default))
        with atomic_output(p) as tmp:
            with open(tmp, "wb") as fh:
                np.savez_compressed(fh, **payload)
    else:
        raise CfaMitsubaError(f"{str(p)!r}: unsupported output type (expected .png, .exr, .npy or .npz)")
    return p
