"""MDSI and HaarPSI with the reference's maps computed once (issue 25): the
same numbers as without them, which tests/metrics/test_mdsi.py and test_haarpsi.py hold to
the authors' MATLAB code; here also on the authors' own values directly."""

from __future__ import annotations

import numpy as np
import pytest

from cfa_mitsuba import metrics as m
from cfa_mitsuba.errors import CfaMitsubaError
from cfa_mitsuba.metrics import colourspace as mc
from cfa_mitsuba.metrics.haarpsi import haarpsi, haarpsi_reference_maps
from cfa_mitsuba.metrics.mdsi import mdsi, mdsi_reference_maps

from reference_data import COLOUR_PAIRS, colour_pair, entries


@pytest.fixture(scope="module")
def pair():
    codes = np.random.default_rng(5).integers(0, 256, (2, 70, 91, 3)).astype(np.float64)
    return codes[0], np.clip(codes[0] + (codes[1] - 128.0) / 6.0, 0.0, 255.0).round()


@pytest.mark.parametrize("pid", COLOUR_PAIRS)
def test_given_maps_give_the_authors_values(pid):
    ref, dist = colour_pair(pid)
    for e in entries("colour_pairs", pid, "mdsi", oracle="MDSI.m"):
        comb, *trap = e["variant"].split("|")
        a, b = (dist, ref) if trap else (ref, dist)
        got = mdsi(a, b, combination=comb, reference_maps=mdsi_reference_maps(a))
        assert got == mdsi(a, b, combination=comb)
        assert abs(got - e["value"]) <= 1e-6
    for e in entries("colour_pairs", pid, "haarpsi", oracle="HaarPSI.m"):
        a, b = (ref, dist) if e["variant"] == "rgb" else (mc.rgb_to_gray(ref), mc.rgb_to_gray(dist))
        got = haarpsi(a, b, reference_maps=haarpsi_reference_maps(a))
        assert got == haarpsi(a, b)
        assert abs(got - e["value"]) <= 1e-6


@pytest.mark.parametrize("options", [{}, {"subsample": False}, {"data_range": 1.0}])
def test_haarpsi_maps_equal_the_direct_call(pair, options):
    ref, test = pair
    scale = 1.0 / 255.0 if options.get("data_range") == 1.0 else 1.0
    a, b = ref * scale, test * scale
    assert haarpsi(a, b, reference_maps=haarpsi_reference_maps(a, **options), **options) == haarpsi(a, b, **options)


@pytest.mark.parametrize("options", [{}, {"combination": "mult"}, {"data_range": 1.0}])
def test_mdsi_maps_equal_the_direct_call(pair, options):
    ref, test = pair
    scale = 1.0 / 255.0 if options.get("data_range") == 1.0 else 1.0
    a, b = ref * scale, test * scale
    maps = mdsi_reference_maps(a, **{k: v for k, v in options.items() if k == "data_range"})
    assert mdsi(a, b, reference_maps=maps, **options) == mdsi(a, b, **options)


@pytest.mark.parametrize("name", ["mdsi", "haarpsi"])
def test_the_adapter_computes_the_maps_once_per_reference(pair, name):
    ref, test = pair
    shared: dict = {}
    first = float(m.evaluate(name, m.MetricInputs(reference_srgb8=ref, test_srgb8=test, shared=shared)))
    keys = [k for k in shared if isinstance(k, tuple) and k[0] == name]
    assert len(keys) == 1
    cached = shared[keys[0]]
    other = np.clip(test + 3.0, 0, 255)
    second = float(m.evaluate(name, m.MetricInputs(reference_srgb8=ref, test_srgb8=other, shared=shared)))
    assert shared[keys[0]] is cached
    direct = mdsi if name == "mdsi" else haarpsi
    assert first == direct(ref, test)
    assert second == direct(ref, other)


def test_maps_of_another_image_or_options_are_refused(pair):
    ref, test = pair
    with pytest.raises(CfaMitsubaError, match="reference_maps"):
        mdsi(ref, test, reference_maps=mdsi_reference_maps(ref[:40]))
    with pytest.raises(CfaMitsubaError, match="reference_maps"):
        mdsi(ref, test, data_range=1000.0, reference_maps=mdsi_reference_maps(ref))
    with pytest.raises(CfaMitsubaError, match="reference_maps"):
        haarpsi(ref, test, reference_maps=haarpsi_reference_maps(ref[:, :50]))
    with pytest.raises(CfaMitsubaError, match="reference_maps"):
        haarpsi(ref, test, subsample=False, reference_maps=haarpsi_reference_maps(ref))
