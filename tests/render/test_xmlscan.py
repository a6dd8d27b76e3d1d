"""Scene files read as Mitsuba reads them (issue 14 acceptance 1, 2) and
hardened (issue 15): includes, <path> folders, the cache key over every
file a render reads, size and nesting bounds, FIFOs, confinement."""

import os
import shutil
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

import cfa_mitsuba as cm
from cfa_mitsuba import spectra
from cfa_mitsuba.errors import CfaMitsubaError
from conftest import REPO, assert_one_line_error, run_cli

SCENES = REPO / "tests" / "data" / "scenes"
SMALL = dict(width=16, height=12, spp=4)


@pytest.fixture
def tabletop(tmp_path):
    """A private copy of the tabletop scene (camera and lights included,
    mesh through <path>, bitmap floor), to edit."""
    shutil.copytree(SCENES / "tabletop", tmp_path / "tabletop")
    return tmp_path / "tabletop"


def test_included_sensor_and_lights_render():
    img = cm.render.render(str(SCENES / "tabletop" / "tabletop.xml"), width=32, height=24, spp=16)
    assert img.data.shape == (24, 32, 31) and np.all(np.isfinite(img.data)) and np.all(img.data >= 0)
    assert spectra.luminance_cd_m2(img.data).mean() == pytest.approx(100.0, rel=5e-3)
    m = img.meta
    assert m["fov_deg"] == pytest.approx(45.0) and m["max_depth"] == 4  # the included camera, the file's depth
    roles = {r for r, _ in m["geometry"]["files"]}
    names = {Path(p).name for _, p in m["geometry"]["files"]}
    assert roles == {"xml", "data"} and {"camera.xml", "lights.xml", "blob.ply", "checker.png"} <= names
    assert m["geometry"]["lens"].startswith("Mitsuba thinlens") and m["geometry"]["aperture_radius_m"] == 0.02


@pytest.mark.parametrize("what,text,needles", [
    ("tint", '<scene version="3.0.0"><shape type="sphere"><bsdf type="principled">'
             '<float name="spec_tint" value="0.5"/></bsdf></shape></scene>',
     ['<bsdf type="principled">', "parts/extra.xml (line 1", "spec_tint"]),
    ("spectral-eta", '<scene version="3.0.0">\n<shape type="sphere"><bsdf type="principledthin">'
                     '<spectrum name="eta" value="400:1.5, 700:1.4"/></bsdf></shape></scene>',
     ['<bsdf type="principledthin">', "parts/extra.xml (line 2", "eta"]),
])
def test_refusals_hold_inside_included_files(tabletop, what, text, needles):
    (tabletop / "parts" / "extra.xml").write_text(text)
    main = tabletop / "tabletop.xml"
    main.write_text(main.read_text().replace('<include filename="parts/lights.xml"/>',
                                             '<include filename="parts/lights.xml"/><include filename="parts/extra.xml"/>'))
    proc = run_cli("render", main, "--out", tabletop / "out", "--width", 8, "--height", 6, "--spp", 1)
    assert_one_line_error(proc, *needles)


def _edit_texture(d: Path):
    Image.fromarray(np.full((16, 16, 3), 30, np.uint8)).save(d / "textures" / "checker.png")


def _edit_mesh(d: Path):
    import importlib.util

    spec = importlib.util.spec_from_file_location("make_assets", SCENES / "make_assets.py")
    assets = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(assets)
    assets.write_ply(d / "meshes" / "blob.ply", *assets.blob_vertices_faces(bumps=0.4))


def _edit_include(d: Path):
    f = d / "parts" / "lights.xml"
    f.write_text(f.read_text().replace('value="1.2, 0.9, 0.6"', 'value="0.3, 0.9, 1.2"'))


@pytest.mark.parametrize("edit", [_edit_texture, _edit_mesh, _edit_include], ids=["texture", "mesh", "included-xml"])
def test_a_changed_file_is_a_new_render(tabletop, tmp_path, edit):
    main = str(tabletop / "tabletop.xml")
    first = cm.render.render_cached(main, cache=tmp_path / "cache", **SMALL)
    again = cm.render.render_cached(main, cache=tmp_path / "cache", **SMALL)
    assert again.meta["cache_reused"] and again.meta["cache_key"] == first.meta["cache_key"]
    edit(tabletop)
    after = cm.render.render_cached(main, cache=tmp_path / "cache", **SMALL)
    assert after.meta["cache_reused"] is False and after.meta["cache_key"] != first.meta["cache_key"]
    assert not np.allclose(after.data, first.data)


def test_path_folders_and_defaults_follow_mitsuba(tabletop):
    """<path> puts its folder in front (a mesh in it shadows one beside the
    file), a <default> is overridden by an earlier one, $name anywhere."""
    from cfa_mitsuba.render import xmlscan

    shutil.copy(tabletop / "meshes" / "blob.ply", tabletop / "blob.ply")
    scan = xmlscan.scan(tabletop / "tabletop.xml")
    assert scan.resolver.resolve("blob.ply") == tabletop / "meshes" / "blob.ply"
    assert [Path(p).name for r, p in scan.files] == ["tabletop.xml", "camera.xml", "lights.xml"]
    assert cm.render.get_scene(str(tabletop / "tabletop.xml")).width == 64  # $res from the main file's <default>


def test_deep_nesting_is_one_line_exit_2(tmp_path):
    p = tmp_path / "deep.xml"
    p.write_text('<scene version="3.0.0">' + "<a>" * 100000 + "</a>" * 100000 + "</scene>")
    proc = run_cli("render", p, "--out", tmp_path / "out")
    assert_one_line_error(proc, "deeper than 64 levels")


def test_oversized_file_is_refused_before_parsing(tmp_path):
    p = tmp_path / "big.xml"
    with open(p, "wb") as fh:
        fh.write(b'<scene version="3.0.0">')
        fh.truncate(17 << 20)
    with pytest.raises(CfaMitsubaError, match="larger than 16 MiB"):
        cm.render.get_scene(str(p))


def test_fifo_include_is_refused_before_it_is_opened(tabletop):
    os.mkfifo(tabletop / "parts" / "pipe.xml")  # opening it for reading would block forever
    main = tabletop / "tabletop.xml"
    main.write_text(main.read_text().replace('<include filename="parts/camera.xml"/>',
                                             '<include filename="parts/camera.xml"/><include filename="parts/pipe.xml"/>'))
    proc = run_cli("render", main, "--out", tabletop / "out")
    assert_one_line_error(proc, '<include filename="parts/pipe.xml">', "a FIFO")


def test_files_outside_the_folder_are_refused_unless_allowed(tabletop, tmp_path):
    outside = tmp_path / "elsewhere"
    outside.mkdir()
    shutil.move(tabletop / "textures" / "checker.png", outside / "checker.png")
    (tabletop / "textures" / "checker.png").symlink_to(outside / "checker.png")  # a symlink out counts as outside
    proc = run_cli("render", tabletop / "tabletop.xml", "--out", tmp_path / "o", "--width", 8, "--height", 6, "--spp", 1)
    assert_one_line_error(proc, '<string name="filename" value="textures/checker.png">', "outside the scene's folder",
                          str(outside / "checker.png"))
    proc = run_cli("render", tabletop / "tabletop.xml", "--out", tmp_path / "o", "--width", 8, "--height", 6, "--spp", 1,
                   "--allow-outside-paths", check_rc=0)
    assert (tmp_path / "o" / "tabletop.exr").is_file()
    inc = tabletop / "tabletop.xml"
    inc.write_text(inc.read_text().replace('<path value="meshes"/>', '<path value="meshes"/><include filename="/etc/hostname"/>'))
    with pytest.raises(CfaMitsubaError, match="outside the scene's folder"):
        cm.render.get_scene(str(inc))


@pytest.mark.parametrize("edit,needles", [
    (('value="45"', 'value="180"'), ['<float name="fov" value="180.0">', "camera.xml", "less than 180"]),
    (('name="max_depth" value="4"', 'name="max_depth" value="100"'), ['<integer name="max_depth" value="100">']),
    (('name="height" value="48"', 'name="height" value="0"'), ['<integer name="height" value="0">']),
])
def test_messages_name_the_xml_element_not_a_flag(tabletop, edit, needles):
    for f in (tabletop / "tabletop.xml", tabletop / "parts" / "camera.xml"):
        f.write_text(f.read_text().replace(*edit))
    with pytest.raises(CfaMitsubaError) as info:
        cm.render.get_scene(str(tabletop / "tabletop.xml"))
    msg = str(info.value)
    assert "--" not in msg and "\n" not in msg
    for n in needles:
        assert n in msg, msg
