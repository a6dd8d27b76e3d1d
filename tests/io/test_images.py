"""Plain image files: round trips, 16-bit PNG, atomic writes, bad files."""

import numpy as np
import pytest

from cfa_mitsuba import io
from cfa_mitsuba.errors import CfaMitsubaError

from reference_data import REFERENCE, load_input


@pytest.mark.parametrize("suffix", [".png", ".exr", ".npy", ".npz"])
def test_round_trip(tmp_path, suffix):
    rng = np.random.default_rng(1)
    img = rng.uniform(0, 1, (9, 11, 3))
    p = io.write_image(tmp_path / f"a{suffix}", img, meta={"k": 1})
    back = io.read_image(p)
    scale = 255 if suffix == ".png" else 1
    tol = 0.5 / 255 if suffix == ".png" else 1e-7
    np.testing.assert_allclose(back.data / scale, img, atol=tol)
    assert not list(tmp_path.glob("*.part"))


def test_16bit_rgb_png_keeps_16_bits():
    # Pillow would return 8-bit data here; the reference .npy holds the truth.
    got = io.read_image(REFERENCE / "inputs/edges/edge_05deg_rgb.png")
    expect = load_input("edges/edge_05deg_rgb.npy")
    assert got.bit_depth == 16
    np.testing.assert_array_equal(got.data, expect)


def test_unwritable_target_leaves_nothing(tmp_path):
    # (tests run as root in CI, so permissions cannot make a directory
    # unwritable; a path under a regular file can never be written)
    blocker = tmp_path / "file.txt"
    blocker.write_text("x")
    with pytest.raises(CfaMitsubaError, match="is a file"):
        io.write_image(blocker / "x.png", np.zeros((4, 4)))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file.txt"]


def test_failed_write_removes_temporary(tmp_path):
    with pytest.raises(RuntimeError):
        with io.atomic_output(tmp_path / "x.bin") as tmp:
            tmp.write_bytes(b"half")
            raise RuntimeError("interrupted")
    assert list(tmp_path.iterdir()) == []


def test_bad_inputs(tmp_path):
    with pytest.raises(CfaMitsubaError, match="no such file"):
        io.read_image(tmp_path / "missing.png")
    (tmp_path / "junk.png").write_bytes(b"not a png")
    with pytest.raises(CfaMitsubaError, match="PNG"):
        io.read_image(tmp_path / "junk.png")
    with pytest.raises(CfaMitsubaError, match="NaN"):
        io.write_image(tmp_path / "n.exr", np.full((3, 3), np.nan))
    assert not (tmp_path / "n.exr").exists()


@pytest.mark.parametrize("bit_depth", [8, 16])
@pytest.mark.parametrize("channels", [None, 1, 2, 3, 4])
def test_png_codes_read_back_exactly(tmp_path, bit_depth, channels):
    """The reader gets back exactly the rounded codes at both depths, for
    grey, grey + alpha, RGB and RGBA (the alpha dropped on reading); the
    writer hands pypng array rows, and grey + alpha is written as such."""
    rng = np.random.default_rng(channels or 0)
    img = rng.uniform(-0.1, 1.1, (13, 17) if channels is None else (13, 17, channels))
    img[0, 0] = 0.5 / 255  # a tie: rounds half to even
    p = io.write_image(tmp_path / "c.png", img, bit_depth=bit_depth)
    back = io.read_image(p)
    top = (1 << bit_depth) - 1
    codes = np.rint(np.clip(img, 0, 1) * top)
    if channels in (2, 4):
        codes = codes[..., :-1]
    if channels == 2 or channels == 1:
        codes = codes[..., 0]
    assert back.bit_depth == bit_depth
    np.testing.assert_array_equal(back.data.reshape(codes.shape), codes)


def test_png_of_five_channels_is_refused(tmp_path):
    with pytest.raises(CfaMitsubaError, match="1 to 4 channels"):
        io.write_image(tmp_path / "five.png", np.zeros((4, 4, 5)))
    assert not list(tmp_path.iterdir())
