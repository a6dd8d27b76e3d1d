"""The stability matrix, rows 5-8: tiny images, MTF edges, a chirp without moire, constant images (collected by tests/test_stability.py)."""

from stability_common import *  # noqa: F401,F403

# ------------------------------------------------------------ 5. tiny images

@case("tiny-render-1x1-8x1-1x8-slanted-edge")
def _():
    shapes = []
    for w, h in ((1, 1), (8, 1), (1, 8)):
        img = cm.render.render("slanted-edge", width=w, height=h, spp=1)
        finite(img.data)
        assert img.data.shape == (h, w, WL.size)
        shapes.append(img)
    msg = raises(lambda: cm.sensor.capture(shapes[0], "bayer"), "oversample 4 does not divide", "use one of 1")
    return f"renders finite (EXR 1x1, 1x8, 8x1); capture with the sidecar's K = 4: {msg}"


@case("tiny-render-chirp-4x4-to-a-2x2-sensor")
def _():
    img = cm.render.render("chirp", width=4, height=4, spp=1)  # oversampled K = 2 by default
    finite(img.data)
    raw = cm.sensor.capture(img, "bayer", seed=1)
    assert raw.raw.shape == (2, 2)
    outs = [cm.isp.process(raw, m) for m in METHODS]
    finite(*[o.xyz for o in outs])
    return "render finite; 2 x 2 bayer sensor (one tile): XYZ finite for all 4 demosaics"


@case("tiny-render-puppy-2x1-path-traced")
def _():
    img = cm.render.render("puppy", width=2, height=1, spp=1)
    finite(img.data)
    assert img.data.shape == (1, 2, WL.size) and img.data.min() >= 0
    ideal = cm.isp.process(cm.sensor.capture_ideal(img))
    finite(ideal.xyz)
    msg = raises(lambda: cm.sensor.capture(img, "bayer"), "smaller than the CFA tile (2 x 2)")
    return f"render finite (1 x 2 px, 1 spp); ideal sensor finite; bayer capture {msg}"


@case("tiny-render-cli-1x1-then-capture")
def _():
    with tempfile.TemporaryDirectory() as d:
        rc, _, err = cli("render", "slanted-edge", "--width", 1, "--height", 1, "--spp", 1, "--no-cache", "--out", d)
        assert rc == 0 and (Path(d) / "slanted-edge.exr").exists(), err
        exr = Path(d) / "slanted-edge.exr"
        refused = cli_error("capture", exr, "--cfa", "bayer", "--out", Path(d) / "r.npz",
                            needles=("oversample 4 does not divide", "use one of 1"))
        rc, out, err = cli("capture", exr, "--cfa", "ideal", "--oversample", 1, "--out", Path(d) / "i.npz")
        assert rc == 0, err
        rc, _, err = cli("process", Path(d) / "i.npz", "--out", Path(d) / "i.npz.png")
        assert rc == 0, err
        ssim = cli_error("metric", "ssim", Path(d) / "i.npz.png", Path(d) / "i.npz.png", needles=("11 x 11",))
        rc, out, _ = cli("metric", "delta-e", Path(d) / "i.npz.png", Path(d) / "i.npz.png", "--json")
        assert rc == 0 and json.loads(out)["value"] == 0.0
    return (f"render exit 0 (a note that 1 x 1 is not a multiple of K = 4); capture {refused}; with "
            f"--oversample 1 the ideal capture, process and delta-e (0) work; ssim {ssim}")


@case("tiny-render-refused-below-chart-minimum")
def _():
    a = raises(lambda: cm.render.render("macbeth", width=8, height=8, spp=1), "at least 30 x 20")
    b = raises(lambda: cm.render.render("gray-bar", width=4, height=4, spp=1), "at least 10 pixels")
    return f"macbeth {a}; gray-bar {b}"


for _h, _w in ((1, 1), (1, 40), (40, 1), (1, 3)):
    @case(f"tiny-capture-{_h}x{_w}-smaller-than-tile")
    def _(h=_h, w=_w):
        s = flat(h, w)
        msgs = [raises(lambda c=c: cm.sensor.capture(s, c, seed=1), "smaller than the CFA tile")
                for c in ("bayer", "rgbw2", "cmy2")]
        ideal = cm.isp.process(cm.sensor.capture_ideal(s))  # no tile: any size works
        finite(ideal.xyz)
        return f"bayer: {msgs[0]}; ideal sensor: finite {h} x {w} XYZ"


@case("tiny-capture-one-row-sensor-with-one-row-tile")
def _():
    bright, dark = (r * WHITE_100[None, None].repeat(20, 1) for r in (0.8, 0.1))
    s = scene(np.concatenate([bright, dark], 1))
    raw = cm.sensor.capture(s, "rgb3", seed=1)  # tile R G B: one row
    assert raw.raw.shape == (1, 40)
    ys = []
    for m in METHODS:
        img = cm.isp.process(raw, m)
        finite(img.xyz, img.srgb)
        ys.append(img.xyz[0, :, 1].mean())
    return (f"1 x 40 sensor with the 1 x 3 stripe tile: finite for all 4 demosaics, mean Y "
            f"{min(ys):.1f}..{max(ys):.1f} cd/m^2")


for _name, _shape in (("bayer", (2, 2)), ("rgbw2", (4, 4)), ("cmy2", (2, 3)), ("rgb4", (3, 3))):
    @case(f"tiny-capture-exactly-one-tile-{_name}")
    def _(name=_name, shape=_shape):
        s = flat(*shape, reflectance=0.3)
        raw = cm.sensor.capture(s, name, noise="off")
        for m in METHODS:
            img = cm.isp.process(raw, m)
            finite(img.xyz, img.srgb)
            # a flat grey through a single tile is still grey at 0.3 x the white
            # (off-axis relative illumination lowers it a little)
            np.testing.assert_allclose(img.xyz / (0.3 * img.white_xyz), 1.0, atol=0.05)
        return f"{shape[0]} x {shape[1]} sensor: flat grey reproduced to < 5 % by all 4 demosaics"


@case("tiny-demosaic-smaller-than-tile")
def _():
    msgs = [raises(lambda m=m: cm.isp.demosaic(np.ones((1, 5)), "bayer", m), "smaller than the CFA tile (2 x 2)")
            for m in METHODS]
    return msgs[0]


def _metrics_on(xyz, white):
    """Every metric on an image and a 1 % brighter copy: value or error."""
    s8a, s8b = srgb8(xyz, white), srgb8(xyz * 1.01, white)
    out = {}
    calls = {
        "delta-e": lambda: M.delta_e(xyz, xyz * 1.01, white),
        "scielab": lambda: M.scielab(xyz, xyz * 1.01, white, samples_per_degree=10),
        "ssim": lambda: M.ssim(s8a, s8b),
        "mdsi": lambda: M.mdsi(s8a, s8b),
        "haarpsi": lambda: M.haarpsi(s8a, s8b),
        "mtf": lambda: M.mtf(xyz),
        "moire": lambda: M.moire(xyz, xyz, white, frequency_cy_per_deg=np.arange(xyz.shape[1], dtype=float)),
        "achromatic": lambda: M.achromatic(xyz, xyz * 1.01, white),
        "achromatic border 0": lambda: M.achromatic(xyz, xyz * 1.01, white, border=0),
        "mean-match": lambda: M.mean_match(xyz, xyz),
    }
    for k, f in calls.items():
        try:
            v = f()
            v = float(np.mean(v))
            assert math.isfinite(v), k
            out[k] = v
        except CfaMitsubaError as exc:
            assert "\n" not in str(exc)
            out[k] = exc
    return out


#: Minimum size each metric names in its error (None: finite at any size).
METRIC_MINIMUM = {"delta-e": None, "scielab": None, "ssim": "11 x 11", "mdsi": "2 x 2", "haarpsi": "2 x 2",
                  "mtf": "8 x 8", "moire": "block", "achromatic": "border 10", "achromatic border 0": None,
                  "mean-match": "border 10"}

for _h, _w in ((1, 1), (1, 40), (40, 1), (2, 2), (10, 10), (11, 11)):
    @case(f"tiny-metrics-{_h}x{_w}")
    def _(h=_h, w=_w):
        xyz = np.broadcast_to([30.0, 32.0, 35.0], (h, w, 3)) * np.linspace(0.5, 1.5, h * w).reshape(h, w, 1)
        white = np.array([95.05, 100.0, 108.9])
        out = _metrics_on(xyz, white)
        for k, need in METRIC_MINIMUM.items():
            ok = not isinstance(out[k], Exception)
            big = {"ssim": min(h, w) >= 11, "mdsi": min(h, w) >= 2, "haarpsi": min(h, w) >= 2,
                   "mtf": False,  # no edge in a gradient: always an error
                   "moire": h >= 15 and w >= 15, "achromatic": w > 20, "mean-match": min(h, w) > 20}.get(k, True)
            assert ok == big, (k, out[k])
            small = {"mtf": min(h, w) < 8}.get(k, True)  # a large gradient has no edge: another error
            if not ok and need and small:
                assert need in str(out[k]), (k, out[k])
        vals = ", ".join(f"{k} {v:.3g}" for k, v in out.items() if not isinstance(v, Exception))
        errs = "; ".join(f"{k}: {v}" for k, v in out.items() if isinstance(v, Exception) and k != "mtf")
        return f"finite: {vals}. Errors: {errs or 'none'}"


@case("tiny-scielab-interior-none")
def _():
    xyz = np.full((5, 5, 3), 40.0)
    r = M.scielab(xyz, xyz * 1.02, [95.05, 100, 108.9], samples_per_degree=72)
    assert r.details["mean_interior"] is None and math.isfinite(float(r))
    return (f"5 x 5 at 72 px/deg: whole-map mean {float(r):.3f}, mean_interior None "
            "(no pixel one degree from the border)")


# ------------------------------------------------------- 6. edges for the MTF

def _edge(angle_deg, n=64, sigma=1.0):
    from scipy.special import erf

    y, x = np.mgrid[0:n, 0:n].astype(float)
    a = np.radians(angle_deg)
    d = (x - n / 2) * np.cos(a) - (y - n / 2) * np.sin(a)
    return 0.2 + 0.6 * 0.5 * (1 + erf(d / (np.sqrt(2) * sigma)))


@case("mtf-edge-0deg-refused")
def _():
    return raises(lambda: M.mtf(_edge(0)), "too close to vertical", "slant it 2-10 deg")


@case("mtf-edge-90deg-refused")
def _():
    return raises(lambda: M.mtf(_edge(90)), "too close to horizontal", "slant it 2-10 deg")


@case("mtf-edge-45deg-refused")
def _():
    return raises(lambda: M.mtf(_edge(45)), "too far from vertical/horizontal", "< 40 deg")


@case("mtf-edge-5deg-and-40deg-analytic")
def _():
    vals = [float(M.mtf(_edge(a))) for a in (5, 40)]
    np.testing.assert_allclose(vals, 0.18739, rtol=0.01)  # Gaussian sigma 1 px: MTF50 = 0.18739 cy/px
    return f"MTF50 {vals[0]:.4f} and {vals[1]:.4f} cy/px (analytic 0.1874)"


@case("mtf-edge-negative-dark-side")
def _():
    r = M.mtf(_edge(5) - 0.4)  # a linear image whose dark side reads below 0 (read noise about black)
    assert 0 <= r.details["contrast"] <= 1 and math.isfinite(float(r))
    return f"MTF50 {float(r):.4f} cy/px, contrast {r.details['contrast']:.2f} (dark side counted as 0)"


@case("mtf-flat-or-noise-refused")
def _():
    a = raises(lambda: M.mtf(np.full((32, 32), 0.5)), "no edge found")
    b = raises(lambda: M.mtf(np.random.default_rng(0).random((32, 32))), "no straight edge found")
    return f"flat: {a}; noise: {b}"


# ------------------------------------------------------ 7. chirp without moire

@case("chirp-ideal-against-itself-no-moire")
def _():
    oi, geo = optics("chirp")
    ideal = cm.isp.process(cm.sensor.capture_ideal(oi))
    r = M.moire(ideal.xyz, ideal.xyz, ideal.white_xyz, frequency_cy_per_deg=geo["frequency_cy_per_deg"],
                row=geo["row"])
    top = float(geo["frequency_cy_per_deg"][7:-7].max())
    assert not r.details["passed"] and not r.details["reference_passes"] and float(r) == top
    return f"passed False, MSP = highest analysed frequency {top:.2f} cy/deg (a lower bound), finite"


@case("chirp-monochrome-camera-never-passes")
def _():
    cfa = _mono_cfa()
    oi, geo = optics("chirp")
    img = cm.isp.process(cm.sensor.capture(oi, cfa, seed=1), "bilinear")
    ideal = cm.isp.process(cm.sensor.capture_ideal(oi))
    r = M.moire(ideal.xyz, M.mean_match(img.xyz, ideal.xyz), ideal.white_xyz,
                frequency_cy_per_deg=geo["frequency_cy_per_deg"], row=geo["row"])
    assert not r.details["passed"] and math.isfinite(float(r))
    chroma = np.nanmax(r.details["block_mean_test"])
    return f"passed False, MSP {float(r):.2f} cy/deg = top of the chirp; max block chroma {chroma:.2g}"


# --------------------------------------------------------- 8. constant images

for _a, _b in ((0, 0), (128, 128), (255, 255), (0, 10), (128, 138), (245, 255)):
    @case(f"constant-images-{_a}-vs-{_b}")
    def _(a=_a, b=_b):
        ra, rb = np.full((32, 32, 3), float(a)), np.full((32, 32, 3), float(b))
        s, m, h = M.ssim(ra, rb), M.mdsi(ra, rb), M.haarpsi(ra, rb)
        hg = M.haarpsi(ra[..., 0], rb[..., 0])
        finite(s, m, h, hg)
        if a == b:
            assert (s, m, h, hg) == (1.0, 0.0, 1.0, 1.0)
        else:
            # SSIM keeps only its luminance term (2 mu_a mu_b + C1) / (mu_a^2 + mu_b^2 + C1)
            c1 = (0.01 * 255) ** 2
            assert s == pytest.approx((2 * a * b + c1) / (a * a + b * b + c1), rel=1e-9)
            assert 0 < m < 0.5 and 0 < h < 1
        return f"SSIM {s:.4f}, MDSI {m:.4f}, HaarPSI {h:.4f} (gray {hg:.4f})"
