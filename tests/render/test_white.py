"""The white reference of 3D scenes (issue 14 acceptance 3), the f-number
setting, the cache key's coverage and render/'s import graph (issue 11)."""

import ast
import math
from pathlib import Path

import numpy as np
import pytest

import cfa_mitsuba as cm
from cfa_mitsuba import spectra
from conftest import REPO, run_cli

SCENES = REPO / "tests" / "data" / "scenes"
ALL = {
    "spheres": (REPO / "scenes" / "examples" / "spheres.xml", dict(width=48, height=32, spp=16)),
    "tabletop": (SCENES / "tabletop" / "tabletop.xml", dict(width=32, height=24, spp=16)),
    "whitepanel": (SCENES / "whitepanel" / "whitepanel.xml", dict(spp=16)),
    "cbox": (SCENES / "cbox" / "cbox.xml", dict(spp=16)),
    "puppy": ("puppy", dict(width=64, height=48, spp=16)),
}


@pytest.fixture(scope="module", params=sorted(ALL))
def rendered(request):
    scene, settings = ALL[request.param]
    return request.param, cm.render.render_cached(str(scene), **settings)


def test_white_lies_between_the_median_and_twice_the_robust_maximum(rendered):
    name, img = rendered
    y = spectra.luminance_cd_m2(img.data)
    white = img.meta["white_luminance_cd_m2"]
    assert np.median(y) <= white <= 2 * np.percentile(y, 99), (name, white, np.median(y), np.percentile(y, 99))
    assert white > 0 and np.all(np.asarray(img.meta["white_radiance"]) > 0)
    assert white == pytest.approx(spectra.luminance_cd_m2(np.asarray(img.meta["white_radiance"])))
    assert img.meta["white_from"] == "panel" and len(img.meta["white_reference"]["panels"]) >= 5


def test_white_matches_a_white_panel_facing_the_light():
    """The camera sees a perfect white panel facing the main light, filling
    the middle of the image: the recorded white is its radiance."""
    img = cm.render.render_cached(str(SCENES / "whitepanel" / "whitepanel.xml"), spp=64)
    panel = img.data[10:22, 16:32].mean(axis=(0, 1))  # the panel, clear of its edges
    white = np.asarray(img.meta["white_radiance"])
    assert spectra.luminance_cd_m2(white) == pytest.approx(spectra.luminance_cd_m2(panel), rel=0.05)
    np.testing.assert_allclose(white / white.sum(), panel / panel.sum(), atol=0.1 / 31)  # same spectral shape


def test_white_rules_illuminant_and_xyz():
    scene, settings = ALL["cbox"]
    panel = cm.render.render_cached(str(scene), **settings)
    illum = cm.render.render_cached(str(scene), **settings, white_from="illuminant")
    assert illum.meta["cache_key"] == panel.meta["cache_key"]  # the white is not part of the render
    y = spectra.luminance_cd_m2(illum.data)
    assert illum.meta["white_luminance_cd_m2"] == pytest.approx(np.percentile(y, 99))
    w_p, w_i = (np.asarray(m.meta["white_radiance"]) for m in (panel, illum))
    np.testing.assert_allclose(w_i / w_i.sum(), w_p / w_p.sum(), rtol=1e-9)  # same spectrum, another level
    xyz = (95.047, 100.0, 108.883)
    given = cm.render.render_cached(str(scene), **settings, white_from="95.047,100,108.883")
    np.testing.assert_allclose(spectra.xyz_from_radiance(np.asarray(given.meta["white_radiance"])), xyz, rtol=1e-9)
    assert given.meta["white_from"] == "xyz"
    # Charts: the exact white under every rule but X,Y,Z.
    a, b = (cm.render.render_cached("macbeth", width=64, height=48, white_from=w) for w in ("panel", "illuminant"))
    np.testing.assert_allclose(a.meta["white_radiance"], b.meta["white_radiance"])


def test_bad_white_from_is_one_line(tmp_path):
    proc = run_cli("render", "macbeth", "--out", tmp_path, "--white-from", "1,2")
    assert proc.returncode == 2 and "white_from (--white-from)" in proc.stderr and "Traceback" not in proc.stderr


def test_f_number_sets_the_thin_lens_and_only_its_key():
    puppy = dict(width=32, height=24, spp=4)
    assert cm.render.cache_key("puppy", **puppy) == cm.render.cache_key("puppy", **puppy, f_number=2.0)
    assert cm.render.cache_key("puppy", **puppy) != cm.render.cache_key("puppy", **puppy, f_number=8.0)
    assert cm.render.cache_key("macbeth", width=32, height=24) == cm.render.cache_key("macbeth", width=32, height=24,
                                                                                      f_number=8.0)
    spheres = str(REPO / "scenes" / "examples" / "spheres.xml")  # a pinhole camera
    assert cm.render.cache_key(spheres) == cm.render.cache_key(spheres, f_number=8.0)
    table = str(SCENES / "tabletop" / "tabletop.xml")  # its own thin lens
    assert cm.render.cache_key(table) != cm.render.cache_key(table, f_number=8.0)
    img = cm.render.render("puppy", **puppy, f_number=8.0)
    g = img.meta["geometry"]
    assert img.meta["f_number"] == g["f_number"] == 8.0
    assert g["aperture_radius_m"] == pytest.approx(g["focal_length_m"] / 16)
    chart = cm.render.render_cached("macbeth", width=32, height=24, f_number=5.6)
    assert chart.meta["f_number"] == 5.6
    lens = cm.render.render(table, width=16, height=12, spp=1, f_number=4.0).meta["geometry"]
    assert lens["aperture_radius_m"] == pytest.approx(lens["focal_length_m"] / 8) and lens["f_number"] == 4.0
    own = cm.render.render(table, width=16, height=12, spp=1).meta["geometry"]
    assert own["aperture_radius_m"] == 0.02 and own["f_number_implied"] == pytest.approx(own["focal_length_m"] / 0.04)


def test_cache_key_covers_the_code_and_data_a_render_reads():
    from cfa_mitsuba.render import engine

    names = {p.name for p in engine._digest_paths()}
    assert {"spectra.py", "values.py", "exr.py", "engine.py", "white.py", "userxml.py"} <= names
    pkg = Path(cm.__file__).parent
    assert pkg / "spectra.py" in engine._digest_paths()
    assert any("colour_checkers" in str(p) for p in engine._digest_paths())  # the Ohta reflectances


def _imports(path: Path) -> set[str]:
    """render/ modules imported by ``path``, at module or function level."""
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.level == 1:
            if node.module:
                out.add(node.module.split(".")[0])
            else:
                out.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("cfa_mitsuba.render."):
            out.add(node.module.split(".")[2])
    return out


def test_render_has_no_import_cycles():
    render_dir = Path(cm.__file__).parent / "render"
    graph = {p.stem: _imports(p) & {q.stem for q in render_dir.glob("*.py")} for p in render_dir.glob("*.py")
             if p.stem != "__init__"}

    def reach(start):
        seen, todo = set(), [start]
        while todo:
            for nxt in graph.get(todo.pop(), ()):
                if nxt not in seen:
                    seen.add(nxt)
                    todo.append(nxt)
        return seen

    cycles = [m for m in graph if m in reach(m)]
    assert not cycles, {m: graph[m] for m in cycles}
    assert not ({"charts", "puppy", "builtins"} & reach("registry"))
