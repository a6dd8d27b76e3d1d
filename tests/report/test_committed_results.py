"""What a committed example folder must hold for ``cfa-mitsuba report`` to
draw every figure from it alone (issue 50: docs/example-report-isetcam had
its tables only, and its report said 'not drawn ... rerun the study'):
the tables and the details of the primary luminance, nothing else."""

from __future__ import annotations

import re
import shutil

from report_fixtures import study_dir

from cfa_mitsuba.report import build_report

#: The files of a results directory a committed example keeps (the lead's recipe in docs/report.md).
KEEP = ("*.csv", "*.json", "details/*/*/*/L100.*", "details/*/ideal/L100.*")


def test_tables_and_the_primary_details_draw_every_figure(tmp_path_factory, tmp_path):
    src = study_dir(tmp_path_factory)
    out = tmp_path / "committed"
    for pattern in KEEP:
        for f in src.glob(pattern):
            target = out / f.relative_to(src)
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(f, target)
    assert not (out / ".work").exists() and not list(out.glob("details/puppy/*/*/L30.*"))
    page = build_report(out, formats=(), workers=1).read_text()
    absent = re.findall(r'<div class="absent"><b>([^<]*)</b>', page)
    assert absent == [], absent
    for key in ("crops-puppy", "patch-errors", "step-snr", "mtf", "moire", "achromatic", "scielab-maps",
                "outputs-puppy", "sensor-curves"):
        assert f'data-figure="{key}"' in page, key


def test_without_details_the_report_says_what_is_missing(tmp_path_factory, tmp_path):
    src = study_dir(tmp_path_factory)
    out = tmp_path / "tables-only"
    out.mkdir()
    for f in list(src.glob("*.csv")) + list(src.glob("*.json")):
        shutil.copy2(f, out / f.name)
    page = build_report(out, formats=(), workers=1).read_text()
    # the figures drawn from tables alone
    for key in ("patch-errors", "step-snr", "dynamic-range", "sensor-curves", "ranks"):
        assert f'data-figure="{key}"' in page, key
    assert "Crops at 1:1 and 4:1: puppy: not drawn." in page and "rerun the study" in page
