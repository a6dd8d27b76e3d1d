"""cfa-mitsuba design end to end, at small size: the 2x2 RGB layouts
against a brute-force full chain of every one of them, the Pareto front
against the named CFAs, the emitted TOMLs through ``cfa-mitsuba study``,
resumption after an interruption, and NSGA-II with parametric spectra."""

import json
import textwrap
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from conftest import run_cli

pytestmark = pytest.mark.slow

STUDY = """
[study]
scenes = ["macbeth", "slanted-edge"]
cfas = ["bayer", "rgb2"]
demosaics = ["bilinear"]
seeds = 3
[study.render.macbeth]
width = 120
height = 106
[study.render.slanted-edge]
width = 320
height = 288
[study.output]
figures = ["png"]
thumbnails = false
"""

BRUTE = """
name = "t22"
seed = 3
[layout]
tiles = ["2x2"]
alphabet = ["R", "G", "B"]
spectra_set = "isetcam-rgb"
[search]
full_chain = 9            # every 2x2 layout: the brute force
agreement_sample = 0
[[objective]]
metric = "mtf"
scene = "slanted-edge"
[[objective]]
metric = "delta-e"
scene = "macbeth"
[[constraint]]
metric = "delta-e"
max = 6.0
""" + STUDY


@pytest.fixture(scope="module")
def brute(tmp_path_factory):
    d = tmp_path_factory.mktemp("design22")
    cfg = d / "d.toml"
    cfg.write_text(textwrap.dedent(BRUTE))
    proc = run_cli("design", cfg, "--out", d / "out", "--quiet", "--workers", "2")
    assert proc.returncode == 0, proc.stderr
    return d, proc


def test_every_2x2_layout_went_through_the_full_chain(brute):
    d, _ = brute
    cands = pd.read_csv(d / "out" / "candidates.csv")
    table = pd.read_csv(d / "out" / "fullchain.csv")
    assert len(cands) == 9 and (cands["chosen"] == "best").all()
    assert set(table.loc[table["kind"] == "candidate", "key"]) == set(cands["key"])
    assert (table.loc[table["kind"] == "candidate", "mtf@slanted-edge/L100/bilinear n"] == 3).all()


def test_the_full_chain_best_is_in_the_proxys_top_5(brute):
    d, _ = brute
    table = pd.read_csv(d / "out" / "fullchain.csv")
    cand = table[table["kind"] == "candidate"]
    best = cand.loc[cand["score"].idxmax()]
    assert best["proxy_rank"] <= 5, cand[["tile_text", "proxy_rank", "score"]]
    agree = json.loads((d / "out" / "agreement.json").read_text())
    assert agree["n"] == 9 and agree["per_objective"]["mtf@slanted-edge/L100/bilinear"] > 0.5


def _dominated(a, b, objectives):
    """a dominates b within intervals (an independent reading of the rule)."""
    strictly = False
    for label, goal in objectives:
        lo_a, hi_a, lo_b, hi_b = a[f"{label} low"], a[f"{label} high"], b[f"{label} low"], b[f"{label} high"]
        a_better = hi_a < lo_b if goal == "min" else lo_a > hi_b
        a_worse = lo_a > hi_b if goal == "min" else hi_a < lo_b
        if a_worse:
            return False
        strictly |= a_better
    return strictly


def test_no_pareto_candidate_is_dominated_by_a_named_cfa(brute):
    d, _ = brute
    table = pd.read_csv(d / "out" / "fullchain.csv")
    pareto = pd.read_csv(d / "out" / "pareto.csv")
    objectives = [("mtf@slanted-edge/L100/bilinear", "max"), ("delta-e@macbeth/L100/bilinear", "min")]
    named = table[table["kind"] == "named"]
    assert len(pareto) >= 1 and set(named["cfa"]) == {"bayer", "rgb2"}
    for _, p in pareto.iterrows():
        for _, n in named.iterrows():
            assert not _dominated(n, p, objectives), (n["cfa"], p["cfa"])
        assert p["delta-e@macbeth/L100/bilinear"] <= 6.0  # the constraint
    # and every dominated candidate names a CFA that does dominate it
    for _, r in table[table["dominated_by"].notna()].iterrows():
        assert _dominated(table[table["cfa"] == r["dominated_by"]].iloc[0], r, objectives)


def test_the_emitted_tomls_reproduce_the_values_in_cfa_mitsuba_study(brute, tmp_path):
    d, _ = brute
    pareto = pd.read_csv(d / "out" / "pareto.csv")
    row = pareto.iloc[0]
    study = textwrap.dedent(STUDY).replace("[study]\n", "").replace("[study.", "[")
    study = study.replace('cfas = ["bayer", "rgb2"]', f'cfas = [{json.dumps(str((d / "out" / row["toml"]).resolve()))}]')
    cfg = tmp_path / "s.toml"
    cfg.write_text('name = "repro"\nseed = 3\nluminances = [100]\n' + study)
    proc = run_cli("study", cfg, "--out", tmp_path / "s", "--quiet", "--no-report", "--workers", "1")
    assert proc.returncode == 0, proc.stderr
    m = pd.read_csv(tmp_path / "s" / "metrics.csv")
    for metric, scene in (("mtf", "slanted-edge"), ("delta-e", "macbeth")):
        label = f"{metric}@{scene}/L100/bilinear"
        got = m[(m["metric"] == metric) & (m["scene"] == scene)].iloc[0]
        assert row[f"{label} low"] - 1e-9 <= got["value"] <= row[f"{label} high"] + 1e-9, (label, got["value"])
        assert got["value"] == pytest.approx(row[label], rel=1e-7)  # same TOML path: the same noise seeds (csv: 8 digits)


def test_results_record_paths_relative_to_their_output_folder(brute):
    from cfa_mitsuba.io.portable import ABSOLUTE_PATH

    d, _ = brute
    out = d / "out"
    for name in ("fullchain.csv", "pareto.csv", "candidates.csv", "agreement.json", "study/config.json"):
        text = (out / name).read_text()
        assert not ABSOLUTE_PATH.search(text), (name, ABSOLUTE_PATH.search(text).group(0))
    for toml in pd.read_csv(out / "fullchain.csv")["toml"].dropna():
        assert (out / toml).is_file(), toml


def test_a_rerun_evaluates_nothing_again(brute):
    d, first = brute
    proc = run_cli("design", d / "d.toml", "--out", d / "out", "--workers", "1")  # not --quiet: its log counts
    assert proc.returncode == 0, proc.stderr
    assert "(0 evaluated now, 9 taken from saved state)" in proc.stderr
    assert "22 evaluation task(s), 22 already done" in proc.stderr  # 11 CFAs x 2 scenes, all saved
    assert (d / "out" / "design.html").stat().st_size > 1000


def test_an_interrupted_exhaustive_search_resumes(tmp_path, monkeypatch):
    from cfa_mitsuba.design import layouts, proxy, search
    from cfa_mitsuba.design.config import parse_design
    import tomllib

    cfg = parse_design(tomllib.loads(textwrap.dedent(BRUTE).replace('["2x2"]', '["3x3"]')))
    monkeypatch.setattr(layouts, "CHUNK", 2048)  # 3^9 = 19683 codes: 10 chunks
    calls = {"n": 0}
    real = proxy.evaluate_layouts

    def dying(*args, **kwargs):
        calls["n"] += 1
        if calls["n"] == 4:
            raise KeyboardInterrupt
        return real(*args, **kwargs)

    monkeypatch.setattr(search.P, "evaluate_layouts", dying)
    with pytest.raises(KeyboardInterrupt):
        search.run_search(cfg, tmp_path, log=lambda m: None)
    saved = sorted((tmp_path / ".design").glob("exhaustive-3x3-*.npz"))
    assert 1 <= len(saved) < 10
    monkeypatch.setattr(search.P, "evaluate_layouts", real)
    resumed = search.run_search(cfg, tmp_path, log=lambda m: None)
    fresh = search.run_search(cfg, tmp_path / "fresh", log=lambda m: None)
    assert resumed.reused > 0 and resumed.evaluated == len(resumed.candidates) - resumed.reused
    pd.testing.assert_frame_equal(resumed.candidates, fresh.candidates)


def test_nsga2_with_bandpass_spectra_is_seeded_resumable_and_emits_loadable_tomls(tmp_path):
    import tomllib

    from cfa_mitsuba.design import search
    from cfa_mitsuba.design.config import parse_design
    from cfa_mitsuba.design.fullchain import candidate_name, write_cfa_toml
    from cfa_mitsuba.sensor import get_cfa

    text = textwrap.dedent(BRUTE).replace('[search]\n', '[search]\nengine = "nsga2"\npopulation = 8\ngenerations = 3\n')
    text = text.replace('spectra_set = "isetcam-rgb"\n', 'spectra_set = "isetcam-rgb"\n[spectra]\nfamily = "bandpass"\n'
                        'letters = ["R", "B"]\ncentre_nm = [420, 680]\nwidth_nm = [40, 160]\npeak = [0.3, 0.9]\n')
    cfg = parse_design(tomllib.loads(text))
    a = search.run_search(cfg, tmp_path / "a", log=lambda m: None)
    assert a.evaluated > 0 and a.candidates["colour"].nunique() > 1  # the spectra vary the colour proxy
    b = search.run_search(cfg, tmp_path / "a", log=lambda m: None)
    assert b.evaluated == 0 and b.reused > 0
    c = search.run_search(cfg, tmp_path / "c", log=lambda m: None)  # same seed, fresh: the same candidates
    assert set(c.candidates["key"]) == set(a.candidates["key"])
    row = a.candidates.sort_values("colour").iloc[0]
    name = candidate_name(cfg.name, row["key"])
    cfa = get_cfa(str(write_cfa_toml(tmp_path / f"{name}.toml", name, row, cfg)))
    params = json.loads(row["params"])
    assert cfa.name == name and cfa.tile_shape == (2, 2)
    r = cfa.sensitivities()[cfa.channels.index("R")]
    wl = np.arange(400.0, 701.0, 10.0)
    assert abs(wl[int(np.argmax(r))] - params[0]["centre_nm"]) < 40  # the R dye peaks near its centre
