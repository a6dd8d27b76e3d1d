"""snr.csv and snr10.csv from metrics.csv rows (study/snr.py), against
values worked out by hand."""

import math

import numpy as np
import pandas as pd
import pytest

from cfa_mitsuba.study.snr import SNR10_COLUMNS, SNR_COLUMNS, crossing, snr10_table, snr_table


def _rows(cfa, lums, ysnr, half=0.1):
    out = []
    for L, y in zip(lums, ysnr):
        out.append({"scene": "gray-bar", "cfa": cfa, "demosaic": "bilinear", "luminance": L, "metric": "ysnr",
                    "value": y, "ci_low": y * (1 - half), "ci_high": y * (1 + half)})
        out.append({"scene": "gray-bar", "cfa": cfa, "demosaic": "bilinear", "luminance": L, "metric": "chroma_snr",
                    "value": y / 2, "ci_low": y / 2, "ci_high": y / 2})
    return out


def test_snr10_interpolates_log_log_and_its_interval_inverts_the_bounds():
    # YSNR proportional to sqrt(L) (shot-noise limited): 10 at L = 100 exactly, by hand
    lums = [1.0, 10.0, 1000.0]
    m = pd.DataFrame(_rows("a", lums, [math.sqrt(L) for L in lums]) + _rows("b", lums, [50.0, 60.0, 70.0]))
    snr = snr_table(m)
    assert list(snr.columns) == SNR_COLUMNS and len(snr) == 6
    assert snr.loc[0, "chroma_snr"] == pytest.approx(0.5)
    s10 = snr10_table(snr)
    assert list(s10.columns) == SNR10_COLUMNS
    a = s10[s10["cfa"] == "a"].iloc[0]
    assert a["snr10_cd_m2"] == pytest.approx(100.0)
    # the upper curve (x 1.1) reaches 10 at (10 / 1.1)^2, the lower one (x 0.9) at (10 / 0.9)^2
    assert a["ci_low"] == pytest.approx((10 / 1.1) ** 2) and a["ci_high"] == pytest.approx((10 / 0.9) ** 2)
    b = s10[s10["cfa"] == "b"].iloc[0]
    assert np.isnan(b["snr10_cd_m2"]) and "already 50" in b["note"]


def test_crossing_is_none_when_the_sweep_never_reaches_the_target():
    assert crossing([1, 10], [1.0, 2.0]) is None
    assert crossing([1, 10], [11.0, 20.0]) is None
    assert crossing([10, 1], [20.0, 2.0]) == pytest.approx(crossing([1, 10], [2.0, 20.0]))


def test_no_ysnr_gives_no_table():
    m = pd.DataFrame([{"scene": "x", "cfa": "a", "demosaic": "d", "luminance": 1.0, "metric": "ssim",
                       "value": 0.5, "ci_low": 0.5, "ci_high": 0.5}])
    assert snr_table(m).empty
