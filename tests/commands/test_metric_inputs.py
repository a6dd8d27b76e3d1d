"""`cfa-mitsuba metric`: inputs that used to give a silent wrong answer
(issue 51, item 7): images of another size than the sidecar's scene, an
alpha channel, a chirp whose frequencies fall."""

from __future__ import annotations

import json

import numpy as np
import pytest

from cfa_mitsuba.cli import main
from cfa_mitsuba.errors import CfaMitsubaError
from cfa_mitsuba.metrics.geometry import scene_geometry


def _run(capsys, *args):
    code = main([str(a) for a in args])
    out = capsys.readouterr()
    return code, out.out, out.err


def _error(capsys, *args):
    code, _, err = _run(capsys, *args)
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert code == 2 and len(lines) == 1 and "Traceback" not in err, err
    return lines[0]


def _sidecar(tmp_path, width=30, height=20):
    patches = [{"rect": [1 + 4 * (i // 6), 1 + 5 * (i % 6), 4 + 4 * (i // 6), 5 + 5 * (i % 6)]} for i in range(24)]
    p = tmp_path / "side.json"
    p.write_text(json.dumps({"width": width, "height": height, "fov_deg": 10.0, "geometry": {"patches": patches}}))
    return p


def test_an_image_of_another_height_than_the_sidecar_is_refused_naming_both(tmp_path, capsys):
    side = _sidecar(tmp_path)
    rng = np.random.default_rng(1)
    x = rng.uniform(10, 90, (40, 30, 3))  # the sidecar's width, twice its height: no single K maps it
    np.savez(tmp_path / "a.npz", xyz=x)
    np.savez(tmp_path / "b.npz", xyz=x * 1.01)
    line = _error(capsys, "metric", "delta-e", tmp_path / "a.npz", tmp_path / "b.npz", "--geometry", side)
    assert "30 x 20" in line and "30 x 40" in line
    with pytest.raises(CfaMitsubaError, match="30 x 20 .* 30 x 40"):
        scene_geometry(json.loads(side.read_text()), (40, 30, 3))
    # the image a K = 2 capture makes (and its one-pixel partial tile) is still the scene's
    for shape in ((10, 15, 3), (11, 15, 3)):
        g = scene_geometry(json.loads(side.read_text()), shape)
        assert g["oversample"] == 2 and g["patches"][0] == (1, 1, 2, 2)


def _png(path, rgba):
    from PIL import Image

    Image.fromarray(rgba if rgba.shape[2] == 4 else rgba[..., :3]).save(path)
    return path


def test_alpha_is_dropped_only_when_opaque_everywhere(tmp_path, capsys):
    rng = np.random.default_rng(2)
    rgba = rng.integers(0, 256, (16, 16, 4), dtype=np.uint8)
    rgba[..., 3] = 255
    test = rgba.copy()
    test[..., :3] = np.clip(rgba[..., :3].astype(int) + 9, 0, 255)
    opaque, other = _png(tmp_path / "o.png", rgba), _png(tmp_path / "t.png", test)
    rgb, other_rgb = _png(tmp_path / "rgb.png", rgba[..., :3]), _png(tmp_path / "trgb.png", test[..., :3])
    values = []
    for a, b in ((opaque, other), (rgb, other_rgb)):
        code, out, err = _run(capsys, "metric", "ssim", a, b, "--json")
        assert code == 0, err
        values.append(json.loads(out)["value"])
    assert values[0] == values[1] < 1  # an opaque alpha changes nothing
    rgba[3, 5, 3] = 254  # one pixel not quite opaque
    line = _error(capsys, "metric", "ssim", _png(tmp_path / "clear.png", rgba), other)
    assert "alpha channel is not opaque at 1 of 256 pixels" in line
    np.savez(tmp_path / "four.npz", image=np.ones((16, 16, 4)))  # no alpha declared: refused, even if all ones
    line = _error(capsys, "metric", "ssim", tmp_path / "four.npz", tmp_path / "four.npz")
    assert "got 4" in line and "declares it alpha" in line


def test_an_exr_alpha_follows_the_same_rule(tmp_path, capsys):
    """The reader keeps an EXR's A apart from its colour (as a PNG's); the
    metric applies the one rule to it."""
    import OpenEXR

    from cfa_mitsuba.io import read_image

    rgb = np.random.default_rng(4).uniform(0.1, 0.9, (16, 16)).astype(np.float32)
    for alpha, ok in ((np.ones((16, 16), np.float32), True), (np.full((16, 16), 0.5, np.float32), False)):
        p = tmp_path / f"a{ok}.exr"
        with OpenEXR.File({"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage},
                          {"R": rgb, "G": rgb, "B": rgb, "A": alpha}) as f:
            f.write(str(p))
        f = read_image(p)
        assert f.data.shape == (16, 16, 3) and f.alpha.shape == (16, 16)
        if ok:
            code, out, err = _run(capsys, "metric", "ssim", p, p, "--json")
            assert code == 0 and json.loads(out)["value"] == pytest.approx(1.0), err
        else:
            assert "not opaque at 256 of 256" in _error(capsys, "metric", "ssim", p, p)


def test_a_falling_chirp_frequency_is_refused(tmp_path, capsys):
    rng = np.random.default_rng(3)
    x = rng.uniform(10, 90, (20, 60, 3))
    np.savez(tmp_path / "a.npz", xyz=x)
    np.savez(tmp_path / "b.npz", xyz=x * 1.01)
    for bad in ("10,1", "5,5", "-1,4"):
        line = _error(capsys, "metric", "moire", tmp_path / "a.npz", tmp_path / "b.npz", f"--frequency-cpd={bad}")
        assert "--frequency-cpd" in line and bad in line
    code, _, err = _run(capsys, "metric", "moire", tmp_path / "a.npz", tmp_path / "b.npz", "--frequency-cpd", "1,10")
    assert code == 0, err
