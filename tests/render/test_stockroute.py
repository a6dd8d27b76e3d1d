"""Scene files with participating media or a wavelength-dependent BSDF
render through Mitsuba's own path tracers, band by band
(render/stockroute.py; issue 27 acceptance 4), and wide cameras up to
Mitsuba's own limit of 180 degrees."""

import math

import numpy as np
import pytest

import cfa_mitsuba as cm
from cfa_mitsuba.errors import CfaMitsubaError

W, H, FOV_DEG = 16, 12, 10.0
#: Extinction (1/m) rising linearly from 400 to 700 nm; the cube is 2 m deep.
SIGMA_400, SIGMA_700 = 0.25, 1.0
BANDS = "450:650:100"  # three 100-nm boxes: 400-500, 500-600, 600-700 nm

SCENE = """<scene version="3.0.0">
  <integrator type="{integrator}"><integer name="max_depth" value="8"/></integrator>
  <sensor type="perspective"><float name="fov" value="{fov}"/>
    <transform name="to_world"><lookat origin="0,0,6" target="0,0,0" up="0,1,0"/></transform>
    <film type="hdrfilm"><integer name="width" value="{w}"/><integer name="height" value="{h}"/></film></sensor>
  <medium type="homogeneous" id="fog">
    <spectrum name="sigma_t" value="400:{s400}, 700:{s700}"/>
    <float name="albedo" value="{albedo}"/>
  </medium>
  <shape type="cube"><bsdf type="null"/><ref name="interior" id="fog"/></shape>
  <shape type="rectangle">
    <transform name="to_world"><scale value="20"/><translate z="-3"/></transform>
    <emitter type="area"><spectrum name="radiance" value="1"/></emitter>
  </shape>
</scene>"""


def _scene(tmp_path, integrator="volpath", albedo=0.0, fov=FOV_DEG):
    p = tmp_path / "fog.xml"
    p.write_text(SCENE.format(integrator=integrator, albedo=albedo, fov=fov, w=W, h=H, s400=SIGMA_400,
                              s700=SIGMA_700))
    return p


def _beer_lambert_band_means(width, height, fov_deg, edges_nm, sub=8):
    """Expected pixel values (H, W, bands): the band mean of exp(-sigma(l) L)
    averaged over each pixel, L the ray's length inside the cube, written
    out from the pinhole geometry (camera at z = 6 looking down -z; every
    ray crosses the cube's faces z = 1 and z = -1, so L = 2 |d| / |d_z|)."""
    t = math.tan(math.radians(fov_deg) / 2)
    u = (np.arange(width * sub) + 0.5) / (width * sub) * 2 - 1
    v = (np.arange(height * sub) + 0.5) / (height * sub) * 2 - 1
    x, y = np.meshgrid(u * t, v * t * height / width)
    length = 2 * np.sqrt(1 + x * x + y * y)
    out = []
    for lo, hi in zip(edges_nm[:-1], edges_nm[1:]):
        lam = np.linspace(lo, hi, 201)
        sigma = SIGMA_400 + (SIGMA_700 - SIGMA_400) * (lam - 400) / 300
        trans = np.exp(-length[..., None] * sigma).mean(axis=-1)
        out.append(trans.reshape(height, sub, width, sub).mean(axis=(1, 3)))
    return np.stack(out, axis=-1)


def test_absorbing_medium_follows_beer_lambert_in_every_band(tmp_path):
    """A pure absorber with an extinction that quadruples from 400 to 700 nm
    in front of a flat emitter of radiance 1: each band of the render is the
    band mean of exp(-sigma L), an independent closed form, within its
    Monte-Carlo error (the surface-only integrator would see through the
    medium: 1 in every band)."""
    img = cm.render.render_canonical(str(_scene(tmp_path)), width=W, height=H, spp=64, bands=BANDS)
    assert img.meta["integrator"].startswith("Mitsuba volpath")
    want = _beer_lambert_band_means(W, H, FOV_DEG, img.meta["band_edges_nm"])
    ratio = img.data / want
    se = ratio.std(axis=(0, 1), ddof=1) / math.sqrt(W * H)  # standard error of each band's image mean
    assert np.all(se < 0.02)
    np.testing.assert_array_less(np.abs(ratio.mean(axis=(0, 1)) - 1), 5 * se)
    assert want[..., 0].mean() / want[..., 2].mean() > 2.5  # the bands really differ


HAIR = """<scene version="3.0.0">
  <integrator type="path"><integer name="max_depth" value="8"/></integrator>
  <sensor type="perspective"><float name="fov" value="30"/>
    <transform name="to_world"><lookat origin="0,0,4" target="0,0,0" up="0,1,0"/></transform>
    <film type="hdrfilm"><integer name="width" value="{w}"/><integer name="height" value="{h}"/></film></sensor>
  <emitter type="constant"><spectrum name="radiance" value="1"/></emitter>
  <shape type="sphere"><bsdf type="hair"><float name="eumelanin" value="0.3"/></bsdf></shape>
</scene>"""


def _mitsuba_band(text: str, lo: float, hi: float, spp: int, seed: int) -> np.ndarray:
    """Mitsuba rendering the scene file's text itself (its loader, its
    integrator) with the hdrfilm swapped for a specfilm whose box
    sensitivity spans [lo, hi] nm: (H, W) band means."""
    import mitsuba as mi

    film = (f'<film type="specfilm"><integer name="width" value="{W}"/><integer name="height" value="{H}"/>'
            f'<rfilter type="box"/><spectrum name="band" value="{lo}:{1 / (hi - lo)}, {hi}:{1 / (hi - lo)}"/>'
            f'</film><sampler type="independent"><integer name="sample_count" value="{spp}"/></sampler>')
    old = f'<film type="hdrfilm"><integer name="width" value="{W}"/><integer name="height" value="{H}"/></film>'
    assert old in text
    return np.array(mi.render(mi.load_string(text.replace(old, film)), seed=seed), dtype=np.float64)[..., 0]


@pytest.mark.parametrize("kind", ["scattering-medium", "hair"])
def test_stock_route_matches_mitsubas_own_render_of_a_band(tmp_path, kind):
    """A scattering medium (albedo 0.8) under the scene's own volpathmis,
    and a hair BSDF (its lobe chosen by the luminance of its attenuations
    at a path's wavelengths) under path: the 500-600 nm band against
    Mitsuba rendering the unchanged scene text with a specfilm over that
    band (its own loader, film and sampler, another seed); image means
    within their Monte-Carlo errors."""
    if kind == "hair":
        p = tmp_path / "hair.xml"
        p.write_text(HAIR.format(w=W, h=H))
        integrator = "Mitsuba path (BSDF hair"
    else:
        p = _scene(tmp_path, integrator="volpathmis", albedo=0.8)
        integrator = "Mitsuba volpathmis (participating media"
    ours = cm.render.render_canonical(str(p), width=W, height=H, spp=64, bands=BANDS)
    assert ours.meta["integrator"].startswith(integrator)
    lo, hi = ours.meta["band_edges_nm"][1:3]
    ref = _mitsuba_band(p.read_text(), lo, hi, 256, seed=12345)
    diff = ours.data[..., 1] - ref  # same expectation in every pixel: only noise is left
    se = diff.std(ddof=1) / math.sqrt(W * H)
    assert se < 0.02 * ref.mean()
    assert abs(diff.mean()) < 5 * se
    if kind != "hair":  # in-scattering seen: brighter than the transmitted light alone
        assert ref.mean() > 1.05 * _beer_lambert_band_means(W, H, FOV_DEG, [lo, hi])[..., 0].mean()


def test_wide_camera_up_to_mitsubas_limit(tmp_path):
    """Mitsuba's cameras take a horizontal field of view in (0, 180) degrees
    (parse_fov); so does cfa-mitsuba: 175 degrees renders, with the focal
    length of that field (w p / 2) / tan(87.5 deg) in the sidecar, and
    180 is refused in one line."""
    p = _scene(tmp_path, fov=175)
    img = cm.render.render(str(p), width=W, height=H, spp=1, bands=BANDS)
    assert img.meta["fov_deg"] == pytest.approx(175.0)
    want_f = 0.5 * W * cm.render.types.LENS_PIXEL_PITCH_M / math.tan(math.radians(87.5))
    assert img.meta["geometry"]["focal_length_m"] == pytest.approx(want_f, rel=1e-9)
    with pytest.raises(CfaMitsubaError, match="180") as info:
        cm.render.get_scene(str(_scene(tmp_path, fov=180)))
    assert "\n" not in str(info.value)
    with pytest.raises(CfaMitsubaError, match="below 180"):
        cm.render.resolve_settings("macbeth", fov=180)
