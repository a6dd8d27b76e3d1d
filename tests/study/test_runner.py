"""End to end: the quick study (the CI end-to-end test), interruption and
resumption, and the same study on a real Dask cluster on loopback.

The three share one uninterrupted local run of configs/quick.toml (module
fixture); the renders it makes are reused from the session's render cache by
the others, so every later run differs only in how the evaluation work is
scheduled or interrupted, and must give the same numbers.
"""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import time
import tomllib
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import tiny_study
from conftest import REPO
from dask_cluster import dask_cluster  # noqa: F401 (the suite's one Dask cluster fixture)

QUICK = REPO / "configs" / "quick.toml"
QUICK_DEMOSAICS = tuple(tomllib.loads(QUICK.read_text())["demosaics"])
KEYS = ["scene", "cfa", "demosaic", "luminance", "metric"]


def study(*args, quiet: bool = True, **popen):
    cmd = [sys.executable, "-m", "cfa_mitsuba", "study", str(QUICK), *(["--quiet"] if quiet else []), *map(str, args)]
    if popen:
        return subprocess.Popen(cmd, cwd=REPO, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, **popen)
    return subprocess.run(cmd, cwd=REPO, capture_output=True, text=True)


@pytest.fixture(scope="module")
def quick(tmp_path_factory):
    out = tmp_path_factory.mktemp("quick")
    proc = study("--out", out)
    assert proc.returncode == 0, proc.stderr
    return out, proc


def test_quick_study_writes_everything(quick):
    out, proc = quick
    for name in ("metrics.csv", "scores.csv", "report.html", "timing.json", "config.json"):
        assert (out / name).is_file(), name
    assert any((out / "figures").glob("*.png")) and any((out / "figures").glob("*.svg"))
    metrics = pd.read_csv(out / "metrics.csv")
    headline = set(metrics["metric"])
    from cfa_mitsuba.metrics import scored_metrics

    assert set(scored_metrics()) <= headline  # the paper's eight, every one
    assert np.isfinite(metrics["value"]).all()
    assert not (out / "failures.csv").exists()


def test_quick_study_matches_stored_values(quick):
    """Every value of the first noise realisation within its stored tolerance
    (4 sigma of the render noise, tests/data/make_quick_expected.py says how
    it was measured); metrics.csv's means are checked against it below."""
    out, _ = quick
    every = pd.read_csv(out / "metrics_realisations.csv")
    got = every[every["realisation"] == 0]
    exp = pd.read_csv(REPO / "tests" / "data" / "quick_expected.csv", comment="#")
    merged = exp.merge(got, on=KEYS, how="outer", suffixes=("_exp", "_got"), indicator=True)
    # a metric added since the values were stored has rows with nothing stored (make_quick_expected.py stores
    # them); every other row must be in both
    new_metric = ~merged["metric"].isin(set(exp["metric"])) & (merged["_merge"] == "right_only")
    missing = merged[(merged["_merge"] != "both") & ~new_metric]
    assert missing.empty, f"rows differ from the stored set:\n{missing[KEYS + ['_merge']]}"
    merged = merged[merged["_merge"] == "both"]
    dev = (merged["value_got"] - merged["value_exp"]).abs()
    bad = merged[dev > merged["tolerance"]]
    assert bad.empty, "values outside tolerance:\n" + bad[KEYS + ["value_exp", "value_got", "tolerance"]].to_string()


def test_quick_study_means_and_intervals(quick):
    """metrics.csv: the mean of the realisations with its 95 % t interval."""
    from scipy.stats import t

    out, _ = quick
    every = pd.read_csv(out / "metrics_realisations.csv")
    means = pd.read_csv(out / "metrics.csv")
    assert {"value", "ci_low", "ci_high", "n"} <= set(means.columns)
    assert (means["n"] == 3).all()
    # a value with bounds among its realisations is their Kaplan-Meier median (study/censored.py; tests/study)
    means = means[means["censored_count"] == 0]
    g = every.merge(means[KEYS], on=KEYS).groupby(KEYS)["value"]
    check = means.set_index(KEYS)
    m, sd = g.mean(), g.std(ddof=1)
    assert np.allclose(check.loc[m.index, "value"], m, rtol=1e-9)
    half = t.ppf(0.975, 2) * sd / np.sqrt(3)
    # metrics.csv holds 10 significant digits: ci_high - value carries up to ~1e-10 of rounding, which is more
    # than rtol 1e-6 of a narrow interval (puppy rgb4/pocs MDSI: half-width 2.3e-5, rounding 2.8e-11)
    assert np.allclose(check.loc[m.index, "ci_high"] - check.loc[m.index, "value"], half, rtol=1e-6, atol=1e-9)
    assert (means["ci_low"] <= means["value"]).all() and (means["value"] <= means["ci_high"]).all()
    scores = pd.read_csv(out / "scores.csv")
    for col in ("total_rank_best", "total_rank_worst", "demosaic_rank_best", "mean_score_ci_low"):
        assert col in scores.columns
    assert (scores["total_rank_best"] <= scores["total_rank"]).all()
    assert (scores["total_rank"] <= scores["total_rank_worst"]).all()


def test_every_scored_metric_tells_the_cfas_apart(quick):
    """Under the default range policy every scored metric's normalised score
    varies across the CFAs for every demosaic (issue 12: no metric constant,
    none silently scored as a tie), and the policies' clipping table is written."""
    out, _ = quick
    scores = pd.read_csv(out / "scores.csv")
    from cfa_mitsuba.metrics import scored_metrics

    n_scored = len(scored_metrics())
    distinct = scores.groupby(["demosaic", "metric"])["score"].agg(lambda v: v.round(9).nunique())
    assert len(distinct) == len(set(scores["demosaic"])) * n_scored and set(scores["demosaic"]) == set(QUICK_DEMOSAICS)
    assert (distinct >= 2).all(), distinct[distinct < 2]
    policies = pd.read_csv(out / "policies.csv")
    clip = policies[policies["scope"] == "clipping"]
    assert set(clip["policy"]) == {"paper", "study", "ideal"} and len(clip) == 3 * n_scored


def test_moire_bounds_are_censored(quick):
    """No MSP at the chirp's top analysed frequency is stored as a
    measurement: every such value is marked censored (a lower bound), and
    every censored value is that top frequency."""
    out, _ = quick
    every = pd.read_csv(out / "metrics_realisations.csv")
    msp = every[every["metric"] == "moire"]
    assert len(msp) and msp["censored"].dtype == bool
    top = msp["value"].max()
    at_top = np.isclose(msp["value"], top, rtol=1e-9)
    assert (msp.loc[at_top, "censored"]).all()
    assert (np.isclose(msp.loc[msp["censored"], "value"], top, rtol=1e-9)).all()
    assert not every.loc[every["metric"] != "moire", "censored"].any()
    means = pd.read_csv(out / "metrics.csv")
    assert means.loc[means["metric"] == "moire", "censored"].any()
    # censored_count: how many realisations are bounds; censored only when all are (study/censored.py)
    keys = ["scene", "cfa", "demosaic", "luminance", "metric"]
    counts = every.groupby(keys)["censored"].sum().rename("count").reset_index()
    both = means.merge(counts, on=keys)
    assert (both["censored_count"] == both["count"]).all()
    assert (both["censored"] == (both["count"] == both["n"])).all()


def test_quick_study_gets_no_worse_with_more_light(quick):
    """Issue 22, acceptance 4: below 100 cd/m^2 no (CFA, demosaic, metric)
    gets worse from one luminance to the next higher by more than its
    interval (the intervals do not overlap); and the study records what
    decided each capture and its SNR against light."""
    import cfa_mitsuba as cm

    out, _ = quick
    m = pd.read_csv(out / "metrics.csv")
    worse, pairs = [], 0
    for (scene, cfa, dem, metric), g in m.groupby(["scene", "cfa", "demosaic", "metric"]):
        rows = g.sort_values("luminance").to_dict("records")
        higher = cm.metrics.METRICS[metric].higher_is_better
        for a, b in zip(rows, rows[1:]):
            if b["luminance"] > 100:
                continue
            pairs += 1
            if (b["ci_high"] < a["ci_low"]) if higher else (b["ci_low"] > a["ci_high"]):
                worse.append(f"{scene} {cfa} {dem} {metric}: {a['value']:.4g} at {a['luminance']:g} -> "
                             f"{b['value']:.4g} at {b['luminance']:g} cd/m^2")
    assert pairs >= 100 and not worse, worse
    for col in ("exposure_s", "analog_gain", "digital_gain", "clipped_fraction"):
        assert m[col].notna().all() and (m[col] >= 0).all(), col
    snr, snr10 = pd.read_csv(out / "snr.csv"), pd.read_csv(out / "snr10.csv")
    assert list(snr.columns[:7]) == ["cfa", "demosaic", "luminance", "ysnr", "ysnr_low", "ysnr_high", "chroma_snr"]
    assert list(snr10.columns[:5]) == ["cfa", "demosaic", "snr10_cd_m2", "ci_low", "ci_high"]
    assert len(snr) == 4 * 4 * 4 and (snr["ysnr_low"] <= snr["ysnr"]).all() and (snr["ysnr"] <= snr["ysnr_high"]).all()
    # every value or a note saying why not; the interval brackets the value
    for r in snr10.itertuples():
        assert (r.ci_low <= r.snr10_cd_m2 <= r.ci_high) if np.isfinite(r.snr10_cd_m2) else isinstance(r.note, str)
    facts = json.loads((out / "cfas.json").read_text())
    assert {f["spectra"] for f in facts.values()} == {"isetcam-rgb", "isetcam-cmy", "isetcam-rgbw"}
    assert "SNR10" in (out / "report.html").read_text()


def _tasks_done(out: Path) -> int:
    return len(list((out / ".work").glob("*.json"))) if (out / ".work").is_dir() else 0


def _wait_for_tasks(out: Path, n: int, proc):
    """Until ``n`` tasks are saved (a study that stops making progress is a hang: pytest-timeout ends it)."""
    while _tasks_done(out) < n:
        assert proc.poll() is None, f"study ended before {n} tasks: {proc.communicate()}"
        time.sleep(0.05)


def test_killed_study_resumes_and_gives_the_same_tables(quick, tmp_path):
    ref, _ = quick
    out = tmp_path / "killed"
    proc = study("--out", out, "--no-report", start_new_session=True)
    _wait_for_tasks(out, 4, proc)
    os.killpg(proc.pid, signal.SIGKILL)  # the study and its worker processes
    proc.communicate()
    finished = _tasks_done(out)
    total = len(pd.read_csv(ref / "metrics.csv").drop_duplicates(["scene", "cfa", "luminance"]))
    assert 4 <= finished < total, (finished, total)
    assert not (out / "metrics.csv").exists()

    again = study("--out", out, "--no-report", quiet=False)  # its log says what was reused
    assert again.returncode == 0, again.stderr
    m = re.search(r"(\d+) task\(s\) run, (\d+) reused", again.stderr)
    assert m and int(m.group(2)) == finished and int(m.group(1)) == total - finished, again.stderr
    assert (out / "metrics.csv").read_bytes() == (ref / "metrics.csv").read_bytes()
    assert (out / "scores.csv").read_bytes() == (ref / "scores.csv").read_bytes()


def test_dask_cluster_gives_identical_results_despite_a_killed_worker(quick, dask_cluster, tmp_path):
    ref, _ = quick
    address, procs = dask_cluster
    out = tmp_path / "dask"
    proc = study("--out", out, "--no-report", "--scheduler", address, start_new_session=True, quiet=False)
    _wait_for_tasks(out, 3, proc)
    os.killpg(procs[1].pid, signal.SIGKILL)  # one worker (its nanny too) dies mid-study
    stdout, stderr = proc.communicate(timeout=600)
    assert proc.returncode == 0, stderr
    assert "Dask cluster" in stderr
    assert (out / "metrics.csv").read_bytes() == (ref / "metrics.csv").read_bytes()
    assert (out / "scores.csv").read_bytes() == (ref / "scores.csv").read_bytes()


def test_decisions_name_exactly_the_cfas_whose_rank_interval_contains_one(quick):
    """decisions.csv (issues 24, 46): the overall row is Table 3's rank intervals plus the practical
    difference, the rule is the same for every decision, each says what it depends on, low light is
    decided on SNR10 and values, the report's cards follow the rows, and policies.csv's totals for the
    study's policy are scores.csv's."""
    import re

    from cfa_mitsuba.study.decisions import COLUMNS, VERDICTS

    out, _ = quick
    d = pd.read_csv(out / "decisions.csv", keep_default_na=False)
    assert list(d.columns) == COLUMNS
    dems = list(dict.fromkeys(pd.read_csv(out / "scores.csv")["demosaic"]))
    assert list(d["aspect"])[:4 + len(dems)] == ["colour", "sharpness", "moire", "overall"] + [f"with {x}" for x in dems]
    assert {"low light", "low light: scielab", "low light: ssim"} <= set(d["aspect"])
    s = pd.read_csv(out / "scores.csv").drop_duplicates("cfa")
    overall = d[d["aspect"] == "overall"].iloc[0]
    can_be_first = set(s[s["total_rank_best"] == 1]["cfa"])
    one = s[(s["total_rank_best"] == 1) & (s["total_rank_worst"] == 1)]
    if len(one) == 1:  # separated: a winner, or equivalent when the lead is below the practical difference
        assert overall["verdict"] in ("winner", "equivalent") and overall["cfas"].split()[0] == one["cfa"].iloc[0]
    else:
        assert overall["verdict"] == "tie" and set(overall["cfas"].split()) == can_be_first
    for r in d.itertuples():
        assert r.verdict in VERDICTS
        assert (r.verdict == "winner") == ("at least the practical difference" in r.detail), r.aspect
        assert str(r.robust) in ("True", "False") and (str(r.robust) == "True") == (r.depends_on == ""), r.aspect
    low = d[d["aspect"] == "low light"].iloc[0]
    assert low["quantity"].startswith("SNR10") and low["verdict"] != "unmeasured"
    # the swept metrics are decided on their values at the lowest luminance below the base one
    cfg = json.loads((out / "config.json").read_text())
    lowest = min(v for sw in cfg["sweeps"] if not sw["metrics"] or {"scielab", "ssim"} & set(sw["metrics"])
                 for v in sw["values"].get("luminance", ()) if v < min(cfg["luminances"]))
    sc = d[d["aspect"] == "low light: scielab"].iloc[0]
    assert float(sc["luminance"]) == lowest and "values" in sc["quantity"]
    # the report's cards name a best CFA only where decisions.csv names a winner
    html = (out / "report.html").read_text()
    named = re.findall(r'<div class="k">Best CFA overall</div><div class="v">(?:<span[^>]*></span>)?([\w-]+)<', html)
    assert named == ([overall["cfas"]] if overall["verdict"] == "winner" else []), named
    pol = pd.read_csv(out / "policies.csv")
    ideal = pol[(pol["scope"] == "rank") & (pol["policy"] == "ideal")].set_index("cfa")
    np.testing.assert_allclose(ideal.loc[s["cfa"], "total_score"].to_numpy(), s["total_score"].to_numpy(), rtol=1e-9)
    assert (ideal.loc[s["cfa"], "total_rank"].to_numpy() == s["total_rank"].to_numpy()).all()


def test_profile_study_after_profiles_the_tables_and_report_on_a_copy(tmp_path, capsys):
    """benchmarks/profile_study.py --after: the work after the evaluation of a
    finished study, by stage and by function, on a copy (the results are not
    touched); a folder that is not a finished run of the config is refused."""
    import importlib.util
    import shutil

    from cfa_mitsuba.cli import main

    spec = importlib.util.spec_from_file_location("profile_study", REPO / "benchmarks" / "profile_study.py")
    prof = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(prof)
    config, out = tmp_path / "tiny.toml", tmp_path / "tiny"
    config.write_text(tiny_study.TINY)  # a study with its report (the quick study's, under cProfile, took 33 s)
    assert main(["study", str(config), "--out", str(out), "--quiet", "--workers", "1"]) == 0
    capsys.readouterr()
    before = {p: p.stat().st_mtime_ns for p in (out / "report.html", out / "metrics.csv", out / "scores.csv")}
    assert prof.main(["--config", str(config), "--after", str(out), "--top", "5"]) == 0
    text = capsys.readouterr().out
    assert re.search(r"tables \(the study resumed: every task reused\)\s+[\d.]+", text)
    assert re.search(r"report \(one process\)\s+[\d.]+", text) and "build_report" in text
    assert {p: p.stat().st_mtime_ns for p in before} == before
    assert prof.main(["--config", str(config), "--after", str(tmp_path / "none")]) == 2  # no .work/
    part = tmp_path / "part"
    shutil.copytree(out / ".work", part / ".work")
    next(iter((part / ".work").glob("*.json"))).unlink()
    assert prof.main(["--config", str(config), "--after", str(part)]) == 2
    assert "1 task(s) of tiny.toml are not finished" in capsys.readouterr().err
