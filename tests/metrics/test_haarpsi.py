"""HaarPSI (metrics/haarpsi.py) against its authors' MATLAB code (HaarPSI.m), in
colour and grey, on the colour pairs of tests/data/reference/; symmetric."""

from __future__ import annotations

import pytest

import cfa_mitsuba.metrics as cm
from cfa_mitsuba.metrics import colourspace as mc
from reference_data import COLOUR_PAIRS, entries, colour_pair


@pytest.mark.parametrize("pid", COLOUR_PAIRS)
def test_haarpsi_matches_haarpsi_m(pid):
    ref, dist = colour_pair(pid)
    for e in entries("colour_pairs", pid, "haarpsi", oracle="HaarPSI.m"):
        if e["variant"] == "rgb":
            got = cm.haarpsi(ref, dist)
        else:
            got = cm.haarpsi(mc.rgb_to_gray(ref), mc.rgb_to_gray(dist))
        assert abs(got - e["value"]) <= 1e-6, (e["variant"], got, e["value"])
        assert abs(cm.haarpsi(dist, ref) - cm.haarpsi(ref, dist)) < 1e-12
