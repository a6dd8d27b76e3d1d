"""README, docs/ and the sources their marked numbers name, copied under a
temporary folder as in the repository (the docs-numbers tests change a copy)."""

from __future__ import annotations

import shutil
from pathlib import Path

from conftest import REPO


def _copy_docs(tmp: Path) -> Path:
    """README, docs/ and every source a marker names, under ``tmp`` as in the repository."""
    shutil.copy(REPO / "README.md", tmp / "README.md")
    shutil.copytree(REPO / "docs", tmp / "docs", ignore=shutil.ignore_patterns("*.png", "*.svg", "*.html"))
    (tmp / "tests" / "data").mkdir(parents=True)
    shutil.copy(REPO / "tests" / "data" / "quick_expected.csv", tmp / "tests" / "data" / "quick_expected.csv")
    return tmp
