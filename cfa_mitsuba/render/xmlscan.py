"""Reading a user's Mitsuba scene file safely, before Mitsuba reads it.

Mitsuba's XML parser (``src/core/parser.cpp``, 3.9) recurses once per
nesting level and follows ``<include>`` by itself, so a hostile or broken
file could exhaust the stack or make it read a FIFO or a file anywhere on
the disk.  This module walks the scene first, without Mitsuba and without
recursion inside a file (expat, a streaming parser), following Mitsuba's
own rules:

- ``<default name value>`` defines ``$name`` unless already defined (a
  ``--define NAME=VALUE``, Mitsuba's ``-D``, is defined first); every
  attribute's ``$name`` is replaced (longest names first, ``\\$`` escapes
  a dollar), an undefined one is an error; definitions are shared by the
  included files, in document order.
- each file resolves relative names against its own folder first, then the
  folders of the files that include it; ``<path value>`` (a child of the
  root only) puts a folder in front of that list for the rest of the file.
- ``<include filename>`` reads another file, at most :data:`MAX_INCLUDE_DEPTH`
  deep (Mitsuba's default limit); ``<spectrum filename>`` reads a spectrum.
- names inside plugins (a mesh's or a bitmap's ``filename``) are resolved
  when Mitsuba builds the scene, against the *main* file's folder and its
  ``<path>`` folders (:attr:`Scan.resolver`), not an included file's.

Bounds, checked before Mitsuba sees anything: :data:`MAX_XML_BYTES` per
file and :data:`MAX_TOTAL_XML_BYTES` for the main file and everything it
includes, elements nested at most :data:`MAX_XML_DEPTH` deep, no entity
declarations.  Every file named must be a regular file (a FIFO or device is
refused before it is opened) and must resolve (symlinks followed) inside
the main file's folder or the one ``asset_root`` folder (the shared
``../../common`` of Mitsuba's own test scenes), unless
``allow_outside_paths`` (which opens every path).
"""

from __future__ import annotations

__all__ = ["MAX_XML_BYTES", "MAX_TOTAL_XML_BYTES", "MAX_XML_DEPTH", "MAX_INCLUDE_DEPTH", "MAX_DEFINES", "Scan",
           "Resolver", "scan", "read_regular", "file_sha256", "checked_file", "parse_defines", "check_asset_root"]

import hashlib
import os
import re
import stat
from dataclasses import dataclass, field
from pathlib import Path
from xml.parsers import expat

from ..errors import CfaMitsubaError
from ..io import guard as _guard

#: Largest scene XML file read (bytes).
MAX_XML_BYTES = 16 << 20
#: Largest total of the main file and every included file (bytes).
MAX_TOTAL_XML_BYTES = 64 << 20
#: Deepest element nesting inside one XML file.
MAX_XML_DEPTH = 64
#: Deepest chain of includes (Mitsuba's ParserConfig.max_include_depth).
MAX_INCLUDE_DEPTH = 15
#: Most ``--define``s one render takes.
MAX_DEFINES = 256
_OUTSIDE_HINT = ("(render with --asset-root DIR naming the shared folder, or --allow-outside-paths; in a study's "
                 "custom scene asset_root = \"DIR\" or allow_outside_paths = true)")
_DEFINE_NAME = re.compile(r"[A-Za-z_]\w*")


def parse_defines(items) -> tuple[tuple[str, str], ...]:
    """Scene parameters as ``((name, value), ...)`` from ``NAME=VALUE``
    strings (``render --define``, repeatable) or a ``{name: value}`` table
    (a study's ``defines``); a later NAME replaces an earlier one.  Names
    are Mitsuba's ``$name`` (letters, digits, ``_``); values are strings
    (Mitsuba substitutes them as text)."""
    if items is None:
        return ()
    pairs = []
    if isinstance(items, dict):
        pairs = [(str(k), v) for k, v in items.items()]
    else:
        if isinstance(items, str):
            items = [items]
        for item in items:
            if isinstance(item, (tuple, list)) and len(item) == 2:
                pairs.append((str(item[0]), item[1]))
                continue
            name, eq, value = str(item).partition("=")
            if not eq:
                raise CfaMitsubaError(f"--define {item!r}: expected NAME=VALUE (as Mitsuba's -D)")
            pairs.append((name.strip(), value))
    if len(pairs) > MAX_DEFINES:
        raise CfaMitsubaError(f"{len(pairs)} scene parameters (--define): at most {MAX_DEFINES}")
    out: dict[str, str] = {}
    for name, value in pairs:
        if not _DEFINE_NAME.fullmatch(name):
            raise CfaMitsubaError(f"--define {name}={value}: {name!r} is not a parameter name (letters, digits, _)")
        if isinstance(value, bool) or not isinstance(value, (str, int, float)):
            raise CfaMitsubaError(f"--define {name}: the value must be a string or a number, got {value!r}")
        text = str(value)
        if len(text) > 4096 or any(ch in text for ch in "\x00\n\r"):
            raise CfaMitsubaError(f"--define {name}: the value must be one line of at most 4096 characters")
        out[name] = text
    return tuple(sorted(out.items()))


def check_asset_root(folder) -> str | None:
    """The asset folder (``--asset-root``) as an absolute real path, refused
    unless it is an existing folder; None stays None."""
    if folder is None:
        return None
    real = Path(os.path.realpath(os.path.expanduser(str(folder))))
    if not real.is_dir():
        raise CfaMitsubaError(f"--asset-root {str(folder)!r}: not an existing folder")
    if real == Path(real.anchor):
        raise CfaMitsubaError(f"--asset-root {str(folder)!r}: the file system's root would open every path; "
                              "use --allow-outside-paths if that is meant")
    return str(real)


def _fail(main: Path, why: str):
    raise CfaMitsubaError(f"scene file {str(main)!r}: {why}")


def _kind(mode: int) -> str:
    return _guard._kind(mode)


def read_regular(path: Path, limit: int) -> bytes:
    """The bytes of regular file ``path``, refused beyond ``limit`` bytes
    (:func:`cfa_mitsuba.io.guard.read_bytes`: checked by stat before
    opening, a FIFO would block the open, and again on the descriptor)."""
    return _guard.read_bytes(path, None, limit)


def file_sha256(path: Path) -> str:
    """SHA-256 of a regular file's content (hex)."""
    h = hashlib.sha256()
    with _guard.open_regular(path) as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


class Resolver:
    """Mitsuba's FileResolver: an absolute name is itself; a relative one is
    the first existing ``folder / name`` in search order, else the name as
    given (relative to the working directory)."""

    def __init__(self, folders=()):
        self.folders = [Path(f) for f in folders]

    def copy(self) -> "Resolver":
        return Resolver(self.folders)

    def prepend(self, folder: Path) -> None:
        self.folders.insert(0, Path(folder))

    def resolve(self, name: str) -> Path:
        p = Path(name)
        if p.is_absolute():
            return p
        for base in self.folders:
            if (base / p).exists():
                return base / p
        return p


@dataclass
class Scan:
    """What :func:`scan` found: ``main`` (the scene file, absolute), ``root``
    (its folder, symlinks resolved: the confinement boundary), ``asset_root``
    (the one other folder files may be in, or None), ``files``
    ([(role, real path)] of every XML and spectrum file read, in reading
    order), ``resolver`` (the main file's resolver as Mitsuba builds plugins
    with it) and ``allow_outside``."""

    main: Path
    root: Path
    allow_outside: bool
    asset_root: Path | None = None
    files: list[tuple[str, Path]] = field(default_factory=list)
    resolver: Resolver = field(default_factory=Resolver)
    xml_bytes: int = 0


def checked_file(scan_: Scan, name: str, resolver: Resolver, where: str, *, directory: bool = False) -> Path:
    """Resolve ``name`` as Mitsuba would, follow symlinks, and check that it
    exists, is a regular file (or a folder, for ``<path>``) and lies inside
    the scene's folder (unless allowed).  ``where`` names the XML element
    and its place for messages.  Returns the real path."""
    target = resolver.resolve(name)
    real = Path(os.path.realpath(target))
    if not real.exists():
        _fail(scan_.main, f"{where}: {name!r} not found (looked in {', '.join(str(f) for f in resolver.folders)})")
    inside = real.is_relative_to(scan_.root) or (scan_.asset_root is not None and real.is_relative_to(scan_.asset_root))
    if not scan_.allow_outside and not inside:
        also = f" or the asset root {str(scan_.asset_root)!r}" if scan_.asset_root is not None else ""
        _fail(scan_.main, f"{where}: {name!r} resolves to {str(real)!r}, outside the scene's folder "
                          f"{str(scan_.root)!r}{also} {_OUTSIDE_HINT}")
    mode = os.stat(real).st_mode
    if directory:
        if not stat.S_ISDIR(mode):
            _fail(scan_.main, f"{where}: {str(real)!r} is not a folder")
    elif not stat.S_ISREG(mode):
        _fail(scan_.main, f"{where}: {str(real)!r} is {_kind(mode)}, not a regular file")
    return real


_PARAM = re.compile(r"\$(\w+)")


def _substitute(value: str, params: dict[str, str]) -> str:
    """Mitsuba's parameter substitution (parser.cpp substitute_parameters):
    longest names first, ``\\$`` escapes; raises KeyError on an undefined name."""
    for key in sorted(params, key=len, reverse=True):
        value = re.sub(r"(?<!\\)\$" + re.escape(key), lambda m, v=params[key]: v, value)
    m = re.search(r"(?<!\\)\$(\w*)", value)
    if m:
        raise KeyError(m.group(1))
    return value.replace("\\$", "$")


def scan(path, *, allow_outside_paths: bool = False, defines=(), asset_root=None) -> Scan:
    """Walk the scene file ``path`` and everything it includes (module
    docstring); ``defines`` ((name, value) pairs, :func:`parse_defines`)
    are set before the file's ``<default>``s; ``asset_root`` (a real folder
    path, :func:`check_asset_root`) is one more folder files may be in.
    Raises :class:`CfaMitsubaError` with one line naming the file, line and
    element on any refusal."""
    main = Path(os.path.abspath(path))
    out = Scan(main=main, root=Path(os.path.realpath(main.parent)), allow_outside=allow_outside_paths,
               asset_root=None if asset_root is None else Path(asset_root))
    _scan_file(out, main, Resolver([Path.cwd()]), dict(defines), 0, top=True)
    return out


def _scan_file(out: Scan, path: Path, parent: Resolver, params: dict[str, str], depth: int, *, top: bool) -> None:
    if depth >= MAX_INCLUDE_DEPTH:
        _fail(out.main, f"includes nest deeper than {MAX_INCLUDE_DEPTH} files (at {str(path)!r})")
    try:
        data = read_regular(path, MAX_XML_BYTES)
    except CfaMitsubaError as exc:
        _fail(out.main, str(exc))
    out.xml_bytes += len(data)
    if out.xml_bytes > MAX_TOTAL_XML_BYTES:
        _fail(out.main, f"the scene and its included files exceed {MAX_TOTAL_XML_BYTES >> 20} MiB of XML")
    out.files.append(("xml", Path(os.path.realpath(path))))
    resolver = parent.copy()
    resolver.prepend(path.parent)
    label = "" if top else f"included file {str(path)!r}, "
    parser = expat.ParserCreate()
    parser.SetParamEntityParsing(expat.XML_PARAM_ENTITY_PARSING_NEVER)
    level = [0]

    def where(tag: str, attr: str | None = None, value: str | None = None) -> str:
        el = f'<{tag} {attr}="{value}">' if attr else f"<{tag}>"
        return f"{el} ({label}line {parser.CurrentLineNumber})"

    def start(tag, attrs):
        level[0] += 1
        if level[0] > MAX_XML_DEPTH:
            _fail(out.main, f"elements nest deeper than {MAX_XML_DEPTH} levels ({label}line {parser.CurrentLineNumber})")
        if level[0] == 1 and top and tag != "scene":
            _fail(out.main, f"is not a Mitsuba scene (its root element is <{tag}>, not <scene>)")
        for k, v in attrs.items():
            if "$" in v:
                try:
                    attrs[k] = _substitute(v, params)
                except KeyError as exc:
                    _fail(out.main, f"{where(tag, k, v)}: undefined parameter ${exc.args[0]} (no <default> defines it)")
        if tag == "default" and attrs.get("name"):
            params.setdefault(attrs["name"], attrs.get("value", ""))
        elif tag == "path" and level[0] == 2 and "value" in attrs:
            resolver.prepend(checked_file(out, attrs["value"], resolver, where(tag, "value", attrs["value"]),
                                          directory=True))
        elif tag == "include" and "filename" in attrs:
            name = attrs["filename"]
            target = checked_file(out, name, resolver, where(tag, "filename", name))
            _scan_file(out, target, resolver, params, depth + 1, top=False)
        elif tag == "spectrum" and "filename" in attrs and "type" not in attrs:
            name = attrs["filename"]
            out.files.append(("spectrum", checked_file(out, name, resolver, where(tag, "filename", name))))

    def end(tag):
        level[0] -= 1

    def no_entities(*args):
        _fail(out.main, f"declares an XML entity ({label}line {parser.CurrentLineNumber}); Mitsuba scenes use <default> "
                        "parameters instead")

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    parser.EntityDeclHandler = no_entities
    try:
        parser.Parse(data, True)
    except expat.ExpatError as exc:
        _fail(out.main, f"is not well-formed XML ({label}line {exc.lineno}, column {exc.offset}: "
                        f"{expat.ErrorString(exc.code)})")
    if top:
        out.resolver = resolver
