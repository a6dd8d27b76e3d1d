"""The report: built from a small real study run here, then checked as a
user would meet it.

- the HTML is one self-contained file (no http(s)://, file://, script,
  stylesheet link or image that is not a data URI);
- every expected figure exists in figures/ and shows data (PNGs are not a
  flat colour, SVGs hold path data) and is embedded in the page;
- Tables 1-3 hold the CSV values;
- headless Chromium loads it with no console message and every embedded
  image decodes (Chromium is installed by setup.sh; the test fails without
  it rather than skipping);
- ``cfa-mitsuba report`` rebuilds it and refuses a bad directory with exit 2.

Partial results directories are in tests/report/test_partial_results.py; both
modules use the one study of tests/report_fixtures.py.
"""

from __future__ import annotations

import html.parser
import io
import json
import os
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from cfa_mitsuba.io.owned import record_written
from conftest import assert_one_line_error, run_cli
from report_fixtures import run_chromium, study_dir

pytestmark = pytest.mark.slow

DEMOSAICS = ("bilinear", "pocs")
SCENES = ("macbeth", "slanted-edge", "chirp", "gray-bar", "puppy")
#: figures/ stems and whether each has an SVG (image sheets are PNG only).
EXPECTED_FIGURES = {
    "radar-demosaic": True, "radar-cfa": True, "ranks": True, "tiles": True, "mtf": True, "moire": True, "achromatic": True,
    "luminance-sweep": True, "scielab-maps": False, "sensor-curves": True,
    **{f"ab-{d}": True for d in DEMOSAICS}, **{f"xy-{d}": True for d in DEMOSAICS},
    **{f"outputs-{s}": False for s in SCENES},
    # issue 50: each patch's error, the gray steps' SNR and dynamic range, the crop grids
    "patch-errors": False, "step-snr": True, "dynamic-range": True,
    **{f"crops-{s}": False for s in ("slanted-edge", "chirp", "puppy")},
}


@pytest.fixture(scope="session")
def report_study(tmp_path_factory) -> Path:
    """A finished study's results directory (report not yet built; shared, do not modify)."""
    return study_dir(tmp_path_factory)


@pytest.fixture(scope="session")
def built_report(report_study, tmp_path_factory) -> Path:
    """A copy of the study with its report built (png and svg figures)."""
    from cfa_mitsuba.report import build_report

    out = tmp_path_factory.mktemp("report-built") / "results"
    shutil.copytree(report_study, out)
    path = build_report(out, formats=("png", "svg"), thumbnails=True)
    assert path == out / "report.html"
    return out


class _Cells(html.parser.HTMLParser):
    """Collects the ``data-value`` of every table cell and the embedded images."""

    def __init__(self):
        super().__init__()
        self.values: list[float] = []
        self.images: list[dict] = []

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "td" and "data-value" in a:
            self.values.append(float(a["data-value"]))
        if tag == "img":
            self.images.append(a)


def _parse(text: str) -> _Cells:
    p = _Cells()
    p.feed(text)
    return p


def _has(values, v, rel=1e-9) -> bool:
    return bool(np.any(np.isclose(values, v, rtol=rel, atol=1e-12)))


# -- the page ----------------------------------------------------------------------------------

def test_report_is_self_contained(built_report):
    text = (built_report / "report.html").read_text(encoding="utf-8")
    low = text.lower()
    for bad in ("http://", "https://", "file://", "<script", "<link", "@import", "<iframe"):
        assert bad not in low, f"report.html holds {bad!r}"
    srcs = re.findall(r'\bsrc="([^"]*)"', text)
    assert srcs and all(s.startswith("data:image/") for s in srcs), [s[:40] for s in srcs if not s.startswith("data:")]
    hrefs = re.findall(r'\bhref="([^"]*)"', text)
    assert all(h.startswith("#") for h in hrefs), [h for h in hrefs if not h.startswith("#")]
    assert "could not be drawn" not in text and "not drawn" not in text


def test_every_figure_exists_and_shows_data(built_report):
    from PIL import Image

    figs = built_report / "figures"
    for stem, svg in EXPECTED_FIGURES.items():
        png = figs / f"{stem}.png"
        assert png.is_file(), f"figures/{stem}.png missing"
        with Image.open(png) as im:
            a = np.asarray(im.convert("RGB"), dtype=float)
        assert a.shape[0] > 100 and a.shape[1] > 100, (stem, a.shape)
        assert a.std() > 5.0, f"{stem}.png is (nearly) one flat colour"
        codes = (a[..., 0] * 65536 + a[..., 1] * 256 + a[..., 2]).astype(np.int64)
        assert np.unique(codes).size > 50, f"{stem}.png has too few colours to hold data"
        if svg:
            text = (figs / f"{stem}.svg").read_text()
            paths = re.findall(r'<path[^>]*\sd="([^"]+)"', text)
            assert len(paths) > 20 and sum(len(p) for p in paths) > 5000, f"{stem}.svg holds no drawing"
        else:
            assert not (figs / f"{stem}.svg").exists()
    # the page embeds each of them once
    cells = _parse((built_report / "report.html").read_text(encoding="utf-8"))
    embedded = [i.get("data-figure") for i in cells.images]
    assert sorted(embedded) == sorted(EXPECTED_FIGURES), embedded


def test_tables_hold_the_csv_values(built_report):
    import pandas as pd

    text = (built_report / "report.html").read_text(encoding="utf-8")
    values = np.array(_parse(text).values)
    scores = pd.read_csv(built_report / "scores.csv")
    metrics = pd.read_csv(built_report / "metrics.csv")
    # Table 2: every scored value
    for r in scores.itertuples():
        assert _has(values, r.value), f"Table 2 lacks {r.cfa}/{r.demosaic}/{r.metric} = {r.value}"
    # Table 3: every mean score and total score
    for v in pd.concat([scores["mean_score"], scores["total_score"]]).unique():
        assert _has(values, v), f"Table 3 lacks score {v}"
    # Table 1: mean dE00, dE76 and grey dL of every CFA and demosaic
    t1 = metrics[metrics["metric"].isin(["delta-e", "delta-e76", "delta-l"]) & (metrics["luminance"] == 100)]
    assert len(t1) == 2 * 2 * 3
    for r in t1.itertuples():
        assert _has(values, r.value), f"Table 1 lacks {r.cfa}/{r.demosaic}/{r.metric} = {r.value}"
    # the sweep's values are in its table too
    sweep = metrics[(metrics["scene"] == "puppy") & (metrics["luminance"] == 30)
                    & metrics["metric"].isin(["scielab", "ssim"])]
    assert len(sweep) and all(_has(values, v) for v in sweep["value"])
    # the best value per metric and demosaic is boxed (ties all boxed)
    from cfa_mitsuba.report.style import metric_display

    higher = {"ssim", "mtf", "moire", "haarpsi"}
    n_best = 0
    for (d, m), g in scores.groupby(["demosaic", "metric"]):
        shown = g["value"].map(lambda v: float(f"{v:.{metric_display(m).decimals}f}"))  # ties as printed: all boxed
        target = shown.max() if m in higher else shown.min()
        n_best += int((shown == target).sum())
    t2 = text[text.index('id="table2"'):text.index('id="table3"')]
    assert t2.count('class="best') == n_best


def test_summary_names_the_best_cfa(built_report):
    import pandas as pd

    scores = pd.read_csv(built_report / "scores.csv")
    best = scores.loc[scores["total_rank"] == 1, "cfa"].iloc[0]
    text = (built_report / "report.html").read_text(encoding="utf-8")
    summary = text[text.index('id="summary"'):text.index('id="tables"')]
    assert "Best CFA overall" in summary and f"{best}</div>" in summary


def test_chromium_loads_it_without_errors(built_report, tmp_path):
    """Headless Chromium: no console message, every image decodes, the DOM
    holds every figure.  A copy of the page gets a one-line script that
    records what the browser decoded (the report itself has no script)."""
    page = built_report / "report.html"
    probe = ('<script>window.addEventListener("load",function(){var im=[].slice.call(document.images);'
             'var bad=im.filter(function(i){return !(i.complete&&i.naturalWidth>0)})'
             '.map(function(i){return i.getAttribute("data-figure")});'
             'document.body.setAttribute("data-check",JSON.stringify({n:im.length,bad:bad}));});</script>')
    check = tmp_path / "check.html"
    check.write_text(page.read_text(encoding="utf-8").replace("</body>", probe + "</body>"), encoding="utf-8")
    proc = run_chromium("--enable-logging=stderr", "--v=0", "--virtual-time-budget=10000", "--dump-dom",
                        check.as_uri())
    assert proc.returncode == 0, proc.stderr[-2000:]
    console = [line for line in proc.stderr.splitlines() if ":CONSOLE" in line]
    assert not console, console
    m = re.search(r'data-check="([^"]*)"', proc.stdout)
    assert m, "Chromium did not finish loading the page"
    got = json.loads(m.group(1).replace("&quot;", '"'))
    assert got["bad"] == [] and got["n"] == len(EXPECTED_FIGURES), got
    for stem in EXPECTED_FIGURES:
        assert f'data-figure="{stem}"' in proc.stdout
    # and the page itself, unmodified, logs nothing either
    plain = run_chromium("--enable-logging=stderr", "--v=0", "--dump-dom", page.as_uri())
    assert plain.returncode == 0 and "Table 3" in plain.stdout
    assert not [line for line in plain.stderr.splitlines() if ":CONSOLE" in line]


def test_chromium_screenshot_is_not_blank(built_report, tmp_path):
    from PIL import Image

    shot = tmp_path / "shot.png"
    proc = run_chromium(f"--screenshot={shot}", "--window-size=1400,3000", "--hide-scrollbars",
                        (built_report / "report.html").as_uri())
    assert proc.returncode == 0 and shot.is_file(), proc.stderr[-2000:]
    with Image.open(shot) as im:
        a = np.asarray(im.convert("RGB"), dtype=float)
    assert a.shape[:2] == (3000, 1400)
    assert a.std() > 20 and (a.mean(axis=2) < 128).mean() > 0.01  # text, tables, a dark header


# -- rebuilding ----------------------------------------------------------------------------------

def test_cli_rebuilds_the_report(report_study, tmp_path):
    out = tmp_path / "results"
    shutil.copytree(report_study, out)
    (out / "figures").mkdir()
    (out / "figures" / "stale-cfa.png").write_bytes(b"old")  # from an earlier build with other CFAs ...
    record_written(out / "figures", ["stale-cfa.png"])  # ... which recorded writing it
    (out / "figures" / "users-own.png").write_bytes(b"mine")  # never written by the project
    proc = run_cli("report", out, "--formats", "png", check_rc=0)
    assert proc.stdout.strip() == str(out / "report.html")
    assert (out / "report.html").stat().st_size > 100_000
    names = {p.name for p in (out / "figures").iterdir()}
    assert "stale-cfa.png" not in names and "radar-cfa.png" in names
    assert (out / "figures" / "users-own.png").read_bytes() == b"mine"  # the report deletes only its own files
    assert not any(n.endswith(".svg") for n in names)
    assert oct((out / "report.html").stat().st_mode & 0o044) == oct(0o044 & ~_umask())


def _umask() -> int:
    m = os.umask(0)
    os.umask(m)
    return m


def test_cli_refuses_a_bad_directory(tmp_path, capsys):
    from cfa_mitsuba.cli import main

    def refused(path, *needles):
        rc = main(["report", str(path)])
        err = capsys.readouterr().err
        assert_one_line_error(subprocess.CompletedProcess([], rc, "", err), *needles)

    refused(tmp_path / "nowhere", "no such results directory")
    refused(tmp_path, "not a results directory", "metrics.csv")
    f = tmp_path / "metrics.csv"
    f.write_text("a,b\n1,2\n")
    refused(tmp_path, "not a metrics table")
    refused(f, "is a file")
    assert not (tmp_path / "report.html").exists()
    # and through the installed command, once
    assert_one_line_error(run_cli("report", tmp_path / "nowhere"), "no such results directory")


def test_build_report_refuses_an_unknown_format(report_study):
    from cfa_mitsuba.errors import CfaMitsubaError
    from cfa_mitsuba.report import build_report

    with pytest.raises(CfaMitsubaError, match="unknown figure format"):
        build_report(report_study, formats=("png", "gif"))


def test_png_bytes_are_images(built_report):
    """The embedded figures decode as what their MIME type says."""
    import base64

    from PIL import Image

    cells = _parse((built_report / "report.html").read_text(encoding="utf-8"))
    for img in cells.images:
        mime, b64 = img["src"][5:].split(";base64,", 1)
        data = base64.b64decode(b64)
        if mime == "image/svg+xml":
            assert data.lstrip().startswith(b"<?xml") and b"<svg" in data[:2000]
        else:
            with Image.open(io.BytesIO(data)) as im:
                assert im.format.lower() in mime and im.width > 100


# -- figures drawn in worker processes --------------------------------------------------------------

def _files(folder: Path) -> dict:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir())}


def test_figures_drawn_in_two_processes_are_the_same_bytes(built_report, report_study, tmp_path):
    """workers=2 spawns processes that each load the results and draw the
    figure functions as they come free: the figures and the page are the
    bytes of the one-process build (the page's only other input, the
    folder's name, is the same here)."""
    from cfa_mitsuba.report import build_report

    out = tmp_path / "results"  # the same folder name as built_report's: the page's footer names it
    shutil.copytree(report_study, out)
    lines = []
    build_report(out, formats=("png", "svg"), thumbnails=True, workers=2, log=lines.append)
    assert any("(2 process(es))" in line for line in lines)
    assert not any("failed" in line for line in lines)
    mine, theirs = _files(out / "figures"), _files(built_report / "figures")
    assert mine.keys() == theirs.keys() and len(mine) > 20
    assert [k for k in mine if mine[k] != theirs[k]] == []
    assert (out / "report.html").read_bytes() == (built_report / "report.html").read_bytes()


def test_a_failed_worker_pool_still_gives_the_whole_report(built_report, report_study, tmp_path, monkeypatch):
    """Processes that cannot start (or die) cost time, never figures: the
    parent draws what they did not return."""
    import concurrent.futures

    from cfa_mitsuba.report import build_report

    class NoProcesses:
        def __init__(self, *args, **kwargs):
            raise OSError("no processes for you")

    monkeypatch.setattr(concurrent.futures, "ProcessPoolExecutor", NoProcesses)
    out = tmp_path / "results"
    shutil.copytree(report_study, out)
    lines = []
    build_report(out, formats=("png", "svg"), thumbnails=True, workers=2, log=lines.append)
    assert any("report worker processes failed (OSError: no processes for you)" in line for line in lines)
    assert _files(out / "figures") == _files(built_report / "figures")


def test_report_workers_are_checked(report_study, tmp_path, capsys, monkeypatch):
    from cfa_mitsuba.cli import main
    from cfa_mitsuba.errors import CfaMitsubaError
    from cfa_mitsuba.report import build_report, report_workers

    for bad in (0, -1, 1.5, "2", True):
        with pytest.raises(CfaMitsubaError, match="report workers must be a whole number"):
            build_report(report_study, workers=bad)
    rc = main(["report", str(report_study), "--workers", "0"])
    assert_one_line_error(subprocess.CompletedProcess([], rc, "", capsys.readouterr().err), "report workers")
    assert not (report_study / "report.html").exists()
    cores = len(os.sched_getaffinity(0))
    monkeypatch.delenv("CFA_MITSUBA_WORKERS", raising=False)  # the suite's own default (tests/conftest.py)
    assert report_workers(None) == min(2, cores) and report_workers(10 ** 6) == cores


def test_svg_ids_do_not_depend_on_numpy_print_mode():
    """matplotlib hashes the repr of a clip rectangle's bounds into its SVG
    id; colour-science's import puts numpy in its 1.13 print mode, which
    writes numpy floats otherwise.  The same figure gives the same SVG in
    either mode (so a figure drawn in a worker that has not imported
    colour-science matches one drawn after it)."""
    import matplotlib

    from cfa_mitsuba.report.figure import RC, figure_bytes, panel_grid

    with matplotlib.rc_context(RC):  # the report's fixed SVG hash salt
        fig, axes = panel_grid(1, 2, 1.7, 1.3)
        for ax in axes:
            ax.plot([0.1, 0.7, 0.3], [1.0, 2.5, 2.0])
        with np.printoptions(legacy=False):
            modern = figure_bytes(fig, "svg")
        with np.printoptions(legacy="1.13"):
            legacy = figure_bytes(fig, "svg")
    assert b"clip-path" in modern and modern == legacy
