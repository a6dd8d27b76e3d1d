"""The crop grid (issue 50): the study saves the same region of every
camera output and of the ideal (study/crops.py) and the report shows it at
1:1 and 4:1 nearest neighbour, a CFA per row, as a lossless PNG at its own
pixels (report/crops.py)."""

from __future__ import annotations

import io

import numpy as np
import pytest
from PIL import Image

from report_fixtures import study_dir

from cfa_mitsuba.report.crops import ZOOM, crop_cell, crop_sheet
from cfa_mitsuba.report.results import load_results
from cfa_mitsuba.study.crops import crop_box


@pytest.fixture(scope="module")
def res(tmp_path_factory):
    return load_results(study_dir(tmp_path_factory))


def test_every_output_and_the_ideal_has_the_same_crop(res):
    for scene in ("chirp", "slanted-edge", "puppy"):
        ideal = np.asarray(Image.open(res.detail_path(scene, None, None, 100.0, ".crop.png")))
        for c in res.cfas:
            for d in res.demosaics:
                crop = np.asarray(Image.open(res.detail_path(scene, c, d, 100.0, ".crop.png")))
                assert crop.shape == ideal.shape and crop.dtype == np.uint8
    assert not res.detail_path("macbeth", "bayer", "pocs", 100.0, ".crop.png").exists()  # no region named


def test_the_4_to_1_panel_is_the_centre_repeated():
    rng = np.random.default_rng(0)
    crop = rng.integers(0, 256, (40, 40, 3), dtype=np.uint8)
    cell = crop_cell(crop, 16)
    h = max(40, 16 * ZOOM)
    assert cell.shape == (h, 40 + 6 + 16 * ZOOM, 3)
    top = (h - 40) // 2
    assert np.array_equal(cell[top:top + 40, :40], crop)
    big = cell[:, 46:]
    assert np.array_equal(big, np.repeat(np.repeat(crop[12:28, 12:28], ZOOM, 0), ZOOM, 1))


def test_regions_sit_where_the_data_file_says(res):
    """The chirp's crop is centred on the column where its local frequency
    reaches 0.375 cy/px; the edge's on its analysis region."""
    from cfa_mitsuba.metrics import scene_geometry

    meta = res.detail("chirp", None, None, 100.0) or {}
    import json

    side = json.loads((res.root / "config.json").read_text())
    assert side["name"] == "report-test" and meta is not None
    from cfa_mitsuba.render import render_cached

    img = render_cached("chirp", width=200, height=120)
    shape = (120 // img.meta["oversample"], 200 // img.meta["oversample"])
    y0, x0, y1, x1 = crop_box("chirp", img.meta, shape)
    f = scene_geometry(img.meta, shape)["frequency_cy_per_px"]
    centre = (x0 + x1) // 2
    assert f[centre - 1] < 0.375 + 0.02 and f[min(centre + 1, len(f) - 1)] > 0.375 - 0.02 or x1 == shape[1]
    assert crop_box("macbeth", img.meta, shape) is None


def test_the_sheet_is_lossless_and_pixelated_in_the_page(res):
    from cfa_mitsuba.report.build import _encode

    fig = crop_sheet(res, "puppy", 100.0)
    assert fig.lossless and fig.image.width > 200
    big = Image.fromarray(np.random.default_rng(1).integers(0, 256, (900, 900, 3), dtype=np.uint8))
    fig.image = big  # far over the JPEG threshold: still PNG
    _, (data, mime) = _encode(fig, ("png",))
    assert mime == "image/png" and np.array_equal(np.asarray(Image.open(io.BytesIO(data))), np.asarray(big))


def test_the_report_shows_the_crop_section(res, tmp_path_factory):
    from cfa_mitsuba.report import build_report

    page = build_report(res.root, formats=(), workers=1).read_text()
    assert 'id="crops"' in page and 'class="raster pixels"' in page
    for scene in ("chirp", "slanted-edge", "puppy"):
        assert f'data-figure="crops-{scene}"' in page
