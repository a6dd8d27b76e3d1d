"""The config checker: every error names the file, the key's dotted path
and the reason (``quick.toml: sensor.pixel_pitch_um: must be a positive
number (got -1)``)."""

from __future__ import annotations

__all__ = ["_Checker", "_typename", "read_toml"]

import math
from pathlib import Path

from ..errors import CfaMitsubaError


class _Checker:
    """Collects the config's file name so every error names file and key."""

    def __init__(self, where: str):
        self.where = where

    def fail(self, key: str, reason: str):
        raise CfaMitsubaError(f"{self.where}: {key}: {reason}")

    def table(self, data, key: str, allowed: dict) -> dict:
        if not isinstance(data, dict):
            self.fail(key, f"must be a table, got {_typename(data)}")
        for k in data:
            if k not in allowed:
                path = f"{key}.{k}" if key else k
                known = ", ".join(sorted(allowed))
                self.fail(path, f"unknown key (known here: {known})")
        return data

    def header(self, data: dict) -> tuple[str, str, int, int | None]:
        """The keys every run config shares: ``name`` (default: the file's
        stem), ``description`` (default ''), ``seed`` (>= 0, default 0) and
        ``workers`` (>= 1, or None when absent)."""
        name = self.string(data.get("name", Path(self.where).stem), "name")
        description = data.get("description", "")
        if not isinstance(description, str):
            self.fail("description", "must be a string")
        seed = self.integer(data.get("seed", 0), "seed", 0)
        workers = data.get("workers")
        if workers is not None:
            workers = self.integer(workers, "workers", 1)
        return name, description, seed, workers

    def string(self, value, key: str, choices=None) -> str:
        if not isinstance(value, str) or not value:
            self.fail(key, f"must be a non-empty string, got {_typename(value)} {value!r}")
        if choices is not None and value not in choices:
            self.fail(key, f"must be one of {', '.join(choices)} (got {value!r})")
        return value

    def boolean(self, value, key: str) -> bool:
        if not isinstance(value, bool):
            self.fail(key, f"must be true or false, got {_typename(value)} {value!r}")
        return value

    def integer(self, value, key: str, minimum: int | None = None) -> int:
        if isinstance(value, bool) or not isinstance(value, int):
            self.fail(key, f"must be an integer, got {_typename(value)} {value!r}")
        if minimum is not None and value < minimum:
            self.fail(key, f"must be at least {minimum} (got {value})")
        return value

    def number(self, value, key: str, *, positive=False, nonneg=False, maximum=None) -> float:
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            self.fail(key, f"must be a finite number, got {_typename(value)} {value!r}")
        if positive and not value > 0:
            self.fail(key, f"must be a positive number (got {value})")
        if nonneg and value < 0:
            self.fail(key, f"must not be negative (got {value})")
        if maximum is not None and value > maximum:
            self.fail(key, f"must be at most {maximum} (got {value})")
        return float(value)

    def string_list(self, value, key: str, *, allow_empty=False) -> tuple[str, ...]:
        if not isinstance(value, list):
            self.fail(key, f"must be a list of strings, got {_typename(value)}")
        if not value and not allow_empty:
            self.fail(key, "must not be empty")
        out = []
        for i, v in enumerate(value):
            out.append(self.string(v, f"{key}[{i}]"))
        if len(set(out)) != len(out):
            dup = next(v for v in out if out.count(v) > 1)
            self.fail(key, f"lists {dup!r} twice")
        return tuple(out)

    def number_list(self, value, key: str) -> tuple[float, ...]:
        if not isinstance(value, list) or not value:
            self.fail(key, f"must be a non-empty list of numbers, got {_typename(value)}")
        out = tuple(self.number(v, f"{key}[{i}]", positive=True) for i, v in enumerate(value))
        if len(set(out)) != len(out):
            self.fail(key, "lists a value twice")
        return out


def _typename(v) -> str:
    return {bool: "boolean", int: "integer", float: "number", str: "string", list: "list",
            dict: "table"}.get(type(v), type(v).__name__)


#: The largest config file read (bytes): a paper-sized study is a few kB, a
#: sweep of 10,000 values about 60 kB.
MAX_CONFIG_BYTES = 1 << 20


def read_toml(path, what: str) -> tuple[Path, dict]:
    """(path, the parsed TOML) of a config file; a missing, unreadable or
    malformed file is one :class:`CfaMitsubaError` naming it (``what``: 'config
    file', 'design config')."""
    from ..io.guard import check_regular, read_toml as _read

    p = Path(path)
    if not p.exists() and not p.is_symlink():
        raise CfaMitsubaError(f"no such {what}: {str(p)!r}")
    size = check_regular(p, what).st_size  # a FIFO, device or folder refused by what it is, before any read
    if size > MAX_CONFIG_BYTES:  # issue 27: parsing a 8 MB sweep list alone took 7 s; refused at once
        raise CfaMitsubaError(f"{p.name}: {size:,} bytes, more than a {what} holds (at most "
                              f"{MAX_CONFIG_BYTES:,}: a sweep this long would be refused for its size anyway)")
    try:  # regular file, bounded, strict UTF-8, nesting the parser survives (io/guard.py)
        return p, _read(p, what, MAX_CONFIG_BYTES)
    except (OSError, UnicodeDecodeError) as exc:
        raise CfaMitsubaError(f"cannot read {what} {str(p)!r}: {exc}") from None
