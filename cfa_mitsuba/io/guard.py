"""The one gate every input file passes: regular file, size, memory,
encoding, decoder errors.

Each reader of the project (CSV and TOML spectra and CFAs, PNG, EXR, ENVI,
MATLAB, npy/npz, sidecars, scene XML) opens its file through this module,
so that a hostile or broken file is refused in one line naming the file and
the problem, at the point of entry, the same way for every format:

* **regular file** (:func:`check_regular`, :func:`open_regular`): a FIFO
  would block the reader forever, ``/dev/zero`` or ``/dev/urandom`` would
  never end, a folder is not a file.  Checked by ``stat`` before opening
  and again on the open descriptor (opened non-blocking, so even a FIFO
  swapped in between cannot block).
* **size** (:func:`read_bytes`, :func:`read_text`): at most ``limit``
  bytes are read; a larger file is refused, never read whole.
* **memory** (:func:`require_pixels`): an image's decoded size, from its
  header alone (:func:`png_header` for PNG), is checked against the memory
  available (:mod:`.limits`, ``$CFA_MITSUBA_MEMORY_LIMIT``) before any
  pixel is decoded.
* **encoding** (:func:`read_text`): text is strict UTF-8; a byte-order mark
  is removed (it would otherwise glue itself to the first field and drop a
  headerless file's first row); Latin-1, UTF-16 or invalid bytes are
  refused with the offset of the first bad byte.
* **structure** (:func:`read_toml`, :func:`read_json`, :func:`read_csv`):
  the three text formats of configs, CFAs, sensors, parity cases and a
  finished study's tables, parsed from the bounded text above; a document
  nested too deeply for the parser (a 5,000-deep TOML array is 11 kB) is
  refused in one line, never a ``RecursionError``.
* **decoder errors** (:func:`decoding`): what third-party decoders raise on
  a corrupt stream (``zlib.error``, ``struct.error``, ``ValueError``,
  ``EOFError``, ``MemoryError`` ...) becomes the same one-line error.

Schemas stay with their formats (:mod:`.validate` for JSON and numpy
headers, :mod:`.envi` for ENVI headers against their data file).
"""

from __future__ import annotations

__all__ = ["MAX_TEXT_BYTES", "MAX_BINARY_BYTES", "check_regular", "open_regular", "read_bytes", "read_text",
           "read_toml", "read_json", "read_csv", "load_json_text", "MAX_JSON_BYTES", "MAX_JSON_DEPTH", "require_pixels", "png_header", "decoding"]

import contextlib
import json
import os
import re
import stat
import struct
import zlib
from pathlib import Path

from ..errors import CfaMitsubaError, one_line

#: Largest text file read (CSV, TOML, header, sidecar), bytes.
MAX_TEXT_BYTES = 64 << 20
#: Largest binary file read whole (PNG, MAT), bytes.
MAX_BINARY_BYTES = 16 << 30

#: Largest JSON document read (bytes): a sidecar of a 32768-column chirp is
#: about 1 MB.
MAX_JSON_BYTES = 64 << 20
#: Deepest nesting of objects and arrays accepted (a sidecar uses 4).
MAX_JSON_DEPTH = 32

_KINDS = ((stat.S_ISFIFO, "a FIFO (named pipe)"), (stat.S_ISDIR, "a directory"),
          (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"))


def _kind(mode: int) -> str:
    return next((name for test, name in _KINDS if test(mode)), "not a regular file")


def _label(path, what: str | None) -> str:
    return f"{what} {str(path)!r}" if what else repr(str(path))


def check_regular(path, what: str | None = None) -> os.stat_result:
    """``os.stat`` of ``path`` (symlinks followed), refused in one line
    unless it exists and is a regular file; ``what`` names it ("CFA file")."""
    try:
        st = os.stat(path)
    except FileNotFoundError:
        raise CfaMitsubaError(f"cannot read {_label(path, what)}: no such file") from None
    except OSError as exc:
        raise CfaMitsubaError(f"cannot read {_label(path, what)}: {exc.strerror}") from None
    if not stat.S_ISREG(st.st_mode):
        raise CfaMitsubaError(f"{_label(path, what)} is {_kind(st.st_mode)}, not a regular file")
    return st


def open_regular(path, what: str | None = None):
    """A binary file object of regular file ``path`` (see the module
    docstring: checked before and after opening, never blocking)."""
    check_regular(path, what)
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
    except OSError as exc:
        raise CfaMitsubaError(f"cannot read {_label(path, what)}: {exc.strerror}") from None
    if not stat.S_ISREG(os.fstat(fd).st_mode):
        os.close(fd)
        raise CfaMitsubaError(f"{_label(path, what)} is not a regular file")
    return os.fdopen(fd, "rb")


def _size(n: int) -> str:
    return f"{n >> 30} GiB" if n >= 1 << 30 else (f"{n >> 20} MiB" if n >= 1 << 20 else f"{n} bytes")


def read_bytes(path, what: str | None = None, limit: int = MAX_BINARY_BYTES) -> bytes:
    """The bytes of regular file ``path``, refused beyond ``limit`` bytes or
    beyond the memory available (its size, checked before it is read)."""
    from . import limits

    with open_regular(path, what) as fh:
        size = os.fstat(fh.fileno()).st_size
        if size > limit:
            raise CfaMitsubaError(f"{_label(path, what)} is larger than {_size(limit)}, the most read from such a "
                                  "file")
        if size > 64 << 20:
            limits.require_memory(size, f"reading {_label(path, what)} ({size} bytes)")
        # Ask for what the file holds plus one byte (to see it has not grown), never for the whole limit: a
        # read(limit + 1) reserves the limit up front, which fails under an address-space limit (ulimit -v).
        chunks = [fh.read(size + 1)]
        total = len(chunks[0])
        while total > size and total <= limit:  # it grew since fstat (or a file system that reports size 0)
            more = fh.read(min(1 << 20, limit + 1 - total))
            if not more:
                break
            chunks.append(more)
            total += len(more)
    if total > limit:
        raise CfaMitsubaError(f"{_label(path, what)} is larger than {_size(limit)}, the most read from such a file")
    return chunks[0] if len(chunks) == 1 else b"".join(chunks)


def read_text(path, what: str | None = None, limit: int = MAX_TEXT_BYTES) -> str:
    """The text of regular file ``path``: strict UTF-8 (a leading byte-order
    mark removed), at most ``limit`` bytes."""
    data = read_bytes(path, what, limit)
    if data[:2] in (b"\xff\xfe", b"\xfe\xff"):
        raise CfaMitsubaError(f"{_label(path, what)} is UTF-16 text; save it as UTF-8")
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = data[:exc.start].count(b"\n") + 1
        raise CfaMitsubaError(f"{_label(path, what)} is not UTF-8 text (byte 0x{data[exc.start]:02x} at offset "
                              f"{exc.start}, line {line}); save it as UTF-8") from None


# A JSON string (with escapes) or one bracket: enough to measure nesting
# without parsing.
_TOKENS = re.compile(r'"(?:[^"\\]|\\.)*"|[\[\]{}]', re.S)


def _depth(text: str) -> int:
    depth = deepest = 0
    for m in _TOKENS.finditer(text):
        c = m.group()
        if c in "[{":
            depth += 1
            if depth > deepest:
                deepest = depth
                if deepest > MAX_JSON_DEPTH:
                    return deepest
        elif c in "]}":
            depth -= 1
    return deepest


def _no_constant(name: str):
    raise CfaMitsubaError(f"holds {name}, which is not a JSON number")


def load_json_text(text: str, what: str, *, allow_nan: bool = False):
    """Parse ``text`` (a JSON document described by ``what``, e.g.
    ``"sidecar 'a.json'"``) within the size and depth bounds; NaN and
    infinity are refused unless ``allow_nan`` (files the project wrote
    itself with Python's default ``json.dumps``, such as a study's
    ``timing.json``)."""
    if len(text) > MAX_JSON_BYTES:
        raise CfaMitsubaError(f"{what} is {len(text) / 1e6:.0f} MB, larger than the {MAX_JSON_BYTES >> 20} MiB a "
                              "JSON document may be")
    depth = _depth(text)
    if depth > MAX_JSON_DEPTH:
        raise CfaMitsubaError(f"{what} is nested more than {MAX_JSON_DEPTH} levels deep (refused unparsed)")
    try:
        return json.loads(text) if allow_nan else json.loads(text, parse_constant=_no_constant)
    except CfaMitsubaError as exc:
        raise CfaMitsubaError(f"{what} {exc}") from None
    except (ValueError, RecursionError) as exc:
        raise CfaMitsubaError(f"{what} is not valid JSON: {exc}") from None


def read_toml(path, what: str | None = None, limit: int = MAX_TEXT_BYTES) -> dict:
    """The TOML document in regular file ``path`` (:func:`read_text`),
    parsed; invalid TOML, or TOML nested too deeply for the parser (which
    recurses once per level), is one line naming the file."""
    import tomllib

    text = read_text(path, what, limit)
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise CfaMitsubaError(f"{_label(path, what)}: invalid TOML: {exc}") from None
    except RecursionError:
        raise CfaMitsubaError(f"{_label(path, what)}: its arrays or tables nest too deeply to read") from None


def read_json(path, what: str | None = None, limit: int = MAX_TEXT_BYTES, *, allow_nan: bool = False):
    """The JSON document in regular file ``path`` (:func:`read_text`),
    parsed within the nesting bound of :func:`.validate.load_json_text`
    (measured on the text before parsing, so ``[`` x 100,000 is refused
    unparsed); NaN and infinity refused unless ``allow_nan``."""
    return load_json_text(read_text(path, what, limit), _label(path, what), allow_nan=allow_nan)


def read_csv(path, what: str | None = None, limit: int = MAX_BINARY_BYTES, **kwargs):
    """``pandas.read_csv`` of regular file ``path``, read through
    :func:`read_bytes` (a FIFO or device refused, the size bounded and
    checked against the memory available); ``kwargs`` go to pandas."""
    import io

    import pandas as pd

    return pd.read_csv(io.BytesIO(read_bytes(path, what, limit)), **kwargs)


def require_pixels(path, height: int, width: int, values_per_pixel: int, bytes_per_value: int,
                   what: str | None = None) -> None:
    """Refuse an image whose decoded array (``height`` x ``width`` x
    ``values_per_pixel`` values of ``bytes_per_value`` bytes, plus the
    float64 copy every reader makes) does not fit in the memory available,
    before it is decoded."""
    from . import limits

    h, w, c = int(height), int(width), int(values_per_pixel)
    if h <= 0 or w <= 0 or c <= 0:
        raise CfaMitsubaError(f"{_label(path, what)}: its header declares {w} x {h} pixels x {c} values")
    need = h * w * c * (int(bytes_per_value) + 8)
    limits.require_memory(need, f"decoding {_label(path, what)} ({w} x {h} pixels x {c} values, from its header)")


def png_header(data: bytes, path, what: str | None = None) -> tuple[int, int, int, int]:
    """``(width, height, bit_depth, colour_type)`` from a PNG's signature and
    IHDR chunk (the first 33 bytes; PNG specification s. 11.2.2), refused
    in one line when they are not a PNG's."""
    if data[:8] != b"\x89PNG\r\n\x1a\n" or len(data) < 33 or data[12:16] != b"IHDR":
        raise CfaMitsubaError(f"{_label(path, what)} is not a PNG file (no PNG signature and IHDR header)")
    width, height, depth, colour = struct.unpack(">IIBB", data[16:26])
    if zlib.crc32(data[12:29]) != struct.unpack(">I", data[29:33])[0]:
        raise CfaMitsubaError(f"{_label(path, what)}: its PNG header (IHDR) fails its checksum: the file is corrupt")
    if not (1 <= width < 1 << 31 and 1 <= height < 1 << 31) or depth not in (1, 2, 4, 8, 16) or \
            colour not in (0, 2, 3, 4, 6):
        raise CfaMitsubaError(f"{_label(path, what)}: its PNG header declares {width} x {height} pixels, bit depth "
                              f"{depth}, colour type {colour}: not a valid PNG")
    return width, height, depth, colour


#: What decoders raise on a corrupt or lying file (besides their own types, passed to :func:`decoding`).
_DECODE_ERRORS = (ValueError, TypeError, KeyError, IndexError, EOFError, OSError, struct.error, zlib.error,
                  UnicodeDecodeError, OverflowError, RecursionError)


def _text(exc: BaseException) -> str:
    """An exception's message on one line (what a decoder or writer said)."""
    return " ".join(str(exc).split())


@contextlib.contextmanager
def decoding(path, what: str | None = None, extra: tuple = ()):
    """Run a third-party decoder on ``path``: any of its errors on a corrupt
    or lying file (and ``extra`` exception types) becomes one line naming
    the file; a :class:`MemoryError` says the file is too large."""
    try:
        yield
    except CfaMitsubaError:
        raise
    except MemoryError:
        raise CfaMitsubaError(f"{_label(path, what)}: too large to decode in the memory available") from None
    except _DECODE_ERRORS + tuple(extra) as exc:
        text = one_line(exc, 200)
        raise CfaMitsubaError(f"{_label(path, what)} is corrupt or not what its header says: {text}") from None
