"""Issue 27, render side: the field of view Mitsuba renders (item 2), cache
entries checked against their checksum (item 3), other people's scenes
(item 11: --define, --asset-root, includes of only <default>s, media,
principled BSDF, orthographic camera)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import cfa_mitsuba as cm
from cfa_mitsuba.errors import CfaMitsubaError
from cfa_mitsuba.io.cache import RenderCache
from cfa_mitsuba.study.config import load_config

from conftest import assert_one_line_error, run_cli

LIGHT = """<shape type="sphere"><point name="center" x="0" y="3" z="2"/><float name="radius" value="0.5"/>
    <emitter type="area"><rgb name="radiance" value="5"/></emitter></shape>"""
BALL = """<shape type="sphere"><bsdf type="diffuse"/></shape>"""


def _sensor(fov_xml: str, width: int = 64, height: int = 64, camera: str = "perspective", sampler: str = "") -> str:
    return f"""<sensor type="{camera}">{fov_xml}
    <transform name="to_world"><lookat origin="0,0,4" target="0,0,0" up="0,1,0"/></transform>{sampler}
    <film type="hdrfilm"><integer name="width" value="{width}"/><integer name="height" value="{height}"/></film>
    </sensor>"""


def _scene(tmp_path, body: str, name: str = "scene.xml", sensor: str | None = None):
    p = tmp_path / name
    p.parent.mkdir(parents=True, exist_ok=True)
    p.write_text(f'<scene version="3.0.0">{sensor if sensor is not None else _sensor("")}{body}</scene>')
    return p


def mitsuba_horizontal_fov(fov_props: dict, width: int, height: int) -> float:
    """The angle (degrees) between the rays Mitsuba's own perspective camera
    shoots through the middle of the film's left and right edges: what it
    renders, computed without the project's field-of-view code."""
    import mitsuba as mi

    cm.render.variant.load(cm.render.variant.choose_variant())
    s = mi.load_dict({"type": "perspective", **fov_props,
                      "film": {"type": "hdrfilm", "width": width, "height": height}})
    d = []
    for x in (0.0, 1.0):
        ray, _ = s.sample_ray(0.0, 0.5, mi.Point2f(x, 0.5), mi.Point2f(0.5, 0.5))
        d.append(np.array([np.asarray(c).reshape(-1)[0] for c in (ray.d.x, ray.d.y, ray.d.z)], dtype=np.float64))
    cos = d[0] @ d[1] / (np.linalg.norm(d[0]) * np.linalg.norm(d[1]))
    return math.degrees(math.acos(cos))


AXES = [
    ({"fov": 40.0, "fov_axis": "x"}, '<float name="fov" value="40"/><string name="fov_axis" value="x"/>'),
    ({"fov": 40.0, "fov_axis": "y"}, '<float name="fov" value="40"/><string name="fov_axis" value="y"/>'),
    ({"fov": 40.0, "fov_axis": "diagonal"}, '<float name="fov" value="40"/><string name="fov_axis" value="diagonal"/>'),
    ({"fov": 40.0, "fov_axis": "smaller"}, '<float name="fov" value="40"/><string name="fov_axis" value="smaller"/>'),
    ({"fov": 40.0, "fov_axis": "larger"}, '<float name="fov" value="40"/><string name="fov_axis" value="larger"/>'),
    ({}, ""),  # no fov: Mitsuba's 50 mm lens over the 36 x 24 mm diagonal
    ({"focal_length": "35mm"}, '<string name="focal_length" value="35mm"/>'),
]


@pytest.mark.parametrize("props,xml", AXES, ids=[p.get("fov_axis", p.get("focal_length", "none")) for p, _ in AXES])
@pytest.mark.parametrize("size", [(64, 32), (32, 64), (64, 64)])
def test_fov_is_the_one_mitsuba_renders_for_every_axis_and_film(tmp_path, props, xml, size):
    """The file's film is square; --width/--height give another aspect
    ratio: the recorded field of view follows it as Mitsuba's camera does
    (issue 27 item 2: the Cornell box at 64 x 48 was recorded as 39.31
    degrees while Mitsuba rendered 50.93)."""
    p = _scene(tmp_path, LIGHT + BALL, sensor=_sensor(xml))
    sc, cfg = cm.render.resolve_settings(str(p), width=size[0], height=size[1])
    want = mitsuba_horizontal_fov(props, *size)
    assert cfg.fov_deg == pytest.approx(want, rel=1e-5)
    built = sc.build(cfg)
    assert built.meta["fov_deg"] == pytest.approx(want, rel=1e-5)
    # the lens images that field onto the film width (types.focal_length_m)
    f = built.meta["geometry"]["focal_length_m"]
    assert 2 * math.degrees(math.atan(0.5 * size[0] * cm.render.types.LENS_PIXEL_PITCH_M / f)) == pytest.approx(want)


def test_sidecar_fov_of_a_render_at_another_aspect(tmp_path):
    """One full render through the command line: the sidecar says what
    Mitsuba rendered (fov_axis smaller, square file, 32 x 16 render)."""
    p = _scene(tmp_path, LIGHT + BALL,
               sensor=_sensor('<float name="fov" value="40"/><string name="fov_axis" value="smaller"/>'))
    out = tmp_path / "out"
    run_cli("render", p, "--out", out, "--width", 32, "--height", 16, "--spp", 4, check_rc=0)
    meta = json.loads((out / "scene.json").read_text())
    want = mitsuba_horizontal_fov({"fov": 40.0, "fov_axis": "smaller"}, 32, 16)
    assert want > 70  # not the file's 40 degrees
    assert meta["fov_deg"] == pytest.approx(want, rel=1e-5)


# ------------------------------------------------------------------ cache

SMALL = dict(width=32, height=24, spp=4)


def test_corrupt_but_readable_cache_entry_is_rendered_again(tmp_path, capsys):
    """One digit of the cached EXR's header changed (issue 27 item 3: the
    white radiance 0.00111 -> 0.00911 was reused): the entry fails its
    checksum, is rendered again with one notice line, and the result is the
    fresh render's."""
    cache = RenderCache(tmp_path / "cache")
    first = cm.render.render_cached("gray-bar", cache=cache, **SMALL)
    entry = cache.path(first.meta["cache_key"])
    white = cm.io.read_spectral_exr(entry).meta["canonical_white_radiance"]
    raw = bytearray(entry.read_bytes())
    at = raw.index(b'"canonical_white_radiance": [') + len(b'"canonical_white_radiance": [')
    digit = next(i for i in range(at, at + 40) if chr(raw[i]).isdigit() and chr(raw[i]) not in "09")
    raw[digit] += 1  # still a number, still a readable EXR
    entry.write_bytes(bytes(raw))
    assert cm.io.read_spectral_exr(entry).meta["canonical_white_radiance"] != white
    capsys.readouterr()
    again = cm.render.render_cached("gray-bar", cache=cache, **SMALL)
    err = [ln for ln in capsys.readouterr().err.splitlines() if ln.strip()]
    assert again.meta["cache_reused"] is False
    assert len(err) == 1 and "checksum" in err[0] and str(entry) in err[0]
    assert cm.io.read_spectral_exr(entry).meta["canonical_white_radiance"] == white
    assert again.meta["white_radiance"] == first.meta["white_radiance"]
    np.testing.assert_array_equal(again.data, first.data)
    # replaced by a good entry: reused silently next time
    third = cm.render.render_cached("gray-bar", cache=cache, **SMALL)
    assert third.meta["cache_reused"] is True and capsys.readouterr().err == ""


def test_cache_entry_without_its_checksum_is_not_trusted(tmp_path, capsys):
    cache = RenderCache(tmp_path / "cache")
    first = cm.render.render_cached("gray-bar", cache=cache, **SMALL)
    cache.checksum_path(first.meta["cache_key"]).unlink()
    assert cm.render.render_cached("gray-bar", cache=cache, **SMALL).meta["cache_reused"] is False
    assert "no checksum" in capsys.readouterr().err


# ------------------------------------------------------- other people's scenes

def test_define_sets_scene_parameters(tmp_path):
    """``<float name="fov" value="$fov"/>`` with no <default>: refused in one
    line without --define, rendered with it, and the value reaches Mitsuba
    (the recorded field of view is the defined one)."""
    p = _scene(tmp_path, LIGHT + BALL, sensor=_sensor('<float name="fov" value="$fov"/>',
                                                      sampler='<sampler type="independent"><integer '
                                                              'name="sample_count" value="$spp"/></sampler>'))
    assert_one_line_error(run_cli("render", p, "--out", tmp_path / "o"), "undefined parameter $fov")
    sc, cfg = cm.render.resolve_settings(str(p), defines=["fov=25", "spp=16"])
    assert cfg.fov_deg == pytest.approx(25.0)
    other = cm.render.cache_key(str(p), defines=["fov=26", "spp=16"])
    assert cm.render.cache_key(str(p), defines=["fov=25", "spp=16"]) != other
    assert_one_line_error(run_cli("render", p, "--out", tmp_path / "o", "--define", "fov"), "NAME=VALUE")
    assert_one_line_error(run_cli("render", "macbeth", "--out", tmp_path / "o", "--define", "a=1"), "scene FILE.xml")
    out = tmp_path / "out"
    run_cli("render", p, "--out", out, "--width", 16, "--height", 16, "--spp", 1, "--define", "fov=25",
            "--define=spp=16", check_rc=0)
    assert json.loads((out / "scene.json").read_text())["fov_deg"] == pytest.approx(25.0)


def test_asset_root_opens_one_shared_folder(tmp_path):
    """Mitsuba's test scenes say ``<path value="../../common"/>``: refused by
    default naming --asset-root, loaded with it; a file outside both folders
    stays refused (unlike --allow-outside-paths, which opens every path)."""
    common = tmp_path / "common"
    (common / "meshes").mkdir(parents=True)
    (tmp_path / "elsewhere").mkdir()
    for folder in (common / "meshes", tmp_path / "elsewhere"):
        (folder / "quad.obj").write_text("v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nf 1 2 3 4\n")
    body = LIGHT + '<shape type="obj"><string name="filename" value="meshes/quad.obj"/></shape>'
    p = _scene(tmp_path / "scenes" / "a", '<path value="../../common"/>' + body)
    assert_one_line_error(run_cli("render", p, "--out", tmp_path / "o"), "outside the scene's folder", "--asset-root")
    sc = cm.render.get_scene(str(p), asset_root=str(common))
    assert any(str(common / "meshes" / "quad.obj") == f for _, f, _ in sc.identity["files"])
    q = _scene(tmp_path / "scenes" / "b", LIGHT + '<shape type="obj"><string name="filename" '
                                                  'value="../../elsewhere/quad.obj"/></shape>')
    with pytest.raises(CfaMitsubaError, match="outside the scene's folder .* or the asset root"):
        cm.render.get_scene(str(q), asset_root=str(common))
    assert_one_line_error(run_cli("render", p, "--out", tmp_path / "o", "--asset-root", tmp_path / "nope"),
                          "--asset-root", "not an existing folder")


def test_include_of_only_defaults_loads(tmp_path):
    """Mitsuba lists no file in its parse state for an include that holds
    only <default>s; the scene loads as Mitsuba loads it (issue 27 item 11:
    12 of its scenes were refused)."""
    (tmp_path / "include").mkdir()
    (tmp_path / "include" / "preamble.xml").write_text(
        '<scene version="3.0.0"><default name="fov" value="33"/></scene>')
    p = _scene(tmp_path, '<include filename="include/preamble.xml"/>' + _sensor('<float name="fov" value="$fov"/>')
               + LIGHT + BALL, sensor="")
    sc, cfg = cm.render.resolve_settings(str(p))
    assert cfg.fov_deg == pytest.approx(33.0)
    assert any(f.endswith("preamble.xml") for _, f, _ in sc.identity["files"])  # still part of the cache key


@pytest.mark.parametrize("body,sensor,needles", [
    (LIGHT + '<shape type="sphere"><bsdf type="principled"><float name="sheen" value="1"/>'
             '<float name="sheen_tint" value="0.5"/></bsdf></shape>', None, ('principled', "sheen_tint")),
    (LIGHT, _sensor("", camera="orthographic"), ('<sensor type="orthographic">', "no angular field of view")),
], ids=["tinted-principled", "orthographic"])
def test_unsupported_plugins_are_refused_naming_them(tmp_path, body, sensor, needles):
    p = _scene(tmp_path, body, sensor=sensor)
    assert_one_line_error(run_cli("render", p, "--out", tmp_path / "o"), str(p), *needles)
    assert not (tmp_path / "o").exists()


def test_untinted_principled_bsdf_renders_through_the_all_band_integrator(tmp_path):
    """The principled BSDF picks its lobes by scalar weights (metallic,
    spec_trans, clearcoat) and a scalar eta, so one sampled direction serves
    every band; with a flat grey base colour under a flat light, every band
    of the ball is the same (a wavelength-dependent route would not be)."""
    light = ('<emitter type="constant"><spectrum name="radiance" value="1"/></emitter>')
    ball = ('<shape type="sphere"><bsdf type="principled"><spectrum name="base_color" value="0.5"/>'
            '<float name="metallic" value="0.3"/><float name="roughness" value="0.4"/></bsdf></shape>')
    p = _scene(tmp_path, light + ball, sensor=_sensor('<float name="fov" value="30"/>'))
    img = cm.render.render_canonical(str(p), width=16, height=16, spp=16)
    centre = img.data[6:10, 6:10].mean(axis=(0, 1))
    assert centre.min() > 0
    np.testing.assert_allclose(centre, centre.mean(), rtol=1e-3)


def test_study_custom_scene_takes_defines_and_asset_root(tmp_path):
    """[[custom_scenes]] keys ``defines`` and ``asset_root`` are the render
    command's --define and --asset-root; bad ones are refused by key."""
    common = tmp_path / "common"
    (common / "meshes").mkdir(parents=True)
    (common / "meshes" / "quad.obj").write_text("v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nf 1 2 3 4\n")
    _scene(tmp_path / "scenes" / "a", '<path value="../../common"/>' + LIGHT
           + '<shape type="obj"><string name="filename" value="meshes/quad.obj"/></shape>',
           sensor=_sensor('<float name="fov" value="$fov"/>'))
    body = """name = "t"
scenes = []
cfas = ["bayer"]
demosaics = ["bilinear"]
luminances = [100]
[[custom_scenes]]
name = "a"
file = "scenes/a/scene.xml"
{extra}
"""
    config = tmp_path / "study.toml"
    config.write_text(body.format(extra='asset_root = "common"\n[custom_scenes.defines]\nfov = 28'))
    spec = next(s for s in load_config(config).scenes if s.name == "a")
    assert spec.render["defines"] == {"fov": "28"} and spec.render["asset_root"] == str(common.resolve())
    sc, cfg = cm.render.resolve_settings(spec.file, **spec.render)
    assert cfg.fov_deg == pytest.approx(28.0)
    config.write_text(body.format(extra='asset_root = "nowhere"'))
    with pytest.raises(CfaMitsubaError, match=r"custom_scenes\[0\]\.asset_root.*not an existing folder"):
        load_config(config)
    config.write_text(body.format(extra='defines = "fov=3"'))
    with pytest.raises(CfaMitsubaError, match=r"custom_scenes\[0\]\.defines: must be a table"):
        load_config(config)
