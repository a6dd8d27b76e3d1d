"""Parity results in dB are compared and printed in dB, with the case's
tolerance (issue 50): a percentage of a logarithm means nothing."""

from __future__ import annotations

import pytest

from cfa_mitsuba.study.parity import describe_difference, run_case


def _result(unit, value, expected, tolerance):
    return {"unit": unit, "value": value, "expected": expected, "tolerance": tolerance,
            "relative_difference": (value - expected) / abs(expected)}


def test_db_in_db_and_others_in_percent():
    assert describe_difference(_result("dB", 21.128, 21.03, 0.001)) == ("+0.098 dB", "±0.021 dB")
    assert describe_difference(_result("dB", -20.045, -20.0432, 0.03)) == ("-0.002 dB", "±0.601 dB")
    assert describe_difference(_result("cy/mm", 74.4, 74.2, 0.03)) == ("+0.27 %", "±3 %")


def test_a_snr_case_reports_its_allowance_in_db(tmp_path):
    """The allowance run_case applies (tolerance x |expected|) is what it reports, in the result's unit."""
    from cfa_mitsuba.study.parity import load_case
    from conftest import REPO

    case = load_case(REPO / "tests" / "parity" / "isetcam" / "pixel-snr-10um.toml")
    r = run_case(case)
    assert r["unit"] == "dB" and r["tolerance_abs"] == pytest.approx(case.tolerance * abs(case.expected))
    assert r["difference"] == pytest.approx(r["value"] - r["expected"])
    assert (abs(r["difference"]) <= r["tolerance_abs"]) == (r["verdict"] == "agrees")
