"""The stability matrix, rows 9-10: NaN / Inf input, bad files and the rest (collected by tests/test_stability.py)."""

from stability_common import *  # noqa: F401,F403

# ------------------------------------------------------- 9. NaN / Inf input

def _write_raw_exr(path, data, extra=None):
    """A JCGT spectral EXR written with OpenEXR directly (our writer refuses NaN)."""
    import OpenEXR

    from cfa_mitsuba.io.exr import spectral_channel_name

    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage,
              "spectralLayoutVersion": "1.0", "emissiveUnits": "W.m^-2.sr^-1"}
    channels = {spectral_channel_name(w): np.ascontiguousarray(data[..., i], dtype=np.float32)
                for i, w in enumerate(WL)}
    channels.update(extra or {})
    with OpenEXR.File(header, channels) as f:
        f.write(str(path))
    return path


def _bad_exr(d: Path, what: str) -> Path:
    data = np.broadcast_to(0.5 * WHITE_100, (8, 8, WL.size)).copy()
    if what == "nan":
        data[3, 4, 5] = np.nan
    elif what == "inf":
        data[0, 0, 0] = np.inf
    elif what == "-inf":
        data[7, 7, 30] = -np.inf
    elif what == "negative":
        data[1, 1, 1] = -0.5
    return _write_raw_exr(d / f"{what}.exr", data)


for _what in ("nan", "inf", "-inf"):
    @case(f"exr-with-{_what}-read-refused")
    def _(what=_what):
        with tempfile.TemporaryDirectory() as d:
            p = _bad_exr(Path(d), what)
            msg = raises(lambda: cm.io.read_spectral_exr(p), "1 NaN or infinite value")
            cli_msg = cli_error("capture", p, "--cfa", "bayer", "--out", Path(d) / "r.npz",
                                needles=("NaN or infinite",))
            assert not (Path(d) / "r.npz").exists()
        return f"read: {msg}; capture CLI {cli_msg}"


@case("exr-with-nan-capture-cli-subprocess")
def _():
    with tempfile.TemporaryDirectory() as d:
        p = _bad_exr(Path(d), "nan")
        proc = run_cli("capture", p, "--cfa", "bayer", "--out", Path(d) / "r.npz")
        assert_one_line_error(proc, "1 NaN or infinite value")
    return f"exit 2, stderr: {proc.stderr.strip()}"


@case("exr-with-nan-in-preview-channel-only")
def _():
    with tempfile.TemporaryDirectory() as d:
        data = np.broadcast_to(0.5 * WHITE_100, (8, 8, WL.size)).copy()
        rgb = np.full((8, 8), np.nan, dtype=np.float32)
        p = _write_raw_exr(Path(d) / "p.exr", data, {"R": rgb, "G": rgb, "B": rgb})
        img = cm.io.read_spectral_exr(p)
        finite(img.data)
    return "read: the spectral (S0) channels are finite; the R, G, B preview is not data and is ignored"


@case("exr-with-negative-radiance-refused")
def _():
    with tempfile.TemporaryDirectory() as d:
        p = _bad_exr(Path(d), "negative")
        img = cm.io.read_spectral_exr(p)  # readable: a file may hold signed data
        msg = raises(lambda: cm.sensor.capture(img, "bayer"), "negative values", "min -0.5")
        cli_msg = cli_error("capture", p, "--cfa", "bayer", "--out", Path(d) / "r.npz", needles=("negative",))
    return f"capture: {msg}; CLI {cli_msg}"


_XML = """<scene version="3.0.0">
    <sensor type="perspective">
        <float name="fov" value="30"/>
        <transform name="to_world"><lookat origin="0, 0, 3" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="4"/><integer name="height" value="4"/></film>
    </sensor>
    <shape type="rectangle">
        <emitter type="area"><spectrum name="radiance" value="RADIANCE"/></emitter>
    </shape>
</scene>
"""


@case("user-xml-with-inf-nan-or-negative-radiance")
def _():
    out = []
    with tempfile.TemporaryDirectory() as d:
        for what, radiance, needles in (
            ("inf", "400:1, 700:inf", ("NaN or infinite radiance values",)),
            ("nan", "400:1, 700:nan", ("cannot load the scene",)),
            ("negative", "400:-1, 700:-2", ("cannot load the scene", "non-negative")),
        ):
            p = Path(d) / f"{what}.xml"
            p.write_text(_XML.replace("RADIANCE", radiance))
            out.append(f"{what}: " + raises(lambda p=p: cm.render.render(str(p), width=4, height=4, spp=1),
                                            *needles))
        rc, _, err = cli("render", Path(d) / "inf.xml", "--width", 4, "--height", 4, "--spp", 1, "--no-cache",
                         "--out", Path(d) / "out")
        # the render command's notice of the Mitsuba variant precedes a render-time error
        lines = err.strip().splitlines()
        assert rc == 2 and "Traceback" not in err and "variant" in lines[0] and len(lines) == 2, err
        assert lines[-1].startswith("cfa-mitsuba render: error:") and "NaN or infinite" in lines[-1]
        out.append(f"CLI exit 2, after the variant notice: {lines[-1]}")
    return "; ".join(out)


@case("xyz-exr-with-nan-into-metric-cli")
def _():
    import OpenEXR

    with tempfile.TemporaryDirectory() as d:
        paths = []
        for name, bad in (("ref.exr", True), ("test.exr", False)):
            a = np.ones((16, 16, 3), dtype=np.float32) * 40
            if bad:
                a[2, 2, 1] = np.nan
            with OpenEXR.File({"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage},
                              {c: np.ascontiguousarray(a[..., i]) for i, c in enumerate("XYZ")}) as f:
                f.write(str(Path(d) / name))
            paths.append(Path(d) / name)
        return cli_error("metric", "delta-e", *paths, needles=("reference image", "NaN or infinite"))


@case("raw-npz-with-nan-into-process")
def _():
    with tempfile.TemporaryDirectory() as d:
        raw = cm.sensor.capture(flat(8, 8), "bayer", seed=1)
        raw.raw[2, 3] = np.nan
        p = cm.io.save_raw_npz(Path(d) / "nan.npz", raw)
        msg = raises(lambda: cm.isp.process(cm.io.load_raw_npz(p), "bilinear"), "1 NaN or infinite")
        cli_msg = cli_error("process", p, "--out", Path(d) / "x.png", needles=("NaN or infinite",))
        raw = cm.sensor.capture(flat(8, 8), "bayer", seed=1)
        raw.electrons_per_radiance[1, 7] = np.inf
        p = cm.io.save_raw_npz(Path(d) / "inf_epr.npz", raw)
        epr = raises(lambda: cm.isp.process(cm.io.load_raw_npz(p), "bilinear"), "channel 1", "not finite")
    return f"NaN in the mosaic: {msg}; CLI {cli_msg}; inf in electrons_per_radiance: {epr}"


@case("metrics-refuse-nan-and-inf")
def _():
    a = np.full((16, 16, 3), 40.0)
    b = a.copy()
    b[1, 1, 0] = np.nan
    msgs = [raises(lambda f=f: f(a, b), "test image contains 1 NaN or infinite")
            for f in (lambda r, t: M.delta_e(r, t, [95, 100, 108]), lambda r, t: M.ssim(r, t),
                      lambda r, t: M.mdsi(r, t), lambda r, t: M.haarpsi(r, t))]
    raises(lambda: M.mtf(np.where(np.isnan(b), np.inf, b)), "NaN or infinite")
    return msgs[0] + " (delta-e, ssim, mdsi, haarpsi, mtf alike)"


# ------------------------------------------------------------ 10. more rows

@case("exposure-zero-refused")
def _():
    s = flat(8, 8)
    msg = raises(lambda: cm.sensor.capture(s, "bayer", exposure_s=0.0), "positive number of seconds")
    with tempfile.TemporaryDirectory() as d:
        exr = cm.io.write_spectral_exr(Path(d) / "f.exr", s)
        cli_msg = cli_error("capture", exr, "--cfa", "bayer", "--exposure", "0", "--out", Path(d) / "r.npz",
                            needles=("--exposure", "positive"))
    return f"{msg}; CLI {cli_msg}"


@case("exposure-1e-300s-no-usable-signal")
def _():
    raw = cm.sensor.capture(flat(8, 8), "bayer", exposure_s=1e-300, seed=1)
    finite(raw.raw)  # a dark frame: black level and read noise
    return raises(lambda: cm.isp.process(raw, "pocs"), "electrons from the scene white", "no usable signal")


@case("exposure-1e-20s-pure-noise-finite")
def _():
    raw = cm.sensor.capture(flat(16, 16), "bayer", exposure_s=1e-20, seed=1)
    img = cm.isp.process(raw, "pocs")
    finite(img.xyz, img.srgb)
    white_e = (raw.electrons_per_radiance @ raw.white_radiance).min()
    y = np.abs(img.xyz[..., 1]).max()
    return (f"the white gives {white_e:.2g} e-: the image is read noise x a white-balance gain of "
            f"{1 / white_e:.2g}, XYZ finite (|Y| up to {y:.3g} cd/m^2)")


@case("exposure-1e300s-every-well-full")
def _():
    raw = cm.sensor.capture(flat(8, 8), "bayer", exposure_s=1e300, seed=1)
    img = cm.isp.process(raw, "pocs")
    finite(raw.raw, img.xyz)
    assert raw.meta["saturated_fraction"] == 1.0 and 0 < img.xyz[..., 1].max() < 1e-280
    return (f"every well full; the clip level, and so every pixel, is Y ~ {img.xyz[..., 1].mean():.2g} cd/m^2: "
            "finite")


@case("exposure-x-luminance-overflow-refused")
def _():
    oi, _ = optics("macbeth")
    return raises(lambda: cm.sensor.capture(oi, "bayer", exposure_s=1e300, luminance_cd_m2=1e300),
                  "overflows the electron count")


@case("saturated-mosaic")
def _():
    raw = cm.sensor.capture(flat(12, 12), "rgbw2", exposure_s=10.0, seed=1)
    auto = cm.sensor.capture(flat(12, 12), "rgbw2", seed=1).exposure_s
    assert raw.meta["saturated_fraction"] == 1.0
    outs = {m: cm.isp.process(raw, m) for m in METHODS}
    for o in outs.values():
        finite(o.xyz, o.srgb)
        assert o.meta["isp"]["saturated_fraction"] > 0.5
    o = outs["bilinear"]
    y = o.xyz[6, 6, 1] / o.white_xyz[1]
    xy, xy_w = M.colourspace.xyz_to_xy(o.xyz[6, 6]), M.colourspace.xyz_to_xy(o.white_xyz)
    return (f"every well full; XYZ finite: every pixel reads the clip level, Y = {y:.3f} x the white's "
            f"(10 s is {10 / auto:.0f} x the auto exposure), tinted: xy ({xy[0]:.3f}, {xy[1]:.3f}) against the white's "
            f"({xy_w[0]:.3f}, {xy_w[1]:.3f}), since each channel clips at its own fraction of its white response")


@case("oversample-equal-to-image-size")
def _():
    s = flat(16, 16)
    a = raises(lambda: cm.sensor.capture(s, "bayer", oversample=16), "smaller than the CFA tile")
    b = raises(lambda: cm.sensor.capture(s, "bayer", oversample=32), "oversample 32 does not divide")
    img = cm.isp.process(cm.sensor.capture(s, "bayer", oversample=8, seed=1), "pocs")
    finite(img.xyz)
    return f"K = 16: {a}; K = 32: {b}; K = 8 (2 x 2 sensor): finite"


@case("gray-world-on-a-black-scene")
def _():
    raw = cm.sensor.capture(BLACK, "bayer", exposure_s=0.01, seed=4)
    img = cm.isp.process(raw, "bilinear", white_balance="gray-world")
    finite(img.xyz, img.meta["isp"]["white_balance_gains"])
    gains = np.round(img.meta["isp"]["white_balance_gains"], 2).tolist()
    return f"gray world on read noise (channel means ~0): gains {gains}, XYZ finite"
