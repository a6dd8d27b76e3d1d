"""The tidy tables a study writes from the details it kept (issue 50):
``mtf.csv`` (:mod:`.mtf_table`), ``patches.csv`` (:mod:`.patches`) and
``steps.csv`` (:mod:`.steps`); a table whose metric the study did not
measure is not written."""

from __future__ import annotations

__all__ = ["write_detail_tables"]

from pathlib import Path


def write_detail_tables(out_dir, tasks, details_dir) -> list[Path]:
    """Write the three tables into ``out_dir``; returns the files written."""
    from .mtf_table import write_mtf_csv
    from .patches import write_patches_csv
    from .steps import write_steps_csv

    written = [write(out_dir, tasks, details_dir) for write in (write_mtf_csv, write_patches_csv, write_steps_csv)]
    return [p for p in written if p is not None]
