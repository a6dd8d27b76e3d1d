"""The registries are the only places a new metric, demosaic, CFA or axis is
named: a toy of each, registered at run time, goes through a tiny study
without any other edit (docs/architecture.md walks the same steps).  The
generic tests also loop over every registered axis."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import cfa_mitsuba as cm
from cfa_mitsuba.study.axes import AXES, Axis, positive, register_axis, unregister_axis
from cfa_mitsuba.study.checker import _Checker
from cfa_mitsuba.study.conditions import Condition


def mean_abs_y(reference_xyz, test_xyz, white_xyz, *, patches=None, scale: float = 1.0):
    """Toy metric: mean |dY| / Y_white over the chart's patches (x ``scale``)."""
    ref, test = np.asarray(reference_xyz), np.asarray(test_xyz)
    d = np.abs(ref[..., 1] - test[..., 1]) / float(white_xyz[1])
    if patches:
        return scale * float(np.mean([d[y0:y1, x0:x1].mean() for y0, x0, y1, x1 in patches]))
    return scale * float(d.mean())


def nearest(raw, cfa, *, shift: int = 0):
    """Toy demosaic: each channel from its nearest sample to the left/up in the tile."""
    pattern = np.asarray(cfa.pattern)
    h, w = raw.shape
    tiled = np.tile(pattern, (h // pattern.shape[0] + 1, w // pattern.shape[1] + 1))[:h, :w]
    out = np.empty((h, w, len(cfa.channels)))
    for k, name in enumerate(cfa.channels):
        filled = np.where(tiled == name, raw, np.nan)
        filled = pd.DataFrame(filled).ffill(axis=1).bfill(axis=1).ffill(axis=0).bfill(axis=0).to_numpy()
        out[..., k] = np.roll(filled, shift, axis=1)
    return out


@pytest.fixture()
def toys():
    record = cm.metrics.MetricRecord(
        name="toy-dy", function=mean_abs_y, scenes=("macbeth",), inputs="xyz", unit="", higher_is_better=False,
        scored=False, label="toy ΔY", description="toy metric of the registry test")
    try:
        cm.metrics.register_metric(record)
        cm.isp.register_demosaic("toy-nearest", nearest, description="toy demosaic of the registry test")
        axis = register_axis(Axis(name="toy_well_e", applies_to="sensor", field="well_capacity_e",
                                  label="well capacity", unit="e⁻", short="wc", check=positive))
        yield record, axis
    finally:
        cm.metrics.unregister_metric("toy-dy")
        from cfa_mitsuba.isp.demosaic import unregister_demosaic

        unregister_demosaic("toy-nearest")
        unregister_axis("toy_well_e")


def test_a_toy_metric_demosaic_and_axis_run_through_a_tiny_study(toys, tmp_path):
    from cfa_mitsuba.study.config import parse_config
    from cfa_mitsuba.study.runner import run_study

    config = parse_config({
        "name": "toys", "seed": 1, "seeds": 2, "workers": 1,
        "scenes": ["macbeth"], "render": {"macbeth": {"width": 96, "height": 84, "spp": 1}},
        "cfas": ["bayer"],
        "demosaics": {"bilinear": {}, "toy-nearest": {"shift": 0}},
        "metrics": {"toy-dy": {"scale": 100.0}},
        "sweep": [{"scene": "macbeth", "toy_well_e": [3000, 12000]}],
        "output": {"report": False, "figures": [], "thumbnails": False},
    }, where="toys.toml")
    assert config.scenes[0].metrics == ("delta-e", "toy-dy")
    res = run_study(config, tmp_path / "out", workers=1, progress=False, log=lambda m: None)
    m = pd.read_csv(tmp_path / "out" / "metrics.csv")
    assert "toy_well_e" in m.columns
    toy = m[m["metric"] == "toy-dy"]
    assert set(toy["demosaic"]) == {"bilinear", "toy-nearest"}
    default_well = cm.sensor.SensorParams().well_capacity_e
    assert set(toy["toy_well_e"]) == {default_well, 3000.0, 12000.0}
    assert toy["value"].gt(0).all() and toy["n"].eq(2).all()
    # the axis reached the sensor: a smaller well clips the bright patches, so the
    # toy error at 3000 e- is not the one at the default well
    by_well = toy[toy["demosaic"] == "bilinear"].set_index("toy_well_e")["value"]
    assert by_well[3000.0] != pytest.approx(by_well[default_well], rel=1e-6)
    # the option from [metrics.toy-dy] reached the function (x100 of a fraction)
    assert toy["value"].max() > 0.1
    assert res.tasks_total == 3


def test_options_of_a_toy_are_checked_against_its_signature(toys):
    from cfa_mitsuba.study.config import parse_config

    base = {"scenes": ["macbeth"], "cfas": ["bayer"]}
    with pytest.raises(cm.CfaMitsubaError, match=r"demosaics.toy-nearest.shiftt: unknown key.*shift"):
        parse_config({**base, "demosaics": {"toy-nearest": {"shiftt": 1}}})
    with pytest.raises(cm.CfaMitsubaError, match=r"demosaics.toy-nearest.shift: must be a finite number"):
        parse_config({**base, "demosaics": {"toy-nearest": {"shift": "one"}}})
    with pytest.raises(cm.CfaMitsubaError, match=r"metrics.toy-dy.patches: unknown key"):
        parse_config({**base, "demosaics": ["bilinear"], "metrics": {"toy-dy": {"patches": 1}}})
    with pytest.raises(cm.CfaMitsubaError, match=r"sweep\[0\].toy_well_e\[0\]: must be a positive number"):
        parse_config({**base, "demosaics": ["bilinear"], "sweep": [{"scene": "macbeth", "toy_well_e": [-1]}]})


def test_pocs_iterations_is_the_pocs_option():
    from cfa_mitsuba.study.config import parse_config

    base = {"scenes": ["macbeth"], "cfas": ["bayer"]}
    old = parse_config({**base, "demosaics": ["pocs"], "isp": {"pocs_iterations": 4}})
    new = parse_config({**base, "demosaics": {"pocs": {"iterations": 4}}})
    assert old.demosaic_options == new.demosaic_options == {"pocs": {"iterations": 4}}
    assert old.chain_settings().isp_options("pocs")["iterations"] == 4
    assert "iterations" not in old.chain_settings().isp_options("bilinear")
    with pytest.raises(cm.CfaMitsubaError, match="pocs_iterations is its old name"):
        parse_config({**base, "demosaics": {"pocs": {"iterations": 4}}, "isp": {"pocs_iterations": 4}})


@pytest.mark.parametrize("name", list(AXES))
def test_every_axis_has_a_default_a_check_and_a_place(name):
    """Each registered axis: its default comes from the stage's parameters,
    the check accepts that default (where it is a value) and refuses a
    wrong type in one line, and a condition carries it to the chain."""
    from cfa_mitsuba.study.chain import ChainSettings

    axis = AXES[name]
    default = axis.default_value()
    assert getattr(Condition(), name) == default
    ck = _Checker("axes.toml")
    if default is not None:
        assert axis.check(ck, default, f"sweep[0].{name}[0]") == default
    with pytest.raises(cm.CfaMitsubaError, match=rf"axes.toml: sweep\[0\].{name}\[0\]: "):
        axis.check(ck, {"not": "a value"}, f"sweep[0].{name}[0]")
    settings = ChainSettings()
    assert getattr(settings.base_condition(), name) == axis.value_in(settings) or axis.applies_to == "capture"
    if axis.applies_to in ("optics", "sensor"):
        optics, sensor = settings.for_condition(Condition())
        assert getattr(optics if axis.applies_to == "optics" else sensor, axis.field) == default
    assert Condition().label(Condition()) == "L100"
