"""A study from Python (issue 50): ``cm.study.run`` and ``cm.study.load``.

    >>> import cfa_mitsuba as cm                                  # doctest: +SKIP
    >>> r = cm.study.run("configs/quick.toml")                    # doctest: +SKIP
    >>> r.decisions[["aspect", "verdict", "cfas"]]                 # doctest: +SKIP
    >>> r.metrics.query("metric == 'mtf'")                         # doctest: +SKIP
    >>> cm.study.load("results/quick").report_path                 # doctest: +SKIP

:func:`run` does what ``cfa-mitsuba study`` does (the same runner, the same
files, the report unless ``report=False``) and returns the tables as pandas
DataFrames (:class:`Results`); :func:`load` reads a finished results
directory the same way, without running anything.

The report is the next stage: this module does not import it.  The report
package registers its builder here when it is imported
(:func:`register_report_builder`), and ``cm.study`` imports it (the
package root, ``cfa_mitsuba/__init__.py``), so ``import cfa_mitsuba as cm;
cm.study.run(...)`` builds the report.
"""

from __future__ import annotations

__all__ = ["Results", "run", "load", "register_report_builder"]

import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import CfaMitsubaError

#: The report's builder, ``f(out_dir, output_config, timing, workers,
#: progress) -> Path``, registered by the report package (module doc).
_REPORT_BUILDER: list = []

#: Tables read into :class:`Results`: attribute -> file (None when the study wrote none).
_TABLES = {"metrics": "metrics.csv", "scores": "scores.csv", "decisions": "decisions.csv", "snr": "snr.csv",
           "snr10": "snr10.csv", "mtf": "mtf.csv", "patches": "patches.csv", "steps": "steps.csv"}


def register_report_builder(builder) -> None:
    """Make ``builder`` the one :func:`run` calls to write the report."""
    _REPORT_BUILDER[:] = [builder]


@dataclass
class Results:
    """A study's results as pandas DataFrames (None where the study wrote
    no such table; docs/study.md describes every column).

    ``metrics``: metrics.csv (one row per scene, CFA, demosaic, condition
    and metric: the mean over the noise realisations, its 95 % interval,
    lux and dB columns); ``scores``: scores.csv; ``decisions``:
    decisions.csv (which CFA to pick per aspect); ``snr``: snr.csv (SNR
    against light); ``snr10``, ``mtf``, ``patches``, ``steps``: the other
    tables; ``report_path``: report.html (None without a report);
    ``out_dir``; ``timing`` and ``config``: timing.json and config.json as dicts.
    """

    out_dir: Path
    metrics: object
    scores: object = None
    decisions: object = None
    snr: object = None
    report_path: Path | None = None
    snr10: object = None
    mtf: object = None
    patches: object = None
    steps: object = None
    timing: dict = field(default_factory=dict)
    config: dict = field(default_factory=dict)

    def __repr__(self) -> str:
        have = [k for k in _TABLES if getattr(self, k) is not None]
        n = 0 if self.metrics is None else len(self.metrics)
        return (f"Results({str(self.out_dir)!r}: {n} metric rows; tables {', '.join(have)}; "
                f"report {str(self.report_path) if self.report_path else 'none'})")


def _read_json(path: Path) -> dict:
    import json

    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError):
        return {}
    return data if isinstance(data, dict) else {}


def load(out_dir) -> Results:
    """Read a finished study's results directory (``metrics.csv`` at least)
    into a :class:`Results`; a one-line :class:`CfaMitsubaError` when it is
    not one."""
    import pandas as pd

    root = Path(out_dir)
    if not root.is_dir():
        raise CfaMitsubaError(f"no such results directory {str(root)!r}")
    if not (root / "metrics.csv").is_file():
        raise CfaMitsubaError(f"{str(root)!r} is not a study's results directory (no metrics.csv)")
    tables = {}
    for attr, name in _TABLES.items():
        path = root / name
        if not path.is_file():
            tables[attr] = None
            continue
        try:
            tables[attr] = pd.read_csv(path, keep_default_na=True)
        except (OSError, ValueError) as exc:
            raise CfaMitsubaError(f"cannot read {str(path)!r}: {exc}") from None
    report = root / "report.html"
    return Results(out_dir=root, report_path=report if report.is_file() else None,
                   timing=_read_json(root / "timing.json"), config=_read_json(root / "config.json"), **tables)


def _config(config_or_path):
    from .config import StudyConfig, load_config, parse_config

    if isinstance(config_or_path, StudyConfig):
        return config_or_path
    if isinstance(config_or_path, dict):
        return parse_config(config_or_path)
    if isinstance(config_or_path, (str, Path)):
        return load_config(config_or_path)
    raise CfaMitsubaError(f"cm.study.run takes a config path, a dict or a StudyConfig, not "
                          f"{type(config_or_path).__name__}")


def run(config_or_path, out=None, *, workers: int | None = None, scheduler: str | None = None,
        report: bool = True, progress: bool = True, quiet: bool = False, force: bool = False) -> Results:
    """Run a study and return its tables (:class:`Results`).

    Parameters
    ----------
    config_or_path : a study config: a TOML path (configs/quick.toml), a
        dict of the same keys, or a parsed ``StudyConfig``.
    out : the results directory (default ``results/<config name>``, as
        ``cfa-mitsuba study``); an interrupted study in it resumes.
    workers, scheduler, force : as ``cfa-mitsuba study`` (local processes,
        a Dask scheduler address, start a study above the size limits).
    report : also write report.html and figures/ (the config's
        ``[output]`` settings); False: the tables only.
    progress : progress bars on stderr; ``quiet``: no bars and no log lines.
    """
    from ..io.validate import safe_name
    from .runner import run_study, timing_summary, write_timing

    config = _config(config_or_path)
    target = Path(out) if out is not None else Path("results") / safe_name(config.name)
    log = (lambda msg: None) if quiet else (lambda msg: print(msg, file=sys.stderr))
    result = run_study(config, target, workers=workers, scheduler=scheduler, progress=progress and not quiet,
                       log=log, force=force)
    if report and config.output.get("report", True):
        if not _REPORT_BUILDER:
            raise CfaMitsubaError("the report stage is not loaded: import cfa_mitsuba.report first (cm.study does), "
                                  "or run(..., report=False)")
        t = time.perf_counter()
        _REPORT_BUILDER[0](result.out_dir, dict(config.output), result.timing, workers or config.workers,
                           progress and not quiet)
        phases = result.timing["phases"]
        phases["report_s"] = time.perf_counter() - t
        phases["total_s"] += phases["report_s"]
        write_timing(result)
    log(timing_summary(result))
    return load(result.out_dir)
