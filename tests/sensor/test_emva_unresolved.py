"""A non-uniformity emva1288 cannot resolve (its variance estimate, less
the temporal noise's share, is negative: NaN from the package) is never a
silent NaN (issue 50): the CSV cell is empty and says why, the command
prints '< noise' with the reason."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from cfa_mitsuba.sensor.emva import ChannelSeries
from cfa_mitsuba.sensor.emva_analysis import UNRESOLVED, parameter_rows


class _Results:
    """The part of emva1288's Results1288 that parameter_rows reads."""

    results_by_section = {"spatial": {"DSNU1288": {"value": math.nan, "unit": "$e^-$", "short": "DSNU"},
                                      "PRNU1288": {"value": 0.8, "unit": "\\\\%", "short": "PRNU"}}}


def _series():
    expected = {"DSNU1288": 0.0, "PRNU1288": 1.0, "clip_e": 6000.0, "analog_gain": 1.0, "dsnu_nominal_e": 0.0,
                "prnu_nominal_percent": 1.0}
    return ChannelSeries("G", Path("."), 540.0, 14, np.zeros(1), np.zeros(1), expected)


def test_nan_becomes_an_empty_cell_with_its_reason():
    rows = {r["parameter"]: r for r in parameter_rows(_series(), _Results())}
    dsnu = rows["DSNU1288"]
    assert dsnu["measured"] == "" and UNRESOLVED in dsnu["description"] and dsnu["relative_error"] == ""
    assert rows["PRNU1288"]["measured"] == 0.8 and rows["PRNU1288"]["relative_error"] == pytest.approx(-0.2)
    assert not any(isinstance(r["measured"], float) and math.isnan(r["measured"]) for r in rows.values())
