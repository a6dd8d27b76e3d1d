"""Shared by the report tests: one small real study per test session, and
headless Chromium.  (No tests here.)"""

from __future__ import annotations

import shutil
import subprocess
import tempfile
from pathlib import Path

import pytest

#: A study small enough to run in a test (about 10 s from an empty render
#: cache): every scene at small sizes, two CFAs, two demosaics, a puppy sweep.
STUDY_TOML = """
name = "report-test"
description = "tiny study for the report tests"
scenes = ["macbeth", "slanted-edge", "chirp", "gray-bar", "puppy"]
cfas = ["bayer", "rgbw1"]
demosaics = ["bilinear", "pocs"]
luminances = [100]

[[sweep]]
scene = "puppy"
metrics = ["scielab", "ssim"]
luminances = [30, 100]

[render.macbeth]
width = 144
height = 128
[render.slanted-edge]
width = 192
height = 160
[render.chirp]
width = 200
height = 120
[render.gray-bar]
width = 160
height = 100
[render.puppy]
width = 144
height = 128
spp = 16
"""

_STUDY: dict = {}


def study_dir(tmp_path_factory) -> Path:
    """The study's results directory, run once per session (process)."""
    if "dir" not in _STUDY:
        from cfa_mitsuba.study.config import load_config
        from cfa_mitsuba.study.runner import run_study

        base = tmp_path_factory.mktemp("report-study")
        cfg = base / "study.toml"
        cfg.write_text(STUDY_TOML)
        out = base / "results"
        run_study(load_config(cfg), out, workers=1, progress=False, log=lambda msg: None)
        _STUDY["dir"] = out
    return _STUDY["dir"]


def chromium() -> str:
    for name in ("chromium", "chromium-browser", "google-chrome"):
        exe = shutil.which(name)
        if exe:
            return exe
    pytest.fail("headless Chromium is needed to check the report: run ./setup.sh (apt-get install chromium)")


def run_chromium(*args, timeout=120) -> subprocess.CompletedProcess:
    """Headless Chromium with a throw-away profile and no network services."""
    profile = tempfile.mkdtemp(prefix="cfa-report-chromium-")
    try:
        return subprocess.run(
            [chromium(), "--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
             "--disable-component-update", "--disable-sync", "--no-first-run", f"--user-data-dir={profile}",
             *args], capture_output=True, text=True, timeout=timeout)
    finally:
        shutil.rmtree(profile, ignore_errors=True)
