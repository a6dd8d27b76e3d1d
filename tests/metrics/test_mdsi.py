"""MDSI (metrics/mdsi.py) against its authors' MATLAB code (MDSI.m), the reference
first, on the colour pairs of tests/data/reference/."""

from __future__ import annotations

import pytest

import cfa_mitsuba.metrics as cm
from reference_data import COLOUR_PAIRS, entries, colour_pair


@pytest.mark.parametrize("pid", COLOUR_PAIRS)
def test_mdsi_matches_mdsi_m_with_reference_first(pid):
    ref, dist = colour_pair(pid)
    for e in entries("colour_pairs", pid, "mdsi", oracle="MDSI.m"):
        comb, *trap = e["variant"].split("|")
        got = cm.mdsi(dist, ref, combination=comb) if trap else cm.mdsi(ref, dist, combination=comb)
        assert abs(got - e["value"]) <= 1e-6, (e["variant"], got, e["value"])
