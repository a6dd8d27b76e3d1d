"""Edge objectives in both directions (design/orientation.py): which tiles
are their own transpose, the transposed TOML of a CFA, the worse of two
values, and the proxy's blur taking the worse direction."""

import numpy as np

from cfa_mitsuba.design.orientation import own_transpose, worse, write_transposed_toml
from cfa_mitsuba.sensor import get_cfa


def test_bayer_is_its_own_transpose_and_full_rows_are_not():
    assert own_transpose(np.array([["G", "R"], ["B", "G"]]))        # G B / R G is G R / B G shifted by (1, 1)
    assert own_transpose(np.array([["R", "B"], ["G", "R"]]))        # symmetric about a diagonal up to a shift
    assert not own_transpose(np.array([["G", "G"], ["B", "R"]]))    # G in rows -> G in columns
    assert not own_transpose(np.array([["G", "R", "G", "B"], ["G", "B", "G", "R"]]))  # 2x4 -> 4x2


def test_transposed_toml_keeps_the_filters(tmp_path):
    cfa = get_cfa("rgb1")
    got = get_cfa(str(write_transposed_toml(tmp_path / "t.toml", cfa)))
    assert got.pattern.tolist() == cfa.pattern.T.tolist()
    assert got.channels == cfa.channels
    np.testing.assert_allclose(got.sensitivities(), cfa.sensitivities(), rtol=1e-6, atol=1e-9)


def test_worse_takes_the_lower_of_a_maximised_value_and_ignores_a_missing_one():
    a, b, nan = (99.0, 98.0, 100.0, 6), (89.0, 88.0, 90.0, 6), (float("nan"),) * 3 + (0,)
    assert worse(a, b, "max") == b and worse(a, b, "min") == a
    assert worse(nan, a, "max") == a and worse(a, nan, "min") == a


def test_proxy_blur_in_both_directions_sees_the_full_rows():
    from cfa_mitsuba.design import proxy as P
    from cfa_mitsuba.design.search import fixed_models
    from cfa_mitsuba.sensor import get_spectra_set

    models = fixed_models(get_spectra_set("isetcam-rgb").curves, ("R", "G", "B"))
    rows = np.array([[1, 1, 2, 0]], np.uint8)        # G G / B R
    cols = np.array([[1, 2, 1, 0]], np.uint8)        # G B / G R, its transpose
    bayer = np.array([[1, 0, 2, 1]], np.uint8)
    one = P.ProxySettings()
    both = P.ProxySettings(edge_both=True)
    blur = {k: P.evaluate_layouts(v, 2, 2, models, s)["blur"][0]
            for k, (v, s) in {"rows": (rows, one), "cols": (cols, one), "bayer": (bayer, one),
                              "rows both": (rows, both), "bayer both": (bayer, both)}.items()}
    assert blur["rows"] < blur["cols"]                      # sharp across the near-vertical edge only
    assert blur["rows both"] == blur["cols"]                # the worse direction
    assert blur["bayer both"] == blur["bayer"]              # Bayer: the same both ways
    assert blur["rows both"] > 1.1 * blur["bayer both"]
