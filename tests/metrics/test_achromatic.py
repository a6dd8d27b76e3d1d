"""The achromatic reproduction error (metrics/achromatic.py): the mean |dL*| over
the gray bar's steps, without the steps' borders."""

from __future__ import annotations

import numpy as np
import pytest

import cfa_mitsuba.metrics as cm
from lab_images import WHITE, lab_image_to_xyz


def test_achromatic_is_mean_abs_dl_without_the_border():
    h, w = 21, 120
    lstar = np.repeat(np.linspace(95, 20, 6), 20)[None, :].repeat(h, 0)
    lab = np.stack([lstar, np.zeros_like(lstar), np.zeros_like(lstar)], -1)
    ideal = lab_image_to_xyz(lab)
    lab2 = lab.copy()
    lab2[..., 0] += np.where(np.arange(w) % 2 == 0, 1.0, -1.0)[None, :]
    lab2[:, :10, 0] += 30.0  # ruined border: excluded
    r = cm.achromatic(ideal, lab_image_to_xyz(lab2), WHITE, steps=[(i * 20, i * 20 + 20) for i in range(6)])
    assert float(r) == pytest.approx(1.0, abs=1e-9) and r.unit == "L*"
    assert r.details["per_step"][1] == pytest.approx(1.0, abs=1e-9)
    assert r.details["l_reference"][50] == pytest.approx(lstar[0, 50])
