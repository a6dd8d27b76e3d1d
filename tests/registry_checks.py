"""The generic checks of every registered thing: each function takes one
registry member (a metric record, a demosaic's name, a denoiser's name, an
axis, a CFA's name, a sensor preset's name) and asserts what the house
promises of every member of its kind.

The test modules run them over the registries (tests/metrics/test_registry.py,
tests/isp/test_demosaic.py, tests/isp/test_denoise.py, tests/study/test_axes.py,
tests/sensor/test_cfa.py, tests/sensor/test_presets.py), so a member added
as the docs say is covered with no edit of a list; tests/test_registries.py
registers a toy of each at run time and runs the same checks on it.  What a
check needs to know of a member that differs between members is on its
record (a metric's ``identical_value`` and the scene kinds it reads, a
demosaic's ``accuracy`` bar), never in a table here.
"""

from __future__ import annotations

import tomllib
from functools import lru_cache

import numpy as np
import pytest

import cfa_mitsuba as cm
from cfa_mitsuba.errors import CfaMitsubaError
from conftest import REPO

# -- metrics ------------------------------------------------------------------------------------


@lru_cache(maxsize=None)
def _quick_render_settings() -> dict:
    """{scene: render settings} of configs/quick.toml (the renders the quick study and the
    report tests make, so a test session renders each chart once)."""
    data = tomllib.loads((REPO / "configs" / "quick.toml").read_text())
    return {name: dict(s) for name, s in data.get("render", {}).items()}


def _scene_of_kind(kind: str) -> str:
    """The built-in scene of ``kind`` (a chart's own kind, or natural: the puppy)."""
    names = [n for n, _ in cm.render.list_scenes() if cm.render.get_scene(n).kind == kind]
    assert names, f"no built-in scene of kind {kind!r} to measure a metric of that kind on"
    return names[0]


@lru_cache(maxsize=None)
def scene_inputs(kind: str):
    """(ideal image, condition, chain) of the built-in scene of ``kind``,
    rendered small (the quick study's size, else half the scene's own) and
    seen by the ideal sensor: the input a metric of that kind reads."""
    from cfa_mitsuba.study.chain import CameraChain

    name = _scene_of_kind(kind)
    scene = cm.render.get_scene(name)
    settings = _quick_render_settings().get(name)
    if settings is None:
        step = 2 * int(scene.oversample or 1)
        settings = {"width": scene.width // 2 // step * step, "height": scene.height // 2 // step * step}
    image = cm.render.render_cached(name, **settings)
    chain = CameraChain()
    cond = chain.settings.base_condition(luminance=100.0)
    ideal = chain.ideal(chain.optical(image, cond), cond)
    return ideal, cond, chain


def check_metric(record) -> None:
    """One computable metric: its record is complete, it evaluates by name
    on a scene of a kind it names, identical images give its record's
    ``identical_value``, a camera image with noise gives a finite value, a
    NaN pixel or another shape is a one-line error, and its options are
    checked by name in a study config."""
    from cfa_mitsuba.metrics.record import INPUT_KINDS

    r = record
    assert r.name and r.function is not None and not r.secondary
    assert isinstance(r.scenes, tuple) and r.scenes and all(isinstance(k, str) and k for k in r.scenes)
    assert r.inputs in INPUT_KINDS and isinstance(r.unit, str) and r.label and r.description
    assert isinstance(r.higher_is_better, bool) and isinstance(r.scored, bool)
    if r.scored:
        worst, best = r.score_range
        assert worst != best and (best > worst) == r.higher_is_better
    listed = cm.metrics.record_json(r)
    assert listed["name"] == r.name and listed["scenes"] == list(r.scenes)
    assert r.name in cm.metrics.metrics_for_scene(r.scenes[0])

    ideal, cond, chain = scene_inputs(r.scenes[0])
    rng = np.random.default_rng(3)
    noisy = ideal.xyz * (1.0 + 0.01 * rng.standard_normal(ideal.xyz.shape))
    value = float(cm.metrics.evaluate(r.name, chain.inputs(ideal, noisy, cond)))
    assert np.isfinite(value), r.name
    if r.identical_value is not None:
        same = float(cm.metrics.evaluate(r.name, chain.inputs(ideal, ideal.xyz.copy(), cond)))
        assert same == pytest.approx(r.identical_value, abs=1e-9), r.name
        assert value != pytest.approx(r.identical_value, abs=1e-12), r.name  # the noise is seen
    bad = noisy.copy()
    bad[2, 3, 1] = np.nan
    with pytest.raises(CfaMitsubaError) as info:
        cm.metrics.evaluate(r.name, chain.inputs(ideal, bad, cond))
    assert "\n" not in str(info.value) and "nan" in str(info.value).lower(), (r.name, str(info.value))
    if r.identical_value is not None:  # a metric comparing the two images: a camera image of another size
        with pytest.raises(CfaMitsubaError):
            cm.metrics.evaluate(r.name, chain.inputs(ideal, np.ascontiguousarray(noisy[:, :-2]), cond))
    _check_options_by_name(r.name)


def _check_options_by_name(name: str) -> None:
    """``[metrics.<name>]`` takes the function's own options, by name, and refuses others."""
    from cfa_mitsuba.study.config import parse_config

    scene = _scene_of_kind(cm.metrics.get_metric(name).scenes[0])
    base = {"scenes": [scene], "cfas": ["bayer"], "demosaics": ["bilinear"]}
    with pytest.raises(CfaMitsubaError, match=rf"metrics\.{name}\.no_such_option: unknown key"):
        parse_config({**base, "metrics": {name: {"no_such_option": 1}}})
    params = cm.metrics.metric_parameters(name)
    given = {k: p.default for k, p in params.items() if isinstance(p.default, (str, int, float, bool))}
    if given:
        cfg = parse_config({**base, "metrics": {name: given}})
        assert cfg.metric_options[name] == given


# -- demosaics ----------------------------------------------------------------------------------


def check_demosaic_samples(name: str, cfa: str) -> None:
    """Shape, finiteness and every sample kept, with partial tiles at both borders."""
    c = cm.sensor.get_cfa(cfa)
    th, tw = c.tile_shape
    shape = (4 * th + th // 2 + 1, 5 * tw + 1)
    raw = np.random.default_rng(0).random(shape)
    out = cm.isp.demosaic(raw, c, name)
    assert out.shape == (*shape, len(c.channels)) and np.all(np.isfinite(out))
    masks = c.masks(shape)
    for k in range(len(c.channels)):
        assert np.array_equal(out[..., k][masks[k]], raw[masks[k]])


def check_demosaic_constants(name: str, cfa: str) -> None:
    """A different constant in each channel, exact to the border (border
    handling that shifts the CFA phase mixes channels and fails); zeros stay
    zeros and a saturated mosaic stays saturated."""
    c = cm.sensor.get_cfa(cfa)
    th, tw = c.tile_shape
    small = (3 * th + 1, 3 * tw + 2)
    levels = np.linspace(0.2, 0.9, len(c.channels))
    truth = np.broadcast_to(levels, (*small, len(levels)))
    assert np.abs(cm.isp.demosaic(cm.isp.mosaic_image(truth, c), c, name) - truth).max() < 1e-12
    assert np.all(cm.isp.demosaic(np.zeros(small), c, name) == 0.0)
    assert np.allclose(cm.isp.demosaic(np.full(small, 4095.0), c, name), 4095.0, rtol=0, atol=1e-9)


def check_demosaic_scale(name: str, cfa: str) -> None:
    """Scale invariance: 1000 x the mosaic gives 1000 x the image."""
    c = cm.sensor.get_cfa(cfa)
    th, tw = c.tile_shape
    raw = np.random.default_rng(5).random((4 * th + 1, 5 * tw + 1))
    a, b = cm.isp.demosaic(raw, c, name), cm.isp.demosaic(1000.0 * raw, c, name)
    assert np.allclose(1000.0 * a, b, rtol=1e-9, atol=1e-9)


def check_demosaic_precision(name: str, cfa: str) -> None:
    """Single precision within a few float32 roundings of the mosaic's range
    of double on a photograph (measured at most 9 over every method and CFA;
    an edge-directed choice near a tie on white noise reaches 16), with the
    mosaic's own float64 samples."""
    from cfa_mitsuba.isp._memo import clear_all

    c = cm.sensor.get_cfa(cfa)
    photo = _photo_mosaic(cfa)
    clear_all()
    double = cm.isp.demosaic(photo, c, name)
    clear_all()
    single = cm.isp.demosaic(photo, c, name, precision="single")
    assert single.dtype == np.float64
    assert float(np.abs(single - double).max()) <= 10 * np.finfo(np.float32).eps * float(np.ptp(photo))
    pm = c.masks(photo.shape)
    for k in range(len(c.channels)):  # the samples are the mosaic's float64 values, not rounded
        assert np.array_equal(single[..., k][pm[k]], photo[pm[k]])


#: Every generic check of one method on one CFA (the test modules run them one by one).
DEMOSAIC_CHECKS = (check_demosaic_samples, check_demosaic_constants, check_demosaic_scale, check_demosaic_precision)


def check_demosaic(name: str, cfa: str) -> None:
    """Every generic check of one method on one CFA (:data:`DEMOSAIC_CHECKS`)."""
    for check in DEMOSAIC_CHECKS:
        check(name, cfa)


def _photo_mosaic(cfa: str, size: int = 96) -> np.ndarray:
    """A crop of scikit-image's astronaut (edges, texture, flat sky), linear
    light 0..1, mosaicked by the CFA's white-balanced channels."""
    from skimage import data

    c = cm.sensor.get_cfa(cfa)
    rgb = (data.astronaut()[100:100 + size, 150:150 + size] / 255.0) ** 2.2
    return cm.isp.mosaic_image(cm.isp.channels_from_rgb(rgb, c), c)


def check_demosaic_too_small(name: str) -> None:
    """A mosaic smaller than the tile is a one-line error; exactly one tile is fine."""
    with pytest.raises(CfaMitsubaError, match="smaller than the CFA tile"):
        cm.isp.demosaic(np.ones((3, 3)), "rgbw2", name)
    with pytest.raises(CfaMitsubaError, match="smaller than the CFA tile"):
        cm.isp.demosaic(np.ones((1, 5)), "bayer", name)
    for cfa in ("bayer", "rgbw2", "rgb3", "cmy2"):
        c = cm.sensor.get_cfa(cfa)
        assert np.allclose(cm.isp.demosaic(np.full(c.tile_shape, 0.3), c, name), 0.3)


def check_demosaic_non_finite(name: str, value: float) -> None:
    """A NaN or an infinity in the mosaic is a one-line error."""
    raw = np.ones((8, 8))
    raw[3, 4] = value
    with pytest.raises(CfaMitsubaError, match="1 NaN or infinite"):
        cm.isp.demosaic(raw, "bayer", name)


def check_demosaic_refusals(name: str) -> None:
    """Bad input is a one-line error for every method (both checks above)."""
    check_demosaic_too_small(name)
    for value in (np.nan, np.inf, -np.inf):
        check_demosaic_non_finite(name, value)


def smooth_errors(cfa: str, name: str):
    """(error everywhere, error inside) of ``name`` on a smooth achromatic
    image (0.5 +- 0.2, periods of 96 and 112 px, plus a ramp)."""
    yy, xx = np.mgrid[0:48, 0:52].astype(float)
    scene = 0.5 + 0.2 * np.sin(2 * np.pi * xx / 96) * np.cos(2 * np.pi * yy / 112) + 0.002 * xx
    out = cm.isp.demosaic(scene, cm.sensor.get_cfa(cfa), name)
    err = np.abs(out - scene[..., None])
    return err, err[6:-6, 6:-6]


@lru_cache(maxsize=None)
def uneven_layout(cfa: str) -> bool:
    """Whether a layout's channels sample unevenly around a pixel: bilinear
    interpolation misses a linear ramp (0.01 and 0.02 per px) by more than a
    quarter of its step inside (measured: 0.0067-0.030 on the sparse,
    quadrant and diagonal-run layouts, at most 0.004 on every other)."""
    ramp = np.add.outer(0.01 * np.arange(48.0), 0.02 * np.arange(52.0))
    out = cm.isp.demosaic(ramp, cfa, "bilinear")
    return float(np.abs(out - ramp[..., None])[10:-10, 10:-10].max()) > 0.25 * 0.02


def check_demosaic_accuracy(name: str, cfa: str) -> None:
    """A method with an accuracy bar (its record's) meets it on ``cfa``:
    white-balanced achromatic content reproduced in every channel, the
    bound growing with the block size on block layouts and wider on the
    layouts that sample unevenly (:func:`uneven_layout`).  A baseline (no
    bar) is not held to it."""
    from cfa_mitsuba.sensor.readout import block_size

    bar = cm.isp.get_demosaic_record(name).accuracy
    if bar is None:
        return
    err, inner = smooth_errors(cfa, name)
    b = block_size(cm.sensor.get_cfa(cfa).pattern)
    if b > 1:
        assert inner.max() < bar.block_max * b and inner.mean() < bar.block_mean * b, (inner.max(), inner.mean())
        assert err.max() < bar.block_border_max * b, err.max()
    elif uneven_layout(cfa):
        assert inner.max() < bar.uneven_max and inner.mean() < bar.uneven_mean, (inner.max(), inner.mean())
        assert err.max() < bar.uneven_border_max, err.max()
    else:
        assert inner.max() < bar.smooth_max and inner.mean() < bar.smooth_mean, (inner.max(), inner.mean())
        assert err.max() < bar.border_max, err.max()


def check_demosaic_ramp(name: str) -> None:
    """A linear ramp is exact on Bayer away from the borders (where the mirror
    folds it), within the margin of the method's accuracy bar; a baseline
    (no bar) is not held to it."""
    bar = cm.isp.get_demosaic_record(name).accuracy
    if bar is None:
        return
    ramp = np.add.outer(0.01 * np.arange(48.0), 0.02 * np.arange(52.0))
    m = bar.ramp_margin_px
    assert np.abs(cm.isp.demosaic(ramp, "bayer", name) - ramp[..., None])[m:-m, m:-m].max() < 1e-9


# -- denoisers ----------------------------------------------------------------------------------


@lru_cache(maxsize=None)
def _grey_captures():
    """A small gray bar captured noisily and noise-free at 10 cd/m^2 (Bayer)."""
    image = cm.render.render_cached("gray-bar", **_quick_render_settings().get("gray-bar", {}))
    noisy = cm.sensor.capture(image, "bayer", luminance_cd_m2=10.0, noise="all", seed=1)
    quiet = cm.sensor.capture(image, "bayer", luminance_cd_m2=10.0, noise="off")
    return noisy, quiet


def check_denoiser(name: str) -> None:
    """One denoiser: its record is complete; in each of its domains it
    returns a finite image of the same shape and records what it applied;
    at scale 0 and on a noise-free capture it changes nothing; an unknown
    option or domain is a one-line error."""
    from cfa_mitsuba.isp.denoise import DOMAINS, get_denoiser

    m = get_denoiser(name)
    assert m.description and m.domains and set(m.domains) <= set(DOMAINS) and m.licence
    noisy, quiet = _grey_captures()
    plain = cm.isp.process(noisy, "bilinear")
    for domain in m.domains:
        out = cm.isp.process(noisy, "bilinear", denoise=name, denoise_options={"domain": domain})
        assert out.xyz.shape == plain.xyz.shape and np.all(np.isfinite(out.xyz))
        rec = out.meta["isp"]["denoise"]
        assert rec["method"] == name
        if m.function is not None:
            assert rec["domain"] == domain and rec["strength"] == m.strength
        still = cm.isp.process(noisy, "bilinear", denoise=name, denoise_options={"domain": domain, "scale": 0})
        assert np.array_equal(still.xyz, plain.xyz)
    assert np.array_equal(cm.isp.process(quiet, "bilinear", denoise=name).xyz, cm.isp.process(quiet, "bilinear").xyz)
    with pytest.raises(CfaMitsubaError, match="has no option 'no_such_option'"):
        cm.isp.process(noisy, "bilinear", denoise=name, denoise_options={"no_such_option": 1})
    with pytest.raises(CfaMitsubaError, match="domain, not 'xyz'"):
        cm.isp.process(noisy, "bilinear", denoise=name, denoise_options={"domain": "xyz"})


# -- axes ---------------------------------------------------------------------------------------


def check_axis(axis) -> None:
    """One study axis: its default comes from the stage's parameters, its
    check accepts that default (where it is a value) and refuses a wrong
    type in one line, a condition carries it to the chain, and its
    behaviour fields are consistent (a scene value only for an axis a
    condition may leave None; a render setting only with a value)."""
    from cfa_mitsuba.study.axes import APPLIES_TO
    from cfa_mitsuba.study.chain import ChainSettings
    from cfa_mitsuba.study.checker import _Checker
    from cfa_mitsuba.study.conditions import Condition

    name = axis.name
    assert axis.applies_to in APPLIES_TO and axis.label and axis.short
    assert isinstance(axis.numeric, bool) and isinstance(axis.realisations, bool)
    default = axis.default_value()
    assert getattr(Condition(), name) == default
    ck = _Checker("axes.toml")
    if default is not None:
        assert axis.check(ck, default, f"sweep[0].{name}[0]") == default
    with pytest.raises(CfaMitsubaError, match=rf"axes.toml: sweep\[0\].{name}\[0\]: "):
        axis.check(ck, {"not": "a value"}, f"sweep[0].{name}[0]")
    settings = ChainSettings()
    assert getattr(settings.base_condition(), name) == axis.value_in(settings) or axis.applies_to == "capture"
    if axis.applies_to in ("optics", "sensor"):
        optics, sensor = settings.for_condition(Condition())
        assert getattr(optics if axis.applies_to == "optics" else sensor, axis.field) == default
    assert Condition().label(Condition()) == "L100"
    assert axis.in_effect(default, {}) == default or default is None
    assert axis.applies(cm.sensor.get_cfa("bayer").pattern, default) or default is None


# -- CFAs and sensor presets --------------------------------------------------------------------


def check_cfa(name: str) -> None:
    """One CFA: a tile of known filters whose channels each sample the tile,
    whose sensitivities are finite, non-negative and positive somewhere for
    every channel, and which mosaics and demosaics."""
    c = cm.sensor.get_cfa(name)
    th, tw = c.tile_shape
    assert c.pattern.shape == (th, tw) and th >= 1 and tw >= 1
    assert set(np.unique(c.pattern)) == set(c.channels)
    qe = c.sensitivities(cm.spectra.DEFAULT_WAVELENGTHS)
    assert qe.shape == (len(c.channels), cm.spectra.DEFAULT_WAVELENGTHS.size)
    assert np.all(np.isfinite(qe)) and np.all(qe >= 0) and np.all(qe.max(axis=1) > 0)
    masks = c.masks((2 * th, 2 * tw))
    assert np.array_equal(np.sum(masks, axis=0), np.ones((2 * th, 2 * tw)))


def check_sensor_preset(name: str) -> None:
    """One sensor preset: valid pixel parameters with their provenance, a
    layout and a spectra set the registries know, and a capture with it
    (its CFA in its spectra set) that gives finite codes within the ADC."""
    p = cm.sensor.get_sensor_preset(name)
    assert isinstance(p.params, cm.sensor.SensorParams) and p.name == name and p.description and p.source
    assert p.params.pixel_pitch_um > 0 and p.params.well_capacity_e > 0
    assert p.spectra in cm.sensor.list_spectra_sets()
    cfa = p.own_cfa if p.own_cfa is not None else cm.sensor.get_cfa(p.cfa_name, spectra=p.spectra)
    image = cm.render.render_cached("gray-bar", **_quick_render_settings().get("gray-bar", {}))
    raw = cm.sensor.capture(image, cfa, luminance_cd_m2=50.0, seed=1, sensor=p.params)
    assert np.all(np.isfinite(raw.raw)) and raw.raw.min() >= 0 and raw.raw.max() <= p.params.max_dn
