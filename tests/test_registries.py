"""The registries are the only places a new metric, demosaic, denoiser, CFA or
axis is named: a toy of each, registered at run time as the docs say, passes
every generic check of its kind (tests/registry_checks.py, the same checks
the registered members pass) and goes through a tiny study without any other
edit (docs/architecture.md walks the same steps); the design search reads a
demosaic's linearity from its record."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from scipy import ndimage

import cfa_mitsuba as cm
import registry_checks as checks
from cfa_mitsuba.metrics._common import as_pair, as_white
from cfa_mitsuba.study.axes import Axis, positive, register_axis, unregister_axis


def mean_abs_y(reference_xyz, test_xyz, white_xyz, *, patches=None, scale: float = 1.0):
    """Toy metric: mean |dY| / Y_white over the chart's patches (x ``scale``)."""
    ref, test = as_pair(reference_xyz, test_xyz)  # the house's input check: shapes, NaN, infinities
    d = np.abs(ref[..., 1] - test[..., 1]) / float(as_white(white_xyz)[1])
    if patches:
        return scale * float(np.mean([d[y0:y1, x0:x1].mean() for y0, x0, y1, x1 in patches]))
    return scale * float(d.mean())


def nearest(raw, cfa, *, shift: int = 0):
    """Toy demosaic: each channel from its nearest sample (a baseline: no
    accuracy bar), in the mosaic's own precision."""
    pattern = np.asarray(cfa.pattern)
    h, w = raw.shape
    tiled = np.tile(pattern, (h // pattern.shape[0] + 1, w // pattern.shape[1] + 1))[:h, :w]
    out = np.empty((h, w, len(cfa.channels)), dtype=raw.dtype)
    for k, name in enumerate(cfa.channels):
        _, (iy, ix) = ndimage.distance_transform_edt(tiled != name, return_indices=True)
        out[..., k] = np.roll(raw[iy, ix], shift, axis=1)
    return out


def box(plane, *, sigma, size: int = 3):
    """Toy denoiser: a box filter mixed in by the strength."""
    return plane + min(float(sigma), 1.0) * (ndimage.uniform_filter(plane, size, mode="reflect") - plane)


@pytest.fixture()
def toys():
    from cfa_mitsuba.isp.demosaic import unregister_demosaic
    from cfa_mitsuba.isp.denoise import DenoiseMethod, register_denoiser, unregister_denoiser

    record = cm.metrics.MetricRecord(
        name="toy-dy", function=mean_abs_y, scenes=("macbeth",), inputs="xyz", unit="", higher_is_better=False,
        identical_value=0.0, scored=False, label="toy ΔY", description="toy metric of the registry test")
    try:
        cm.metrics.register_metric(record)
        cm.isp.register_demosaic("toy-nearest", nearest, description="toy demosaic of the registry test",
                                 linear=True)
        register_denoiser(DenoiseMethod(name="toy-box", function=box, description="toy denoiser of the registry test",
                                        strength=0.5, tuning="none: a toy", licence="this test's"))
        axis = register_axis(Axis(name="toy_well_e", applies_to="sensor", field="well_capacity_e",
                                  label="well capacity", unit="e⁻", short="wc", check=positive))
        yield record, axis
    finally:
        cm.metrics.unregister_metric("toy-dy")
        unregister_demosaic("toy-nearest")
        unregister_denoiser("toy-box")
        unregister_axis("toy_well_e")


def test_each_toy_passes_the_generic_checks_of_its_kind(toys):
    record, axis = toys
    checks.check_metric(record)
    for cfa in cm.sensor.list_cfas():
        checks.check_demosaic("toy-nearest", cfa)
        checks.check_demosaic_accuracy("toy-nearest", cfa)  # a baseline: no bar to meet
    checks.check_demosaic_ramp("toy-nearest")
    checks.check_demosaic_refusals("toy-nearest")
    checks.check_denoiser("toy-box")
    checks.check_axis(axis)
    # and the registries list them where the command line and the study look
    assert "toy-dy" in cm.metrics.metrics_for_scene("macbeth")
    assert ("toy-nearest", "toy demosaic of the registry test") in cm.isp.list_demosaics()
    from cfa_mitsuba.isp.denoise import list_denoisers

    assert "toy-box" in [n for n, _ in list_denoisers()]


def test_a_toy_cfa_passes_the_generic_checks():
    wl = cm.spectra.DEFAULT_WAVELENGTHS
    own = cm.sensor.get_cfa("rgbw1")
    curves = {ch: (wl, q) for ch, q in zip(own.channels, own.sensitivities(wl))}
    c = cm.sensor.make_cfa("toy-rgbw", "R G / W B", curves, description="toy 2x2 RGBW")
    try:
        cm.sensor.register_cfa(c)
        checks.check_cfa("toy-rgbw")
        for name, _ in cm.isp.list_demosaics():
            checks.check_demosaic(name, "toy-rgbw")
            checks.check_demosaic_accuracy(name, "toy-rgbw")
    finally:
        from cfa_mitsuba.sensor.cfa import _REGISTRY

        _REGISTRY.pop("toy-rgbw", None)


def test_the_design_search_reads_linear_from_the_record(toys):
    """A demosaic whose record says it is linear is predicted by its own
    impulse responses (the search once kept its own list and put laplacian
    in place of any other); a nonlinear one by the Laplacian's."""
    from cfa_mitsuba.design import responses

    assert responses.linear_core("toy-nearest") == "toy-nearest"
    assert responses.linear_core("pocs") == "laplacian" and responses.linear_core("bilinear") == "bilinear"
    layout = np.array([[0, 1], [1, 2]])
    gains = responses.demosaic_noise_gains(layout, ("R", "G", "B"), np.eye(3), "toy-nearest")
    bilinear = responses.demosaic_noise_gains(layout, ("R", "G", "B"), np.eye(3), "bilinear")
    # nearest copies each sample whole (gain 1 per output, averaged over the phases), bilinear averages
    assert np.all(np.isfinite(gains)) and gains[1, 1] == pytest.approx(1.0) and bilinear[1, 1] < gains[1, 1]


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
