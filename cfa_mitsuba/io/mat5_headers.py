"""The variables a MATLAB v5 file declares, from their headers alone,
without inflating their data.

scipy's ``whosmat`` cannot be used for this: its zlib stream decompresses a
whole block of the compressed data at once, with no bound on the output,
so a 2 MB file of compressed zeros is inflated to gigabytes just to list
its variables (measured: ``whosmat`` grew the process by 257 MB on a
241 kB file holding a 248 MB cube).  No library reads only the headers, so
this module does, by hand, from the format's own description (MathWorks,
"MAT-File Format", R2024a, ch. 1: the 128-byte file header, data elements
of an 8-byte tag ``(type, bytes)`` or a 4-byte "small element" tag, and
``miMATRIX`` elements whose first sub-elements are the array flags (class
in the low byte), the dimensions and the name).  Each compressed element
(``miCOMPRESSED``) is inflated only as far as those first sub-elements,
with ``zlib``'s ``max_length`` bound.
"""

from __future__ import annotations

__all__ = ["declared_variables"]

import struct
import zlib

_MI_INT8, _MI_INT32, _MI_UINT32, _MI_MATRIX, _MI_COMPRESSED = 1, 5, 6, 14, 15
#: mxCLASS codes (array flags' low byte) -> whosmat's class names.
_CLASSES = {1: "cell", 2: "struct", 3: "object", 4: "char", 5: "sparse", 6: "double", 7: "single", 8: "int8",
            9: "uint8", 10: "int16", 11: "uint16", 12: "int32", 13: "uint32", 14: "int64", 15: "uint64"}
#: Bytes per value of each class once loaded (a char is a 4-byte numpy
#: unicode character; structs, cells, objects and sparse arrays do not say
#: their contents' size in their header: 0).
_CLASS_BYTES = {"double": 8, "single": 4, "int8": 1, "uint8": 1, "int16": 2, "uint16": 2, "int32": 4, "uint32": 4,
                "int64": 8, "uint64": 8, "logical": 1, "char": 4}
_LOGICAL, _COMPLEX = 0x200, 0x800
#: Bytes of a matrix's start that hold its flags, dimensions and name (a name is at most 63 characters, and
#: dimensions beyond 32 would be refused anyway).
_HEADER_BYTES = 512


def _tag(buf: bytes, pos: int, e: str):
    """(type, bytes, data start) of the data element tag at ``pos``."""
    first, = struct.unpack_from(e + "I", buf, pos)
    if first >> 16:  # small data element: bytes in the upper half, data in the tag's second word
        return first & 0xFFFF, first >> 16, pos + 4
    mtype, n = struct.unpack_from(e + "II", buf, pos)
    return mtype, n, pos + 8


def _matrix_header(buf: bytes, e: str):
    """(name, shape, class name, bytes per value) from the start of an
    ``miMATRIX``'s data."""
    t, n, at = _tag(buf, 0, e)
    if t != _MI_UINT32 or n < 8:
        raise ValueError("a matrix without its array flags")
    flags, = struct.unpack_from(e + "I", buf, at)
    pos = at + ((n + 7) // 8) * 8 if n > 4 else at + 4
    t, n, at = _tag(buf, pos, e)
    if t != _MI_INT32 or n % 4:
        raise ValueError("a matrix without its dimensions")
    shape = struct.unpack_from(e + f"{n // 4}i", buf, at)
    pos = at + (((n + 7) // 8) * 8 if pos + 8 == at else 4)
    t, n, at = _tag(buf, pos, e)
    name = buf[at:at + n].decode("latin-1") if t == _MI_INT8 else ""
    cls = "logical" if flags & _LOGICAL else _CLASSES.get(flags & 0xFF, "unknown")
    return name, tuple(int(s) for s in shape), cls, _CLASS_BYTES.get(cls, 0) * (2 if flags & _COMPLEX else 1)


def _inflate_start(fh, n_compressed: int) -> bytes:
    """The first :data:`_HEADER_BYTES` of a compressed element's inflated
    data, reading at most its ``n_compressed`` bytes and never inflating
    more than that bound."""
    z = zlib.decompressobj()
    out = b""
    left = n_compressed
    while len(out) < _HEADER_BYTES and left > 0:
        chunk = fh.read(min(4096, left))
        if not chunk:
            break
        left -= len(chunk)
        out += z.decompress(z.unconsumed_tail + chunk, _HEADER_BYTES - len(out))
    return out


def declared_variables(fh) -> list[tuple[str, tuple, str, int]] | None:
    """``[(name, shape, class, bytes once loaded)]`` of the
    variables of the MATLAB v5 file open in ``fh`` (binary, seekable), the
    first three as ``scipy.io.whosmat`` lists them (0 bytes for a struct,
    cell, object or sparse array, whose header does not say), or None when the file is not a v5 file (v4 has no compression, so
    ``whosmat`` reads it safely).  Raises ValueError, struct.error or
    zlib.error on a broken file."""
    head = fh.read(128)
    if len(head) < 128 or head[126:128] not in (b"IM", b"MI"):
        return None
    e = "<" if head[126:128] == b"IM" else ">"
    if struct.unpack_from(e + "H", head, 124)[0] != 0x0100:
        return None
    out = []
    while True:
        tag = fh.read(8)
        if len(tag) < 8:
            break
        outer, n, _ = _tag(tag, 0, e)
        start = fh.tell()
        if outer == _MI_COMPRESSED:
            data = _inflate_start(fh, n)
            inner, _, at = _tag(data, 0, e)
            data = data[at:]
        else:
            inner, data = outer, fh.read(min(n, _HEADER_BYTES))
        if inner == _MI_MATRIX and n:
            name, shape, cls, nbytes = _matrix_header(data, e)
            values = 1
            for s in shape:
                values *= max(0, s)
            # as whosmat lists them: a char array's last dimension is its strings' length
            out.append((name, shape[:-1] if cls == "char" and len(shape) > 1 else shape, cls, values * nbytes))
        # the next element: uncompressed ones are padded to 8 bytes, compressed ones are not
        fh.seek(start + n + ((-n) % 8 if outer != _MI_COMPRESSED else 0))
    return out
