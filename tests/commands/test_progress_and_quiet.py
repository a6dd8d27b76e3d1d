"""Every long command shows progress on a terminal and prints only its
result path with --quiet (issue 50): report, render and study here; the
bar itself is tested on a pseudo-terminal."""

from __future__ import annotations

import shutil

from conftest import run_cli
from io_progress_helpers import run_on_terminal
from report_fixtures import study_dir


def test_report_quiet_prints_only_the_path(tmp_path_factory, tmp_path):
    src = study_dir(tmp_path_factory)
    results = tmp_path / "results"
    shutil.copytree(src, results)
    proc = run_cli("report", results, "--quiet", "--formats", "none", "--workers", "1", check_rc=0)
    assert proc.stdout == f"{results / 'report.html'}\n" and proc.stderr == ""


def test_report_draws_a_bar_on_a_terminal(tmp_path_factory, tmp_path):
    src = study_dir(tmp_path_factory)
    results = tmp_path / "results"
    shutil.copytree(src, results)
    code = ("import sys; from cfa_mitsuba.cli import main; "
            f"sys.exit(main(['report', {str(results)!r}, '--formats', 'none', '--workers', '1']))")
    err = run_on_terminal(code, tty=True)
    assert "report:" in err and "figure" in err


def test_render_quiet_prints_only_the_files(tmp_path):
    proc = run_cli("render", "gray-bar", "--out", tmp_path, "--width", 60, "--height", 20, "--quiet", check_rc=0)
    assert proc.stderr == ""
    assert proc.stdout.split() == [str(tmp_path / "gray-bar.exr"), str(tmp_path / "gray-bar.json")]


def test_study_quiet_prints_only_the_path(tmp_path):
    cfg = tmp_path / "q.toml"
    cfg.write_text('name = "q"\nscenes = ["macbeth"]\ncfas = ["bayer"]\ndemosaics = ["bilinear"]\nseeds = 2\n'
                   '[render.macbeth]\nwidth = 60\nheight = 53\n[output]\nreport = false\n')
    proc = run_cli("study", cfg, "--out", tmp_path / "out", "--quiet", "--workers", "1", check_rc=0)
    assert proc.stdout == f"{tmp_path / 'out' / 'metrics.csv'}\n" and proc.stderr == ""
    loud = run_cli("study", cfg, "--out", tmp_path / "out2", "--workers", "1", check_rc=0)
    assert "study 'q'" in loud.stderr and "done in" in loud.stderr and "\r" not in loud.stderr  # no bar in a pipe
