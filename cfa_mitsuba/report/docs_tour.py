"""The README's command-line tour, produced by running it.

The tour is the ```console block between ``<!-- tour -->`` and
``<!-- /tour -->`` in README.md.  :func:`run_tour` runs each ``$
cfa-mitsuba ...`` line in a fresh folder with an empty render cache (as
``python3 -m cfa_mitsuba``, the same program) and writes its output back
under it, keeping the block's layout: a command shown without output stays
so (a trailing ``# comment`` or no lines below it), a long output shown
with a ``...`` line keeps as many lines before and after it and its lines
are cut at 150 characters with ``...``, and the notices on how files were read
(``... pass --X to override``) are left out.  Nothing is typed by hand, so
the numbers the tour prints (exposure, raw range, condition number, dE00)
are those of the code.  ``normalised`` masks what changes between runs
(seconds, cache keys) so a test can compare a fresh run with the README.
"""

from __future__ import annotations

__all__ = ["TOUR", "tour_commands", "run_tour_block", "run_tour", "normalised"]

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


def run_tour(repo: Path) -> None:
    """Rewrite README.md's tour block by running it (about a minute on 2 cores)."""
    readme = repo / "README.md"
    src = readme.read_text()
    m = TOUR.search(src)
    if not m:
        raise CfaMitsubaError("README.md has no <!-- tour --> ```console ... ``` <!-- /tour --> block")
    new = run_tour_block(repo, m.group("block"))
    readme.write_text(src[:m.start("block")] + new + src[m.end("block"):])


def normalised(text: str) -> str:
    """``text`` with what differs between runs masked: seconds and cache keys."""
    text = re.sub(r"\b[0-9a-f]{32}\b", "KEY", text)
    return re.sub(r"\b\d+(\.\d+)? s\b", "T s", text)
