"""``cfa-mitsuba metric NAME REF TEST`` / ``cfa-mitsuba metric mtf IMAGE``:
one metric on image files."""

from __future__ import annotations

import json
import sys
from pathlib import Path

HELP = "compute one image-quality metric on image files"

DESCRIPTION = """\
Compute one of the eight metrics on two image files (reference = ideal,
test = camera), or on one edge image for mtf.  The files are compared
exactly as given unless --mean-match is passed.

How pixel values are read (--input; inferred when omitted, with a notice):
  8-bit PNG      srgb8  (sRGB code values)
  16-bit PNG     linear for mtf (linear code / 65535), else srgb (encoded)
  EXR X,Y,Z      xyz    (absolute XYZ; white from --white, else (95.05, 100, 108.9))
  EXR R,G,B / Y  linear (linear RGB, white = 1)
  NPY / NPZ      linear for mtf, else xyz (the white of a 'process' .npz is
                 its stored white_xyz unless --white is given)
An alpha channel (PNG, EXR 'A') opaque everywhere is dropped; one with any
transparency is refused, as is a fourth channel an NPY / NPZ does not
declare alpha.
Metrics on XYZ (delta-e, scielab, moire, achromatic) convert sRGB / linear
input with the IEC 61966-2-1 matrix (white (95.05, 100, 108.9)); ssim, mdsi
and haarpsi convert XYZ / linear input to sRGB code values (0..255).

Scene geometry (patches, edge ROI, chirp frequencies, field of view) comes
from the render's sidecar with --geometry SIDECAR.json, rescaled to the
image by the sidecar's oversampling factor (an image that is not the
sidecar's scene divided by one whole factor is refused).

Headlines: delta-e mean CIEDE2000 (per patch with --geometry, else per
pixel); scielab mean of the whole dE map; ssim, mdsi, haarpsi the index;
mtf luminance MTF50 in cy/px (cy/mm with --pixel-pitch-um); moire the MSP
in cy/deg; achromatic mean |dL*|.
"""

INPUTS = ("srgb8", "srgb", "linear", "xyz")


def _floats(text: str, n: int, what: str):
    from ..errors import CfaMitsubaError

    try:
        vals = [float(v) for v in text.split(",")]
    except ValueError:
        raise CfaMitsubaError(f"{what} must be {n} comma-separated numbers, got {text!r}") from None
    if len(vals) != n:
        raise CfaMitsubaError(f"{what} must be {n} comma-separated numbers, got {text!r}")
    return vals


def add_arguments(parser) -> None:
    from ..metrics import metric_names

    names = metric_names()
    parser.add_argument("name", choices=list(names), metavar="NAME", help="metric: " + ", ".join(names))
    parser.add_argument("images", nargs="+", metavar="IMAGE", help="REF TEST (mtf, info-capacity: one IMAGE)")
    parser.add_argument("--input", choices=INPUTS, help="how to read the pixel values (default: from the file)")
    parser.add_argument("--samples-per-degree", type=float, metavar="N", help="S-CIELAB viewing: pixels per degree")
    parser.add_argument("--fov-deg", type=float, metavar="DEG", help="horizontal field of view (samples per degree = width / DEG)")
    parser.add_argument("--white", metavar="X,Y,Z", help="white point of XYZ input (default 95.05,100,108.9)")
    parser.add_argument("--pixel-pitch-um", type=float, metavar="P", help="pixel pitch for MTF50 in cy/mm")
    parser.add_argument("--mean-match", action="store_true", help="scale TEST so its interior mean equals REF's")
    parser.add_argument("--geometry", metavar="SIDECAR.json", help="render sidecar with the scene geometry")
    parser.add_argument("--roi", metavar="Y0,X0,Y1,X1", help="mtf: edge region (default: found automatically)")
    parser.add_argument("--version", choices=("2000", "1976"), default="2000", help="delta-e / scielab: dE formula")
    parser.add_argument("--matrix", choices=("xyz2", "xyz10"), default="xyz2", help="scielab: opponent matrix")
    parser.add_argument("--block", type=int, default=15, help="moire: averaging block (px, odd; default 15)")
    parser.add_argument("--threshold", type=float, default=25.0, help="moire: C*ab threshold (default 25)")
    parser.add_argument("--frequency-cpd", metavar="LO,HI",
                        help="moire: chirp frequency at the first and last column (linear), cy/deg")
    parser.add_argument("--json", action="store_true", help="print one JSON object on stdout")


_NOTICES: list[str] = []


def _notice(text: str) -> None:
    """Queue a notice; printed to stderr only when the metric succeeds, so a
    failure is exactly one line."""
    _NOTICES.append(text)


def _flush_notices() -> None:
    for text in _NOTICES:
        sys.stderr.write(f"cfa-mitsuba metric: {text}\n")
    _NOTICES.clear()


class _Loaded:
    def __init__(self, path, data, mode, why, meta):
        self.path, self.data, self.mode, self.why, self.meta = path, data, mode, why, meta


def _load(path, forced, metric_inputs):
    import numpy as np

    from ..errors import CfaMitsubaError
    from ..io import read_image

    f = read_image(path)
    data = f.data
    if f.alpha is not None:  # the one rule for a channel beyond the colour ones (DESCRIPTION)
        clear = int(np.count_nonzero(f.alpha != 1.0))
        if clear:
            raise CfaMitsubaError(f"{path}: its alpha channel is not opaque at {clear} of {f.alpha.size} pixels; "
                                  "flatten the image onto its background first (metrics compare colour only)")
    if f.format == "png":
        data = data / float((1 << f.bit_depth) - 1)  # 0..1 as stored
        if forced == "xyz":
            raise CfaMitsubaError(f"{path}: a PNG cannot hold XYZ; use --input srgb8, srgb or linear")
        if forced:
            mode, why = forced, "--input"
        elif f.bit_depth == 8:
            mode, why = "srgb8", "8-bit PNG"
        else:
            mode = "linear" if metric_inputs == "linear" else "srgb"
            why = "16-bit PNG"
        if mode == "srgb8":
            data = data * 255.0
    else:
        if forced:
            mode, why = forced, "--input"
        elif f.format == "exr":
            mode = "xyz" if f.channels == ("X", "Y", "Z") else "linear"
            why = f"EXR channels {','.join(f.channels or ())}"
        else:
            mode = "linear" if metric_inputs == "linear" else "xyz"
            why = f"{f.format.upper()} array"
    if data.ndim == 3 and data.shape[2] not in (1, 3):
        raise CfaMitsubaError(f"{path}: expected 1 or 3 channels, got {data.shape[2]} (a channel beyond the colour "
                              "ones is dropped only when the file declares it alpha and it is opaque everywhere)")
    if data.ndim == 3 and data.shape[2] == 1:
        data = data[..., 0]
    return _Loaded(str(path), np.asarray(data, dtype=np.float64), mode, why, f.meta)


def _stored_white(path):
    """The ``white_xyz`` array of a ``cfa-mitsuba process`` .npz, else None."""
    import numpy as np

    if Path(path).suffix.lower() != ".npz":
        return None
    from ..io.guard import open_regular

    try:
        with open_regular(path, "image") as fh, np.load(fh, allow_pickle=False) as z:
            if "white_xyz" not in z.files:
                return None
            w = np.asarray(z["white_xyz"], dtype=np.float64).ravel()
    except (ValueError, OSError):
        return None  # _load has already reported an unreadable file
    return w if w.size == 3 else None


def _to_xyz(img: _Loaded, white):
    import numpy as np

    from ..metrics import colourspace as mc

    d = img.data if img.data.ndim == 3 else np.repeat(img.data[..., None], 3, axis=2)
    if img.mode == "xyz":
        return d
    lin = {"srgb8": lambda v: mc.srgb_to_linear(v / 255.0), "srgb": mc.srgb_to_linear, "linear": lambda v: v}[img.mode](d)
    return mc.linear_to_xyz(lin, scale=white[1])


def _to_codes(xyz_or_none, img: _Loaded, white):
    import numpy as np

    from ..metrics import colourspace as mc

    if xyz_or_none is not None:
        return mc.xyz_to_srgb8(xyz_or_none, white, quantize=False)
    d = img.data
    if img.mode == "srgb8":
        return d
    if img.mode == "srgb":
        return 255.0 * d
    if img.mode == "linear":
        return 255.0 * mc.linear_to_srgb(np.clip(d, 0.0, 1.0))
    return mc.xyz_to_srgb8(d if d.ndim == 3 else np.repeat(d[..., None], 3, axis=2), white, quantize=False)


def _to_linear(img: _Loaded, white):
    from ..metrics import colourspace as mc

    d = img.data
    if img.mode == "srgb8":
        _notice(f"{img.path}: decoding sRGB to linear for the edge analysis (a linear image gives a truer MTF)")
        return mc.srgb_to_linear(d / 255.0)
    if img.mode == "srgb":
        _notice(f"{img.path}: decoding sRGB to linear for the edge analysis")
        return mc.srgb_to_linear(d)
    if img.mode == "xyz" and d.ndim == 3:
        return mc.xyz_to_linear(d, scale=white[1])
    return d


def _geometry(path, shape):
    """Scene geometry from a render sidecar, rescaled to an image of ``shape``."""
    from ..io import read_sidecar
    from ..metrics.geometry import scene_geometry

    return scene_geometry(read_sidecar(path), shape)  # read_sidecar checks it against the sidecar schema


#: The metrics of one edge image (linear), not a REF TEST pair.
SINGLE_IMAGE = ("mtf", "info-capacity")


def run(args) -> int:
    import numpy as np

    from .. import metrics as cm
    from ..errors import require

    _NOTICES.clear()
    info = cm.get_metric(args.name)
    single = args.name in SINGLE_IMAGE
    need = 1 if single else 2
    require(len(args.images) == need,
            f"{args.name} takes {'one image (the edge)' if single else 'two images: REF TEST'}, got {len(args.images)}")
    imgs = [_load(p, args.input, info.inputs) for p in args.images]
    from ..metrics._common import check_values

    for im, role in zip(imgs, ("edge image",) if single else ("reference image", "test image")):
        check_values(im.data, f"{role} {im.path}")  # before any conversion: sRGB would clip an infinity to white
    stored = next((w for w in map(_stored_white, args.images) if w is not None), None)
    if args.white:
        white = np.array(_floats(args.white, 3, "--white"), dtype=np.float64)
    elif stored is not None:
        white = stored  # 'cfa-mitsuba process' stores the scene white of its XYZ
    else:
        white = np.array(cm.colourspace.SRGB_WHITE_XYZ, dtype=np.float64)
    require(bool(np.all(np.isfinite(white)) and np.all(white > 0)),
            f"--white must be positive, got {args.white}" if args.white else f"stored white_xyz {white.tolist()} is not positive")
    for im in imgs:
        if not args.input:
            _notice(f"reading {im.path} as {im.mode} ({im.why}); pass --input to override")
        if im.mode == "xyz" and info.inputs != "srgb8" and not args.white:
            if stored is not None:
                _notice(f"{im.path}: XYZ white point {tuple(round(float(v), 4) for v in white)} from the "
                        "processed file's white_xyz; pass --white X,Y,Z to override")
            else:
                _notice(f"{im.path}: XYZ white point assumed (95.05, 100, 108.9); pass --white X,Y,Z")
    geo = _geometry(args.geometry, imgs[-1].data.shape) if args.geometry else {}

    if single:
        roi = _floats(args.roi, 4, "--roi") if args.roi else geo.get("roi")
        inputs = cm.MetricInputs(white_xyz=white, geometry=geo, pixel_pitch_um=args.pixel_pitch_um,
                                 test_linear=_to_linear(imgs[0], white))
        return _emit(args, cm.evaluate(args.name, inputs, roi=roi), imgs)

    ref, test = imgs
    require(ref.data.shape[:2] == test.data.shape[:2],
            f"reference and test images differ in size: {ref.data.shape[:2]} vs {test.data.shape[:2]}")
    xyz_r = xyz_t = None
    if info.inputs == "xyz" or args.mean_match:
        xyz_r, xyz_t = _to_xyz(ref, white), _to_xyz(test, white)
        if args.mean_match:
            xyz_t, scale = cm.mean_match(xyz_t, xyz_r, return_scale=True)
            _notice(f"mean-matched the test image (x {scale:#.6g})")

    options = {"version": args.version}
    if info.inputs == "srgb8":
        inputs = cm.MetricInputs(white_xyz=white, geometry=geo, reference_srgb8=_to_codes(xyz_r, ref, white),
                                 test_srgb8=_to_codes(xyz_t, test, white))
    else:
        inputs = cm.MetricInputs(xyz_r, xyz_t, white, geometry=geo, pixel_pitch_um=args.pixel_pitch_um)
    if args.name == "scielab":
        spd = args.samples_per_degree
        if spd is None and args.fov_deg:
            spd = xyz_r.shape[1] / args.fov_deg
        require(spd is not None or geo.get("samples_per_degree") is not None,
                "scielab needs the viewing geometry: --samples-per-degree N or --fov-deg DEG "
                "(or --geometry with the sidecar's fov_deg)")
        options.update(samples_per_degree=spd, matrix=args.matrix)
    elif args.name == "moire":
        if args.frequency_cpd:
            lo, hi = _floats(args.frequency_cpd, 2, "--frequency-cpd")
            require(np.isfinite(lo) and np.isfinite(hi) and 0 <= lo < hi,
                    f"--frequency-cpd LO,HI: the chirp's frequency at its first column must be at least 0 and below "
                    f"that at its last (a chirp rises left to right), got {args.frequency_cpd!r}")
            options["frequency_cy_per_deg"] = np.linspace(lo, hi, xyz_r.shape[1])
        require(options.get("frequency_cy_per_deg") is not None or geo.get("frequency_cy_per_deg") is not None,
                "moire needs the chirp's frequency map: --frequency-cpd LO,HI or --geometry SIDECAR.json")
        options.update(block=args.block, threshold=args.threshold)
    return _emit(args, cm.evaluate(args.name, inputs, **options), imgs)


def _emit(args, result, imgs) -> int:
    _flush_notices()
    payload = result.to_dict()  # maps summarised, curves kept
    payload["inputs"] = {im.path: im.mode for im in imgs}
    if args.json:
        sys.stdout.write(json.dumps(payload, allow_nan=False) + "\n")
        return 0
    unit = f" {result.unit}" if result.unit else ""
    print(f"{result.name}: {float(result):#.6g}{unit}")
    for key, val in payload.items():
        if key in ("metric", "value", "unit", "inputs") or isinstance(val, (dict, list)):
            continue
        # six significant digits, as the headline: a reader needs no more, and the last digits of
        # a float differ between BLAS and libm builds (--json keeps full precision)
        print(f"  {key}: {val:#.6g}" if isinstance(val, float) else f"  {key}: {val}")
    return 0
