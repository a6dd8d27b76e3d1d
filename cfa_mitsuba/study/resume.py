"""A study's resume state: the finished evaluation tasks under ``.work/``.

Each finished task is one JSON file (``<task id>.json``, written atomically
by the runner).  A file a later run cannot trust (not a regular file, too
large, not JSON, nested deeper than any result, or JSON of another shape: a
string, a list, ``NaN``) is not an error of the study: its task is simply
run again, with one notice line, and the file is replaced when it finishes.
"""

from __future__ import annotations

__all__ = ["load_finished", "valid_result"]

import json
import math
import os
import shutil
import stat
from pathlib import Path

from .task_values import TaskResult

#: The largest task file read back (a task's rows are a few kB; a study's
#: biggest, a sweep task with every metric and several realisations, well
#: under 1 MB).
MAX_TASK_FILE_BYTES = 64 * 2**20
#: Keys of an evaluation task's result as saved (study.task_values.TaskResult.to_dict)
#: and the type each holds.
_SHAPE = {"rows": list, "failures": list, "ideal_rows": list, "timing": dict}


def _scalar(v) -> bool:
    # rows hold numbers (NaN allowed: a metric's value may be undefined), strings, booleans, None
    return v is None or isinstance(v, (str, bool, int, float))


def valid_result(result) -> str | None:
    """None when ``result`` has the shape of an evaluation task's result,
    else what is wrong with it (a short phrase)."""
    if not isinstance(result, dict):
        return f"holds a JSON {type(result).__name__}, not a task's result"
    missing = [k for k in ("rows", "timing") if k not in result]
    if missing:
        return f"has no {missing[0]!r}"
    for key, kind in _SHAPE.items():
        if key in result and not isinstance(result[key], kind):
            return f"{key!r} is not a {kind.__name__}"
    for key in ("rows", "failures", "ideal_rows"):
        for row in result.get(key, []):
            if not isinstance(row, dict) or not all(_scalar(v) for v in row.values()):
                return f"{key!r} holds a malformed row"
    for row in result["rows"] + result.get("ideal_rows", []):
        if not isinstance(row.get("metric"), str) or isinstance(row.get("value"), (bool, str)) \
                or not isinstance(row.get("value"), (int, float)):
            return "a row has no metric name or numeric value"
    if not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
               for v in result["timing"].values()):
        return "'timing' holds a value that is not a finite number"
    return None


def _read(f: Path):
    """(result, None) or (None, why the file is not trusted)."""
    from ..errors import CfaMitsubaError
    from ..io.guard import _kind, read_text

    try:
        st = os.stat(f)
        if not stat.S_ISREG(st.st_mode):
            return None, f"is {_kind(st.st_mode)}, not a regular file"
        if st.st_size > MAX_TASK_FILE_BYTES:
            return None, f"is larger than {MAX_TASK_FILE_BYTES // 2**20} MiB"
        # through the one bounded regular-file reader: a FIFO swapped in after the stat cannot block it
        result = json.loads(read_text(f, "saved task result", MAX_TASK_FILE_BYTES))
    except RecursionError:
        return None, "is nested too deeply"
    except CfaMitsubaError as exc:  # grew past the bound, became a FIFO, not UTF-8: the reader says which
        return None, f"cannot be read ({exc})"
    except (OSError, ValueError) as exc:
        return None, f"is not readable JSON ({type(exc).__name__})"
    why = valid_result(result)
    return (None, why) if why else (result, None)


def _remove(f: Path) -> None:
    """Clear the place of an untrusted result so the rerun task's result can
    be written there: a file or link is removed, a folder (which a rename
    cannot replace) too, with what it holds (``.work`` is the study's own)."""
    if f.is_symlink() or not f.is_dir():
        f.unlink(missing_ok=True)
    else:
        shutil.rmtree(f, ignore_errors=True)


def load_finished(work: Path, task_ids, log) -> dict:
    """{task id: :class:`~.task_values.TaskResult`} of the finished tasks among ``task_ids`` under
    ``work``.  A file that is not a valid result is removed (when it is a
    file) and its task left to run again; one notice line says how many and
    why the first was refused."""
    done, bad = {}, []
    for tid in task_ids:
        f = work / f"{tid}.json"
        if not f.exists() and not f.is_symlink():
            continue
        result, why = _read(f)
        if why is None:
            done[tid] = TaskResult.from_dict(result)
            continue
        bad.append(f"{f.name} {why}")
        _remove(f)
    if bad:
        log(f"notice: {len(bad)} saved task result(s) under {work} could not be trusted and will be "
            f"recomputed ({bad[0]}{'; ...' if len(bad) > 1 else ''})")
    return done
