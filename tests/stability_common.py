"""Helpers and shared inputs of the stability matrix (tests/test_stability.py)."""

from __future__ import annotations

import contextlib
import functools
import io
import json
import math
import sys
import tempfile
from pathlib import Path

import numpy as np
import pytest

import cfa_mitsuba as cm
from cfa_mitsuba import spectra
from cfa_mitsuba.errors import CfaMitsubaError
from cfa_mitsuba.values import SpectralImage

sys.path.insert(0, str(Path(__file__).resolve().parent))
from conftest import assert_one_line_error, run_cli  # noqa: E402

M = cm.metrics
WL = spectra.DEFAULT_WAVELENGTHS
D65 = spectra.illuminant("D65", WL)
WHITE_100 = D65 * (100.0 / spectra.luminance_cd_m2(D65, WL))  # a 100 cd/m^2 white, W/(m^2 sr nm)
#: Every registered method: a new one is covered without editing a list.
METHODS = tuple(n for n, _ in cm.isp.list_demosaics())
LUMINANCES = (0.01, 0.1, 1.0, 10.0, 100.0, 1e3, 1e4, 1e5)

CASES: dict[str, callable] = {}


def case(name):
    """Register a row of the matrix under ``name`` (its pytest id)."""

    def add(fn):
        assert name not in CASES, name
        CASES[name] = fn
        return fn

    return add


def raises(fn, *needles):
    """Run ``fn``; it must raise a one-line CfaMitsubaError naming ``needles``."""
    with pytest.raises(CfaMitsubaError) as info:
        fn()
    msg = str(info.value)
    assert "\n" not in msg, msg
    for n in needles:
        assert n.lower() in msg.lower(), (n, msg)
    return f"error: {msg}"


def cli(*args):
    """``cfa-mitsuba ARGS`` in this process: (exit status, stdout, stderr)."""
    from cfa_mitsuba.cli import main

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            rc = main([str(a) for a in args])
        except SystemExit as exc:  # argparse
            rc = exc.code
    return rc, out.getvalue(), err.getvalue()


def cli_error(*args, needles=()):
    """The CLI must exit 2 with one line on stderr naming ``needles``."""
    rc, _, err = cli(*args)
    lines = [line for line in err.splitlines() if line.strip()]
    assert rc == 2 and len(lines) == 1 and "Traceback" not in err, (rc, err)
    for n in needles:
        assert n.lower() in lines[0].lower(), (n, lines[0])
    return f"exit 2: {lines[0]}"


def finite(*arrays):
    for a in arrays:
        a = np.asarray(a, dtype=float)
        assert np.all(np.isfinite(a)), f"{np.size(a) - np.count_nonzero(np.isfinite(a))} non-finite values"


def scene(data, *, white=WHITE_100, **meta) -> SpectralImage:
    """A synthetic spectral image with the sidecar a render would give."""
    m = {"fov_deg": 10.0, "scene_distance_m": 1.2, "oversample": 1, "illuminant": "D65"}
    if white is not None:
        m["white_radiance"] = np.asarray(white, float).tolist()
    m.update(meta)
    return SpectralImage(np.asarray(data, dtype=np.float64), WL.copy(), m)


def flat(h, w, reflectance=0.5, **meta):
    return scene(np.broadcast_to(reflectance * WHITE_100, (h, w, WL.size)).copy(), **meta)


def srgb8(xyz, white):
    return M.colourspace.xyz_to_srgb8(xyz, white)


# -------------------------------------------------------------- shared inputs

@functools.lru_cache(maxsize=None)
def render(name):
    """Small closed-form chart renders (no path tracing; ~2 s for the first,
    Mitsuba's start-up, then ~0.1 s each)."""
    size = {"macbeth": (72, 48), "slanted-edge": (256, 256), "chirp": (256, 64)}[name]
    return cm.render.render(name, width=size[0], height=size[1], spp=4)


@functools.lru_cache(maxsize=None)
def optics(name):
    img = render(name)
    oi = cm.optics.compute_optics(img)
    return oi, M.scene_geometry(img.meta, oi.pixel_irradiance_w_m2_nm.shape)


@functools.lru_cache(maxsize=None)
def sweep(luminance):
    """The whole chain at one luminance, with the exposure chosen at 100 cd/m^2
    and kept (the 'reference' policy: a fixed camera, so that the bright rows
    clip and the dim ones starve): macbeth -> bayer -> bilinear -> metrics."""
    oi, geo = optics("macbeth")
    raw = cm.sensor.capture(oi, "bayer", luminance_cd_m2=luminance, seed=1, exposure_policy="reference")
    img = cm.isp.process(raw, "bilinear")
    ideal = cm.isp.process(cm.sensor.capture_ideal(oi, luminance_cd_m2=luminance))
    cam = M.mean_match(img.xyz, ideal.xyz, border=2)
    w = ideal.white_xyz
    r8, t8 = srgb8(ideal.xyz, w), srgb8(cam, w)
    de = M.delta_e(ideal.xyz, cam, w, patches=geo["patches"])
    out = {
        "raw": raw.raw, "xyz": img.xyz, "srgb": img.srgb, "ideal": ideal.xyz,
        "saturated": raw.meta["saturated_fraction"],
        "de00": float(de), "dl_grey": de.details["mean_dl_grey"],
        "scielab": float(M.scielab(ideal.xyz, cam, w, samples_per_degree=geo["samples_per_degree"])),
        "ssim": M.ssim(r8, t8), "mdsi": M.mdsi(r8, t8), "haarpsi": M.haarpsi(r8, t8),
    }
    # MTF on the slanted edge, as the study measures it (the ideal's edge line
    # as fallback when noise hides the edge's position)
    oi_e, geo_e = optics("slanted-edge")
    e_img = cm.isp.process(cm.sensor.capture(oi_e, "bayer", luminance_cd_m2=luminance, seed=1,
                                             exposure_policy="reference"), "bilinear")
    e_ideal = cm.isp.process(cm.sensor.capture_ideal(oi_e, luminance_cd_m2=luminance))
    lin = M.colourspace.xyz_to_linear(e_img.xyz, scale=e_ideal.white_xyz[1])
    ref = M.colourspace.xyz_to_linear(e_ideal.xyz, scale=e_ideal.white_xyz[1])
    try:
        r = M.mtf(lin, roi=geo_e["roi"], pixel_pitch_um=2.2, reference=ref)
        out["mtf"] = (float(r), r.details["edge_source"])
    except CfaMitsubaError as exc:
        out["mtf"] = f"error: {exc}"
    # moire on the chirp
    oi_c, geo_c = optics("chirp")
    c_img = cm.isp.process(cm.sensor.capture(oi_c, "bayer", luminance_cd_m2=luminance, seed=1), "bilinear")
    c_ideal = cm.isp.process(cm.sensor.capture_ideal(oi_c, luminance_cd_m2=luminance))
    mo = M.moire(c_ideal.xyz, M.mean_match(c_img.xyz, c_ideal.xyz, border=2), c_ideal.white_xyz,
                 frequency_cy_per_deg=geo_c["frequency_cy_per_deg"], row=geo_c["row"], block=7)
    out["msp"] = (float(mo), mo.details["passed"], float(geo_c["frequency_cy_per_deg"][3:-3].min()))
    return out


def _sweep_row(luminance):
    s = sweep(luminance)
    finite(s["raw"], s["xyz"], s["srgb"], s["ideal"])
    assert 0 <= s["raw"].min() and s["raw"].max() <= 4095
    assert 0 <= s["srgb"].min() and s["srgb"].max() <= 1
    for k in ("de00", "dl_grey", "scielab", "ssim", "mdsi", "haarpsi"):
        assert math.isfinite(s[k]), k
    assert s["de00"] >= 0 and s["scielab"] >= 0 and s["mdsi"] >= 0
    assert -1 <= s["ssim"] <= 1 and 0 <= s["haarpsi"] <= 1
    assert math.isfinite(s["msp"][0])
    # the ideal image is the same scene at any luminance: Y scales exactly
    ref = sweep(100.0)["ideal"]
    np.testing.assert_allclose(s["ideal"], ref * (luminance / 100.0), rtol=1e-9, atol=1e-300)
    mtf = s["mtf"] if isinstance(s["mtf"], str) else f"{s['mtf'][0]:.1f} cy/mm ({s['mtf'][1]} edge)"
    return (f"raw {s['raw'].min():.0f}..{s['raw'].max():.0f} DN, {100 * s['saturated']:.0f} % wells full; "
            f"dE00 {s['de00']:.2f}, grey |dL*| {s['dl_grey']:.2f}, S-CIELAB {s['scielab']:.2f}, SSIM {s['ssim']:.3f}, "
            f"MDSI {s['mdsi']:.3f}, HaarPSI {s['haarpsi']:.3f}; MTF50 {mtf}; "
            f"MSP {s['msp'][0]:.2f} cy/deg (passed {s['msp'][1]})")


BLACK = scene(np.zeros((16, 16, WL.size)))


def _mono_cfa():
    """A one-channel CFA (tile "W"), loaded from a TOML file as a user's is."""
    with tempfile.TemporaryDirectory() as d:
        p = Path(d) / "mono.toml"
        p.write_text('name = "mono"\ntile = "W"\n')
        return cm.sensor.get_cfa(str(p))


#: everything above, underscore helpers included, for the row modules' star import
__all__ = [n for n in dir() if not n.startswith("__")]
