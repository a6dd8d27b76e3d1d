"""A known answer found again (issue 26): among all 2x2 RGB layouts on the
same filters, Bayer (up to translation and mirrors) is on the Pareto front
of {MTF50, dE00, YSNR at 10 cd/m^2} under the exposure program, every 2x2
layout run through the full chain (a brute force, not the proxy's guess).

Measured (6 noise realisations, ISETCam's RGB filters, bilinear): two
layouts tie Bayer within a few per cent and sometimes dominate it within
the intervals, depending on the realisations: G G / B R (G in full rows:
as sharp across the near-vertical edge, which sees only horizontal
frequencies; a horizontal edge would see its gaps) and R B / G R (R in
Bayer's G sites), both 2-3 % above Bayer's YSNR.  So the test asks what
holds every time: Bayer is on the front, or whatever dominates it is
better by less than 5 % on every objective (Bayer on the front within the
noise of the measurement), and most layouts are dominated."""

import textwrap

import numpy as np
import pandas as pd
import pytest

from conftest import run_cli

pytestmark = pytest.mark.slow

CONFIG = """
name = "rediscovery"
seed = 5
layout = { tiles = ["2x2"], alphabet = ["R", "G", "B"], spectra_set = "isetcam-rgb" }
search = { full_chain = 9, agreement_sample = 0 }    # every distinct 2x2 layout through the full chain
[[objective]]
metric = "mtf"
scene = "slanted-edge"
luminance = 100
[[objective]]
metric = "delta-e"
scene = "macbeth"
luminance = 100
[[objective]]
metric = "ysnr"
scene = "gray-bar"
luminance = 10
[study]
scenes = ["macbeth", "slanted-edge", "gray-bar"]
cfas = ["bayer"]
demosaics = ["bilinear"]
seeds = 6                 # narrow intervals: dominance within intervals needs them
[study.sensor]
exposure_policy = "program"
[study.output]
figures = ["png"]
thumbnails = false
""" + "".join(f"[study.render.{scene}]\nwidth = {w}\nheight = {h}\n"
              for scene, (w, h) in {"macbeth": (120, 106), "slanted-edge": (320, 288), "gray-bar": (250, 120)}.items())


def _is_bayer(tile_text: str) -> bool:
    """A 2x2 tile with G on one diagonal and R, B on the other: Bayer up to
    translation and mirrors (an independent reading of the layout)."""
    g = np.array([[c == "G" for c in row.split()] for row in tile_text.split("/")])
    other = sorted(c for row in tile_text.split("/") for c in row.split() if c != "G")
    return g.shape == (2, 2) and other == ["B", "R"] and (g.trace() == 2 or np.fliplr(g).trace() == 2)


def test_bayer_is_on_the_front_of_all_2x2_rgb_layouts(tmp_path):
    cfg = tmp_path / "d.toml"
    cfg.write_text(textwrap.dedent(CONFIG))
    proc = run_cli("design", cfg, "--out", tmp_path / "out", "--quiet", "--workers", "2")
    assert proc.returncode == 0, proc.stderr
    table = pd.read_csv(tmp_path / "out" / "fullchain.csv")
    cand = table[table["kind"] == "candidate"]
    assert len(cand) == 9  # the 2x2 tiles with all three letters, translations and mirrors folded
    bayer = cand[cand["tile_text"].map(_is_bayer)]
    assert len(bayer) == 1, cand["tile_text"].tolist()
    row = bayer.iloc[0]
    labels = [c for c in table.columns if c.endswith("/bilinear")]
    if not bool(row["pareto"]):
        better = table[table["cfa"] == row["dominated_by"]].iloc[0]
        gap = {c: abs(better[c] / row[c] - 1) for c in labels}
        assert max(gap.values()) < 0.05, (better["tile_text"], gap)
    # and the front is not everyone: most layouts are dominated
    assert int(cand["pareto"].sum()) <= 4, cand[["tile_text", "pareto"]]
    # the candidate is the named Bayer seen through other noise realisations: equal within the intervals
    named = table[table["cfa"] == "bayer"].iloc[0]
    for col in labels:
        assert row[f"{col} low"] <= named[f"{col} high"] and named[f"{col} low"] <= row[f"{col} high"], col
