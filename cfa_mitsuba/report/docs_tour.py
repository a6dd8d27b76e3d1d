"""Command-line examples in README.md and docs/*.md, produced by running them.

A tour is a ```console block between ``<!-- tour -->`` and
``<!-- /tour -->`` (README.md's tour of the command line, the capture
examples of docs/sensor.md, ...).  :func:`run_tour` runs each ``$
cfa-mitsuba ...`` line of each block in a fresh folder (one per block, so
a block may make the files its later lines read) with an empty render cache (as
``python3 -m cfa_mitsuba``, the same program) and writes its output back
under it, keeping the block's layout: a command shown without output stays
so (a trailing ``# comment`` or no lines below it), a long output shown
with a ``...`` line keeps as many lines before and after it and its lines
are cut at 150 characters with ``...``, and the notices on how files were read
(``... pass --X to override``) are left out.  Nothing is typed by hand, so
the numbers the tour prints (exposure, raw range, condition number, dE00)
are those of the code.  ``normalised`` masks what changes between runs
(seconds, cache keys) and :func:`differences` compares a fresh run with the
README as text and numbers: the words exactly, an integer exactly, a
decimal within ``TOUR_RTOL`` of the shown value or one unit in its last
printed digit, whichever is larger (a value that moved in its last bits on
another CPU, BLAS or libm can still turn its last printed digit over; a
change two units or 1e-6 beyond it is real).
"""

from __future__ import annotations

__all__ = ["TOUR", "TOUR_RTOL", "tour_files", "tour_commands", "run_tour_block", "run_tour", "normalised",
           "differences"]

import os
import re
import shlex
import subprocess
import sys
import tempfile
from pathlib import Path

from ..errors import CfaMitsubaError

TOUR = re.compile(r"(<!-- tour -->\n```console\n)(?P<block>.*?)(```\n<!-- /tour -->)", re.S)
_NOTICE = re.compile(r"pass --[\w-]+( \S+)? to override$")
#: relative tolerance of a printed decimal (beyond one unit in its last digit)
TOUR_RTOL = 1e-6
#: a printed number: sign, digits, an optional fraction and exponent
_NUMBER = re.compile(r"(?<![\w])([-+]?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?)")
_WIDTH = 150


def tour_commands(block: str) -> list[tuple[str, list[str], bool]]:
    """[(command line, the output lines shown now, blank line after)] of a tour block."""
    out, cmd, shown = [], None, []
    lines = block.splitlines()
    for i, line in enumerate(lines):
        if line.startswith("$ "):
            if cmd is not None:
                out.append((cmd, shown, False))
            cmd, shown = line, []
        elif line.strip() == "":
            if cmd is not None:
                out.append((cmd, shown, True))
            cmd, shown = None, []
        elif cmd is not None:
            shown.append(line)
    if cmd is not None:
        out.append((cmd, shown, False))
    return out


def _cut(line: str) -> str:
    if len(line) <= _WIDTH:
        return line
    head = line[:_WIDTH]
    at = head.rfind("; ")
    return (head[:at + 2] if at > 0 else head) + "..."


def _shape(output: list[str], shown: list[str]) -> list[str]:
    if not shown:
        return []
    output = [ln for ln in output if not _NOTICE.search(ln.strip())]
    if "..." not in shown:
        return output
    k = shown.index("...")
    after = len(shown) - k - 1
    if len(output) > k + after:
        output = output[:k] + ["..."] + (output[-after:] if after else [])
    return [_cut(ln) for ln in output]


def _run(cmd: str, cwd: Path, env: dict) -> list[str]:
    words = shlex.split(cmd[2:], comments=True)
    if not words or words[0] != "cfa-mitsuba":
        raise CfaMitsubaError(f"tour line {cmd!r} does not run cfa-mitsuba")
    proc = subprocess.run([sys.executable, "-m", "cfa_mitsuba", *words[1:]], cwd=cwd, env=env,
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=600)
    return proc.stdout.rstrip("\n").splitlines()


def run_tour_block(repo: Path, block: str) -> str:
    """The tour block with every command's output from running it now."""
    with tempfile.TemporaryDirectory(prefix="cfa-tour-") as tmp:
        work = Path(tmp) / "tour"
        work.mkdir()
        (work / "configs").symlink_to(repo / "configs")  # the tour names shipped configs by relative path
        env = {**os.environ, "CFA_MITSUBA_CACHE": str(Path(tmp) / "cache"), "PYTHONPATH": str(repo),
               "NO_COLOR": "1", "TQDM_DISABLE": "1"}
        parts = []
        for cmd, shown, blank in tour_commands(block):
            parts.append(cmd)
            parts += _shape(_run(cmd, work, env), shown)
            if blank:
                parts.append("")
        return "\n".join(parts) + "\n"


def tour_files(repo: Path) -> list[Path]:
    """README.md and the docs/*.md that hold at least one tour block."""
    files = [repo / "README.md", *sorted((repo / "docs").glob("*.md"))]
    return [f for f in files if TOUR.search(f.read_text())]


def run_tour(repo: Path) -> int:
    """Rewrite every tour block of README.md and docs/*.md by running it
    (a few minutes on 2 cores); returns the number of blocks."""
    n = 0
    for path in tour_files(repo):
        src = path.read_text()
        parts, last = [], 0
        for m in TOUR.finditer(src):
            parts += [src[last:m.start("block")], run_tour_block(repo, m.group("block"))]
            last = m.end("block")
            n += 1
        path.write_text("".join(parts) + src[last:])
    if not n:
        raise CfaMitsubaError("no <!-- tour --> ```console ... ``` <!-- /tour --> block in README.md or docs/*.md")
    return n


def normalised(text: str) -> str:
    """``text`` with what differs between runs masked: seconds and cache keys."""
    text = re.sub(r"\b[0-9a-f]{32}\b", "KEY", text)
    return re.sub(r"\b\d+(\.\d+)? s\b", "T s", text)


def _last_digit_unit(token: str) -> float:
    """One unit in the last printed digit of the decimal ``token`` ('1.68723' -> 1e-5, '2.5e-07' -> 1e-8)."""
    mantissa, _, exponent = token.lower().partition("e")
    return 10.0 ** (int(exponent or 0) - len(mantissa.split(".")[1]))


def _numbers_differ(fresh: str, shown: str, rtol: float) -> bool:
    if "." not in shown.lower().partition("e")[0] or "." not in fresh.lower().partition("e")[0]:
        return fresh != shown  # an integer (a count, a size, a seed) or an exact input: exactly
    allowed = max(rtol * abs(float(shown)), _last_digit_unit(shown))
    return abs(float(fresh) - float(shown)) > allowed * (1.0 + 1e-9)  # the subtraction's own rounding


def differences(fresh: str, shown: str, rtol: float = TOUR_RTOL) -> list[str]:
    """Where a tour's fresh output differs from the block shown in the docs,
    one line each (empty: they agree).  Both are :func:`normalised`; words
    and integers must match exactly, decimals within ``rtol`` relative or one
    unit in the shown value's last digit (module docstring)."""
    a, b = normalised(fresh).splitlines(), normalised(shown).splitlines()
    if len(a) != len(b):
        return [f"{len(a)} lines printed now, {len(b)} shown"]
    out = []
    for n, (now, was) in enumerate(zip(a, b), 1):
        parts_now, parts_was = _NUMBER.split(now), _NUMBER.split(was)
        # split with one group: text at even positions, numbers at odd ones
        if len(parts_now) != len(parts_was) or parts_now[::2] != parts_was[::2] or any(
                _numbers_differ(x, y, rtol) for x, y in zip(parts_now[1::2], parts_was[1::2])):
            out.append(f"line {n}: now {now!r}, shown {was!r}")
    return out
