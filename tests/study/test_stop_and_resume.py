"""Hardening, round three (issue 27), the study's items: a stopped study
stops every process it started and resumes (1); untrusted resume files are
recomputed with one notice (8).

A small study (one Macbeth render, six CFAs, two workers) runs once
uninterrupted; every stopped or damaged run must end, when run again, with
byte-identical tables.
"""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd
import pytest

from conftest import REPO

SMALL = """\
name = "small"
seed = 1
seeds = 2
scenes = ["macbeth"]
cfas = ["bayer", "rgb4", "cmy1", "rgbw1", "rgb1", "rgb2"]
demosaics = ["bilinear", "pocs"]
luminances = [100]
[render.macbeth]
width = 120
height = 106
[output]
report = false
"""


def _cmd(config: Path, out: Path, *extra, quiet: bool = True) -> list[str]:
    return [sys.executable, "-m", "cfa_mitsuba", "study", str(config), "--out", str(out), *(["--quiet"] if quiet else []),
            *map(str, extra)]


def _study(config: Path, out: Path, *extra, quiet: bool = True, **kw) -> subprocess.CompletedProcess:
    """The study command (``quiet``: --quiet, which prints the result path alone)."""
    return subprocess.run(_cmd(config, out, *extra, quiet=quiet), cwd=REPO, capture_output=True, text=True, **kw)


@pytest.fixture(scope="module")
def small(tmp_path_factory):
    config = tmp_path_factory.mktemp("small") / "small.toml"
    config.write_text(SMALL)
    proc = _study(config, config.parent / "reference", "--workers", 1)  # the tables do not depend on the workers
    assert proc.returncode == 0, proc.stderr
    return config, config.parent / "reference"


def _parents() -> dict[int, int]:
    """{pid: parent pid} of every process, from /proc (Linux)."""
    out = {}
    for name in os.listdir("/proc"):
        if name.isdigit():
            try:
                stat = Path(f"/proc/{name}/stat").read_text()
            except OSError:
                continue
            out[int(name)] = int(stat.rsplit(")", 1)[1].split()[1])
    return out


def _descendants(root: int) -> set[int]:
    parents, found, frontier = _parents(), set(), {root}
    while frontier:
        frontier = {pid for pid, ppid in parents.items() if ppid in frontier} - found
        found |= frontier
    return found


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"  # a zombie has ended; only its parent's bookkeeping is left


def _tables(out: Path) -> dict[str, bytes]:
    return {n: (out / n).read_bytes() for n in ("metrics.csv", "scores.csv", "metrics_realisations.csv")}


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGKILL], ids=["SIGTERM", "SIGKILL"])
def test_a_stopped_study_leaves_no_process_and_resumes(small, tmp_path, sig):
    config, reference = small
    out = tmp_path / "stopped"
    log = open(tmp_path / "stderr.txt", "w")  # not a pipe: a leaked worker would hold it open forever
    proc = subprocess.Popen(_cmd(config, out, "--workers", 2), cwd=REPO, stdout=subprocess.DEVNULL, stderr=log)
    children: set[int] = set()
    try:
        # evaluating (a study that never gets there is a hang: pytest-timeout ends the test)
        while not (out / ".work").is_dir() or not any((out / ".work").glob("*.json")):
            assert proc.poll() is None, (tmp_path / "stderr.txt").read_text()
            time.sleep(0.05)
        children = _descendants(proc.pid)
        assert len(children) >= 3, children  # two pool workers and multiprocessing's resource tracker
        proc.send_signal(sig)  # the main process only, as a CI timeout or the OOM killer does
        proc.wait(timeout=300)
        for _ in range(600):  # workers notice their parent's end within a second; 60 s of polls at most
            left = sorted(pid for pid in children if _alive(pid))
            if not left:
                break
            time.sleep(0.1)
        assert not left, f"alive a minute after {sig.name}: " + "; ".join(
            Path(f"/proc/{p}/cmdline").read_text().replace("\0", " ")[:100] for p in left)
    finally:
        log.close()
        for pid in children:  # never leave a leaked worker behind a failed test
            if _alive(pid):
                os.kill(pid, signal.SIGKILL)
    assert proc.returncode == -sig
    assert not (out / "metrics.csv").exists()
    finished = len(list((out / ".work").glob("*.json")))
    again = _study(config, out, "--workers", 2, quiet=False)  # its log says what was reused
    assert again.returncode == 0, again.stderr
    m = re.search(r"(\d+) task\(s\) run, (\d+) reused", again.stderr)
    assert m and int(m.group(2)) == finished and int(m.group(1)) == 6 - finished, again.stderr
    assert _tables(out) == _tables(reference)


DAMAGE = {
    "a string": json.dumps("not a result"),
    "a list": json.dumps([1, 2, 3]),
    "NaN": "NaN",
    "100,000-deep array": "[" * 100_000 + "]" * 100_000,
    "rows of strings": json.dumps({"rows": ["x"], "timing": {}}),
    "not JSON": "{\"rows\": [",
}


def test_untrusted_resume_files_are_recomputed_with_one_notice(small, tmp_path):
    import shutil

    config, reference = small
    out = tmp_path / "damaged"
    shutil.copytree(reference, out)  # a finished study's saved task results (the same config)
    files = sorted((out / ".work").glob("*.json"))
    assert len(files) == 6
    for f, text in zip(files, DAMAGE.values()):
        f.write_text(text)
    again = _study(config, out, "--workers", 1, quiet=False)  # its log says what was recomputed
    assert again.returncode == 0, again.stderr
    assert "Traceback" not in again.stderr
    notices = [line for line in again.stderr.splitlines() if "could not be trusted" in line]
    assert len(notices) == 1 and "6 saved task result(s)" in notices[0], again.stderr
    assert "6 task(s) run, 0 reused" in again.stderr
    assert _tables(out) == _tables(reference)
    # and the rewritten files are trusted by the next run
    third = _study(config, out, "--workers", 1, quiet=False)
    assert third.returncode == 0 and "0 task(s) run, 6 reused" in third.stderr, third.stderr


# ------------------------------------------------------------------ item 4: sized before it starts

def _sweep_of_a_million() -> str:
    values = ", ".join(f"{1 + i / 100:g}" for i in range(100))
    seeds = ", ".join(str(i) for i in range(100))
    return SMALL + f'\n[[sweep]]\nscene = "macbeth"\nread_noise_e = [{values}]\npixel_pitch_um = [{values}]\nseed = [{seeds}]\n'


@pytest.mark.parametrize("case", ["seeds", "sweep"])
def test_runaway_studies_are_refused_fast_with_the_estimate(tmp_path, case):
    text = SMALL.replace("seeds = 2", "seeds = 10000000") if case == "seeds" else _sweep_of_a_million()
    config = tmp_path / f"{case}.toml"
    config.write_text(text)
    out = tmp_path / "out"
    proc = _study(config, out, timeout=600)  # a study the limits fail to refuse must not run on
    lines = [line for line in proc.stderr.splitlines() if line.strip()]
    assert proc.returncode == 2 and len(lines) == 1 and "Traceback" not in proc.stderr, proc.stderr
    assert f"{case}.toml" in lines[0] and "--force" in lines[0]
    if case == "seeds":
        assert "60,000,000 capture(s)" in lines[0] and "24 h limit" in lines[0]
    else:  # counted, not built: 100 x 100 x 100 crossed plus the base condition
        assert "1,000,001 condition(s)" in lines[0] and "100,000-task limit" in lines[0]
    assert re.search(r"about [\d.,]+ (h|days)", lines[0])
    assert not out.exists()
    # how fast the refusal comes: benchmarks/bench_refusals.py (never a wall-time limit in a test)


def test_the_count_never_builds_the_conditions(monkeypatch):
    from cfa_mitsuba.study import conditions, runner
    from cfa_mitsuba.study.config import parse_config
    from cfa_mitsuba.study.sizing import study_size

    import tomllib

    config = parse_config(tomllib.loads(_sweep_of_a_million()), where="sweep.toml")

    def built(*args, **kwargs):
        raise AssertionError("the size estimate built the conditions it should only count")

    monkeypatch.setattr(conditions, "cross", built)
    monkeypatch.setattr(runner, "scene_conditions", built)
    size = study_size(config, 2)
    assert (size.conditions, size.tasks, size.captures, size.outputs) == (1_000_001, 6_000_006, 12_000_012,
                                                                          24_000_024)


def test_config_workers_are_capped_at_the_cores_unless_the_command_insists(monkeypatch):
    from cfa_mitsuba.study.executors import _cpu_count
    from cfa_mitsuba.study.sizing import resolve_workers

    said = []
    assert resolve_workers(None, 1000, said.append) == _cpu_count()
    assert len(said) == 1 and "capped" in said[0] and "--workers 1000" in said[0]
    said.clear()
    assert resolve_workers(1000, 1, said.append) == 1000 and not said
    monkeypatch.delenv("CFA_MITSUBA_WORKERS", raising=False)  # the suite's own default (tests/conftest.py)
    assert resolve_workers(None, None, said.append) == min(2, _cpu_count()) and not said


def test_the_memory_check_covers_every_worker(tmp_path):
    config = tmp_path / "small.toml"
    config.write_text(SMALL)
    proc = _study(config, tmp_path / "out", "--workers", 1000)
    lines = [line for line in proc.stderr.splitlines() if line.strip()]
    assert proc.returncode == 2 and len(lines) == 1, proc.stderr
    assert "1000 worker(s) need more than" in lines[0] and "fewer --workers" in lines[0]
    assert not (tmp_path / "out").exists()


def test_result_rows_are_counted_as_the_study_writes_them(small):
    from cfa_mitsuba.study.config import load_config
    from cfa_mitsuba.study.sizing import study_size

    config, out = small
    size = study_size(load_config(config), 2)
    written = len(pd.read_csv(out / "metrics_realisations.csv"))
    # macbeth: 6 CFAs x 2 seeds x 2 demosaics x (delta-e and the two values read from its details)
    assert size.rows == written == 72
    assert size.rows_bytes > 0 and size.peak_bytes > size.rows_bytes


def test_rows_that_cannot_fit_are_refused_even_with_force(tmp_path, monkeypatch):
    """A study of many realisations on a small chart: inside the time limit,
    but its result rows alone outgrow the memory (here 10,000 seeds: 360,000
    rows, 1.5 GB, against a 1 GB limit that the render fits); --force does
    not lift it."""
    config = tmp_path / "small.toml"
    config.write_text(SMALL.replace("seeds = 2", "seeds = 10000"))
    env = {**os.environ, "CFA_MITSUBA_MEMORY_LIMIT": "1G"}
    proc = subprocess.run(_cmd(config, tmp_path / "out", "--force"), cwd=REPO, capture_output=True, text=True,
                          env=env, timeout=60)
    lines = [line for line in proc.stderr.splitlines() if line.strip()]
    assert proc.returncode == 2 and len(lines) == 1 and "Traceback" not in proc.stderr, proc.stderr
    assert "its 360,000 result rows alone need about 1.47 GB" in lines[0] and "--force does not lift" in lines[0]
    assert "h limit" not in lines[0] and not (tmp_path / "out").exists()


DESIGN_CASES = {
    "population": ('engine = "exhaustive"', 'engine = "nsga2"\npopulation = 100000000', "lower search.population"),
    "max_exhaustive": ('engine = "exhaustive"', "max_exhaustive = 1000000000000", "8.47e+11 raw layouts"),
    "generations": ('engine = "exhaustive"', 'engine = "nsga2"\ngenerations = 1000000000', "24 h limit"),
}


@pytest.mark.parametrize("case", list(DESIGN_CASES))
def test_runaway_designs_are_refused_with_the_estimate(tmp_path, case):
    old, new, needle = DESIGN_CASES[case]
    text = (REPO / "configs" / "design-quick.toml").read_text().replace(old, new)
    if case == "max_exhaustive":
        text = text.replace('tiles = ["2x2", "2x3", "3x2", "3x3", "2x4", "4x2"]', 'tiles = ["5x5"]')
    config = tmp_path / f"{case}.toml"
    config.write_text(text)
    out = tmp_path / "out"
    proc = subprocess.run([sys.executable, "-m", "cfa_mitsuba", "design", str(config), "--out", str(out), "--quiet"],
                          cwd=REPO, capture_output=True, text=True, timeout=600)  # a hang guard only
    lines = [line for line in proc.stderr.splitlines() if line.strip()]
    assert proc.returncode == 2 and len(lines) == 1 and "Traceback" not in proc.stderr, proc.stderr
    assert f"{case}.toml" in lines[0] and "candidate evaluation(s)" in lines[0] and needle in lines[0]
    assert "peak memory about" in lines[0] and re.search(r"about [\d.,]+ (h|days)", lines[0])
    assert not out.exists()


# ------------------------------------------------------------------ item 10: checked before any work

LATE = {
    "version": ('\n[metrics.delta-e]\nversion = "1999"\n', "metrics.delta-e", "unknown dE version '1999'"),
    "matrix": ('\n[metrics.scielab]\nmatrix = "xyz3"\n', "metrics.scielab", "unknown value 'xyz3'"),
    "luminance": (None, "luminances[0]", "at most 1e+10 cd/m^2"),
    "sweep_luminance": ('\n[[sweep]]\nscene = "macbeth"\nluminance = [10, 1e300]\n', "sweep[0].luminance[1]",
                        "got 1e+300"),
    "seeds": (None, "seeds", "at least 2 noise realisations"),
}


@pytest.mark.parametrize("case", list(LATE))
def test_values_are_checked_with_the_config_and_nothing_is_written(tmp_path, case):
    extra, key, needle = LATE[case]
    text = SMALL + (extra or "")
    if case == "luminance":
        text = text.replace("luminances = [100]", "luminances = [1e308]")
    if case == "seeds":
        text = text.replace("seeds = 2", "seeds = 1")
    config = tmp_path / f"{case}.toml"
    config.write_text(text)
    out = tmp_path / "out"
    proc = _study(config, out, timeout=120)
    lines = [line for line in proc.stderr.splitlines() if line.strip()]
    assert proc.returncode == 2 and len(lines) == 1 and "Traceback" not in proc.stderr, proc.stderr
    assert f"{case}.toml: {key}:" in lines[0] and needle in lines[0], lines[0]
    assert not out.exists()  # no config.json, no .work


def test_good_metric_options_and_noiseless_single_realisations_pass():
    import tomllib

    from cfa_mitsuba.study.config import parse_config

    text = SMALL.replace("seeds = 2", "seeds = 1") + '[sensor]\nnoise = "off"\n[metrics.delta-e]\nversion = "1976"\n' \
        '[metrics.scielab]\nmatrix = "xyz10"\n[[sweep]]\nscene = "macbeth"\nluminance = [1e9]\n'
    config = parse_config(tomllib.loads(text), where="ok.toml")
    assert config.seeds == 1 and config.metric_options["delta-e"] == {"version": "1976"}


def test_an_unparseable_exr_illuminant_is_called_unparseable(tmp_path):
    import OpenEXR
    import numpy as np

    from cfa_mitsuba import spectra
    from cfa_mitsuba.io import read_spectral_exr
    from cfa_mitsuba.io.exr import spectral_channel_name

    channels = {spectral_channel_name(w): np.full((4, 5), 0.01, np.float32) for w in spectra.DEFAULT_WAVELENGTHS}
    notes = {}
    for name, attribute in (("garbled", "300nm:0.1;garbage"), ("plain", None)):
        header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage,
                  "spectralLayoutVersion": "1.0", "emissiveUnits": "W.m^-2.sr^-1.nm^-1"}
        if attribute:
            header["illuminant"] = attribute
        with OpenEXR.File(header, channels) as f:
            f.write(str(tmp_path / f"{name}.exr"))
        with pytest.warns(UserWarning):
            notes[name] = " ".join(read_spectral_exr(tmp_path / f"{name}.exr").meta["read_notices"])
    assert "'illuminant' attribute" in notes["garbled"] and "unparseable" in notes["garbled"]
    assert "names none" not in notes["garbled"]
    assert "the file names none" in notes["plain"]


def test_force_starts_what_the_limits_refuse(monkeypatch):
    import tomllib

    from cfa_mitsuba.errors import CfaMitsubaError
    from cfa_mitsuba.study.config import parse_config
    from cfa_mitsuba.study.sizing import check_study_size

    # over the time limit with result rows that fit (1.44 M rows, 5.9 GB, on 1.3-megapixel renders; on the small
    # renders a study this long has more rows than a machine holds, which --force does not lift)
    text = (SMALL.replace("seeds = 2", "seeds = 40000").replace("width = 120", "width = 1200")
            .replace("height = 106", "height = 1060"))
    config = parse_config(tomllib.loads(text), where="big.toml")
    monkeypatch.setenv("CFA_MITSUBA_MEMORY_LIMIT", "16G")
    with pytest.raises(CfaMitsubaError, match="24 h limit") as refused:
        check_study_size(config, 2)
    assert "result rows" not in str(refused.value) and "--force to run it anyway" in str(refused.value)
    said = []
    size = check_study_size(config, 2, force=True, log=said.append)
    assert size.captures == 240_000 and size.rows == 1_440_000 and len(said) == 1 and said[0].endswith("(--force)")
    monkeypatch.setenv("CFA_MITSUBA_MEMORY_LIMIT", "4G")  # less than the rows need: --force does not help
    with pytest.raises(CfaMitsubaError, match="--force does not lift a memory limit"):
        check_study_size(config, 2, force=True)


def test_a_sweep_listing_a_million_values_is_refused_before_parsing(tmp_path, monkeypatch):
    import tomllib

    from cfa_mitsuba.errors import CfaMitsubaError
    from cfa_mitsuba.study.config import load_config

    config = tmp_path / "long.toml"
    config.write_text(SMALL + '\n[[sweep]]\nscene = "macbeth"\nseed = [' + ", ".join(map(str, range(10**6))) + "]\n")

    def parsed(*args, **kwargs):  # parsing it alone took 7 s: the size check must come first
        raise AssertionError("the config was parsed before its size was checked")

    monkeypatch.setattr(tomllib, "loads", parsed)
    monkeypatch.setattr(tomllib, "load", parsed)
    with pytest.raises(CfaMitsubaError, match=r"long.toml: 7,\d{3},\d{3} bytes, more than a config file holds"):
        load_config(config)
