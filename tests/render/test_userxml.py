"""Users' Mitsuba scene files: rendered with our film, sampler and
integrator, or refused with one clear line."""

from pathlib import Path

import numpy as np
import pytest

import cfa_mitsuba as cm
from cfa_mitsuba import spectra
from cfa_mitsuba.errors import CfaMitsubaError

REPO = Path(__file__).resolve().parents[2]
EXAMPLE = REPO / "scenes" / "examples" / "spheres.xml"

SCENE = """<scene version="3.0.0">
  {sensor}
  {body}
</scene>"""
SENSOR = """<sensor type="perspective"><float name="fov" value="40"/>
    <transform name="to_world"><lookat origin="0,0,4" target="0,0,0" up="0,1,0"/></transform>
    <film type="hdrfilm"><integer name="width" value="24"/><integer name="height" value="16"/></film></sensor>"""
LIGHT = """<shape type="sphere"><point name="center" x="0" y="3" z="2"/><float name="radius" value="0.5"/>
    <emitter type="area"><rgb name="radiance" value="5"/></emitter></shape>"""
BALL = """<shape type="sphere"><bsdf type="{bsdf}"/></shape>"""


def _write(tmp_path, text, name="scene.xml"):
    p = tmp_path / name
    p.write_text(text)
    return p


def test_example_scene_renders_with_its_camera():
    sc = cm.render.get_scene(str(EXAMPLE))
    assert sc.name == "spheres" and (sc.width, sc.height) == (96, 64)  # the file's film size
    assert sc.fov_deg == pytest.approx(30.0) and sc.max_depth == 4  # its camera, its integrator's depth
    assert sc.kind == "natural" and {"scielab", "ssim", "mdsi", "haarpsi"} <= set(cm.metrics.metrics_for_scene(sc.kind))
    img = cm.render.render(str(EXAMPLE), width=48, height=32, spp=16)
    assert img.data.shape == (32, 48, 31)
    assert spectra.luminance_cd_m2(img.data).mean() == pytest.approx(100.0, rel=5e-3)
    assert img.meta["fov_deg"] == pytest.approx(30.0)
    assert img.meta["spp"] == 16 and img.meta["max_depth"] == 4
    white = np.asarray(img.meta["white_radiance"])
    assert np.all(white > 0)  # the D65 (RGB-upsampled) area light, directly
    # The red ball (left) is red, the blue one (right) is blue.
    left, right = img.data[14:20, 6:14].mean(axis=(0, 1)), img.data[14:20, 32:40].mean(axis=(0, 1))
    assert left[25] > 2 * left[5] and right[5] > right[25]


def test_cache_key_follows_the_file(tmp_path):
    p = _write(tmp_path, SCENE.format(sensor=SENSOR, body=LIGHT + BALL.format(bsdf="diffuse")))
    k1 = cm.render.cache_key(str(p))
    p.write_text(SCENE.format(sensor=SENSOR, body=LIGHT + BALL.format(bsdf="roughplastic")))
    assert cm.render.cache_key(str(p)) != k1


@pytest.mark.parametrize("text,needle", [
    (SCENE.format(sensor="", body=LIGHT + BALL.format(bsdf="diffuse")), "no <sensor>"),
    (SCENE.format(sensor=SENSOR, body=BALL.format(bsdf="diffuse")), "no emitter"),
    (SCENE.format(sensor=SENSOR, body=LIGHT + '<shape type="sphere"><bsdf type="principled">'
                  '<float name="spec_tint" value="0.5"/></bsdf></shape>'), "spec_tint"),
    (SCENE.format(sensor=SENSOR.replace("perspective", "orthographic"), body=LIGHT), "orthographic"),
    ("<scene version='3.0.0'><shape type='sphere'>", "well-formed"),
    ("<notascene/>", "not a Mitsuba scene"),
    (SCENE.format(sensor=SENSOR, body=LIGHT + '<shape type="ply"><string name="filename" value="missing.ply"/></shape>'),
     "'missing.ply' not found"),
])
def test_refused_scene_files(tmp_path, text, needle):
    p = _write(tmp_path, text)
    with pytest.raises(CfaMitsubaError, match=needle) as info:
        cm.render.get_scene(str(p))
    assert "\n" not in str(info.value)


def test_unknown_plugin_is_refused_when_built(tmp_path):
    """Mitsuba's parser accepts any plugin name; building the scene refuses
    it in one line."""
    p = _write(tmp_path, SCENE.format(sensor=SENSOR, body=LIGHT + '<shape type="nosuchshape"/>'))
    with pytest.raises(CfaMitsubaError, match="nosuchshape") as info:
        cm.render.render(str(p), spp=1)
    assert "\n" not in str(info.value)


def test_missing_file_and_fov_option(tmp_path):
    with pytest.raises(CfaMitsubaError, match="no such scene file"):
        cm.render.get_scene(str(tmp_path / "nope.xml"))
    with pytest.raises(CfaMitsubaError, match="fov"):
        cm.render.resolve_settings(str(EXAMPLE), fov=20)


def test_white_reference_under_a_uniform_sky_is_the_sky(tmp_path):
    """A perfect white diffuser under a uniform sky of radiance 1 (every
    band) and nothing else in its hemisphere reflects exactly 1: an
    independent check of the white probe and of the scale bookkeeping."""
    sky = '<emitter type="constant"><spectrum name="radiance" value="1"/></emitter>'
    ball = '<shape type="sphere"><point name="center" x="0" y="0" z="-3"/><float name="radius" value="0.5"/><bsdf type="diffuse"/></shape>'
    p = _write(tmp_path, SCENE.format(sensor=SENSOR, body=sky + ball))
    img = cm.render.render(str(p), spp=16)
    white = np.asarray(img.meta["white_radiance"]) / img.meta["scale_from_canonical"]
    np.testing.assert_allclose(white, 1.0, rtol=0.01)
    # The sky seen directly is 1 as well (top-left pixel misses the ball).
    np.testing.assert_allclose(img.data[0, 0] / img.meta["scale_from_canonical"], 1.0, rtol=1e-5)


def test_a_scene_that_fails_to_load_is_never_instantiated_in_this_process(tmp_path, monkeypatch):
    """Mitsuba 3.9 leaves the emitters of a half-built scene registered when
    instantiation fails part way; a later render in the same process then
    called a freed area light and crashed (CI, Nov 2026).  A scene file is
    therefore first loaded in a child process, and a failure there is
    refused without instantiating anything here."""
    from cfa_mitsuba.render import variant

    mi = variant.load(cm.render.choose_variant())
    calls = []
    real = mi.parser.instantiate
    monkeypatch.setattr(mi.parser, "instantiate", lambda *a, **k: calls.append(a) or real(*a, **k))
    bad = _write(tmp_path, SCENE.format(sensor=SENSOR, body=LIGHT + '<shape type="nosuchshape"/>'), "bad.xml")
    with pytest.raises(CfaMitsubaError, match="nosuchshape") as info:
        cm.render.render(str(bad), spp=1)
    assert "\n" not in str(info.value) and str(bad) in str(info.value)
    assert calls == []
    good = _write(tmp_path, SCENE.format(sensor=SENSOR, body=LIGHT + BALL.format(bsdf="diffuse")), "good.xml")
    cm.render.render(str(good), spp=1)
    assert len(calls) >= 1  # the scene that loads in the child is then loaded here


def test_a_crash_while_loading_is_one_line(tmp_path, monkeypatch):
    import subprocess

    from cfa_mitsuba.render import userxml

    p = _write(tmp_path, SCENE.format(sensor=SENSOR, body=LIGHT + BALL.format(bsdf="diffuse")), "crash.xml")
    monkeypatch.setattr(userxml.subprocess, "run",
                        lambda cmd, **kw: subprocess.CompletedProcess(cmd, -11, "", "Fatal Python error\n"))
    with pytest.raises(CfaMitsubaError, match=r"signal 11") as info:
        cm.render.render(str(p), spp=1)
    assert "\n" not in str(info.value) and "crash.xml" in str(info.value)
