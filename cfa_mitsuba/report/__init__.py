"""report/: the study's report, figures and tables (Bae 2020, Tables 1-3 and
Figs 6-17, re-created for a run).

``build_report(results_dir)`` reads what a study wrote (metrics.csv,
scores.csv, ranges.json, timing.json, config.json, details/) and writes

    results_dir/report.html   one self-contained page (figures embedded)
    results_dir/figures/      every figure as PNG and SVG

The modules: :mod:`.results` (reading the directory), :mod:`.style`
(colours, labels), :mod:`.figures_scores` (radar, ranks, luminance sweep),
:mod:`.figures_detail` (MTF, moire, patches, S-CIELAB maps, gray bar,
thumbnails), :mod:`.tables` (Tables 1-3), :mod:`.page` (the HTML),
:mod:`.build`, and :mod:`.convergence` (the plot of ``cfa-mitsuba
convergence``).
"""

from .build import FIGURE_FORMATS, build_report, report_workers  # noqa: F401
from .results import Results, load_results  # noqa: F401


def _study_report(out_dir, output: dict, timing: dict, workers, progress: bool = False):
    """The report of ``cm.study.run`` (study/api.py), as ``cfa-mitsuba study`` builds it."""
    return build_report(out_dir, formats=output.get("figures", ("png", "svg")),
                        thumbnails=output.get("thumbnails", True), timing=timing, workers=report_workers(workers),
                        progress=progress)


def _register() -> None:
    from ..study.api import register_report_builder

    register_report_builder(_study_report)


_register()

__all__ = ["build_report", "report_workers", "load_results", "Results", "FIGURE_FORMATS"]
