"""``cfa-mitsuba process RAW.npz --demosaic NAME --out IMAGE``."""

from __future__ import annotations

HELP = "demosaic and colour-correct a raw capture into XYZ and sRGB"

DESCRIPTION = """\
Process a raw capture (from `cfa-mitsuba capture`) into an image:
black level, white balance, demosaic, colour matrix -> CIE XYZ on the ideal
sensor's absolute scale (Y in cd/m^2) and display sRGB.  The ideal sensor's
capture is XYZ already and passes through.

Output by suffix:
  .png  8-bit sRGB (scene white -> 255)
  .exr  float32 XYZ, channels X, Y, Z, cd/m^2; the processing record in the
        'cfaMitsuba' JSON attribute
  .npz  arrays xyz, srgb, white_xyz and meta (JSON string)

Noise reduction (--denoise NAME, before demosaicing by default) takes its
strength from the capture's own predicted noise times the method's tuning
constant; sharpening (--sharpen unsharp) runs after the colour matrix.
Both are off by default.

`cfa-mitsuba list demosaics` and `cfa-mitsuba list denoise` list the
methods; docs/isp.md defines them.
"""


def add_arguments(parser) -> None:
    parser.add_argument("raw", metavar="RAW.npz", help="raw capture written by 'cfa-mitsuba capture'")
    parser.add_argument("--demosaic", default="bilinear", metavar="NAME",
                        help="demosaicing method (default bilinear; see 'list demosaics')")
    parser.add_argument("--out", required=True, metavar="IMAGE", help="output .png, .exr or .npz")
    parser.add_argument("--white-balance", default="illuminant", choices=("illuminant", "gray-world"),
                        help="illuminant: from the sensor's response to the scene white (default); "
                             "gray-world: equal channel means")
    parser.add_argument("--least-squares", action="store_true",
                        help="plain least-squares colour matrix (default: white-preserving)")
    parser.add_argument("--precision", default="double", choices=("double", "single"),
                        help="demosaic in double (default) or single precision (float32: faster, "
                             "within float32 rounding; a study's default)")
    parser.add_argument("--denoise", default="none", metavar="NAME",
                        help="noise reduction (default none; see 'list denoise')")
    parser.add_argument("--denoise-domain", choices=("raw", "rgb"), metavar="DOMAIN",
                        help="raw: the mosaic before demosaicing (default); rgb: the demosaicked channels")
    parser.add_argument("--denoise-scale", type=float, metavar="S",
                        help="times the method's tuning constant (default 1)")
    parser.add_argument("--sharpen", default="none", metavar="NAME",
                        help="sharpening after demosaicing (default none; 'unsharp')")
    parser.add_argument("--radius", type=float, metavar="PX", help="unsharp: Gaussian radius in pixels (default 1)")
    parser.add_argument("--amount", type=float, metavar="A", help="unsharp: amount (default 0.5)")
    parser.add_argument("--iterations", type=int, metavar="N", help="pocs: at most N iterations (default 10)")
    parser.add_argument("--tolerance", type=float, metavar="T",
                        help="pocs: stop when an iteration changes less than T relative RMS (default 1e-3)")


def _write_npz(path, image) -> None:
    import json

    import numpy as np

    from ..io.atomic import atomic_output
    from ..io.sidecar import json_default

    with atomic_output(path) as tmp:
        with open(tmp, "wb") as fh:
            np.savez_compressed(fh, xyz=image.xyz, srgb=image.srgb, white_xyz=image.white_xyz,
                                meta=np.array(json.dumps(image.meta, default=json_default)))


def run(args) -> int:
    from pathlib import Path

    from ..errors import CfaMitsubaError
    from ..io.images import write_image
    from ..io.raw_npz import load_raw_npz
    from ..isp import get_demosaic, get_sharpener, process
    from ..isp.denoise import check_denoise_options

    out = Path(args.out)
    suffix = out.suffix.lower()
    if suffix not in (".png", ".exr", ".npz"):
        raise CfaMitsubaError(f"output {str(out)!r} must end with .png, .exr or .npz")
    get_demosaic(args.demosaic)  # an unknown method fails before the file is read
    options = {k: v for k, v in (("iterations", args.iterations), ("tolerance", args.tolerance)) if v is not None}
    if options and args.demosaic != "pocs":
        raise CfaMitsubaError(f"--iterations and --tolerance apply to pocs, not {args.demosaic!r}")
    denoise_options = {k: v for k, v in (("domain", args.denoise_domain), ("scale", args.denoise_scale))
                       if v is not None}
    check_denoise_options(args.denoise, denoise_options)  # unknown names and options fail before the file is read
    get_sharpener(args.sharpen)
    sharpen_options = {k: v for k, v in (("radius", args.radius), ("amount", args.amount)) if v is not None}
    if sharpen_options and args.sharpen != "unsharp":
        raise CfaMitsubaError(f"--radius and --amount apply to --sharpen unsharp, not {args.sharpen!r}")
    from ..io.validate import check_process_file

    check_process_file(args.raw)  # memory, from the mosaic's header, before it is read
    raw = load_raw_npz(args.raw)
    image = process(raw, args.demosaic, white_balance=args.white_balance,
                    white_preserving=not args.least_squares, demosaic_precision=args.precision,
                    denoise=args.denoise, denoise_options=denoise_options, sharpen=args.sharpen,
                    sharpen_options=sharpen_options, **options)
    if suffix == ".png":
        write_image(out, image.srgb, bit_depth=8)
    elif suffix == ".exr":
        write_image(out, image.xyz, channels=("X", "Y", "Z"), meta=image.meta)
    else:
        _write_npz(out, image)
    isp = image.meta.get("isp", {})
    cond = isp.get("condition_number")
    extra = f", colour matrix condition number {cond:.2f}" if cond is not None else ""
    steps = [isp.get("demosaic") or "no demosaic"]
    steps += [f"{k} {isp[k]['method']}" for k in ("denoise", "sharpen") if (isp.get(k) or {}).get("method", "none") != "none"]
    print(f"wrote {out} ({isp.get('cfa')}, {', '.join(steps)}{extra})")
    return 0
