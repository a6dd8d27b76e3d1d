"""Bilinear demosaicing (isp/bilinear.py) against colour-demosaicing 0.2.7's
``demosaicing_CFA_Bayer_bilinear`` on every Bayer phase (the generic checks
of every CFA are tests/isp/test_demosaic.py's)."""

from __future__ import annotations

import numpy as np
import pytest

import cfa_mitsuba as cm
from bayer_phases import PHASES, bayer, cdm


@pytest.mark.parametrize("pattern", PHASES)
@pytest.mark.parametrize("shape", [(17, 22), (32, 41)])
def test_bilinear_equals_colour_demosaicing(pattern, shape):
    raw = np.random.default_rng(1).random(shape)
    ours = cm.isp.demosaic(raw, bayer(pattern), "bilinear")
    theirs = cdm.demosaicing_CFA_Bayer_bilinear(raw, pattern)
    assert np.abs(ours - theirs)[1:-1, 1:-1].max() <= 1e-12
