"""``cfa-mitsuba render PATH`` for a measured spectral image (a ``.exr``,
``.hdr`` or ``.mat`` file, or a folder of per-band PNGs): the flags it adds
to the render command and the run that converts instead of rendering
(:mod:`cfa_mitsuba.render.measured`)."""

from __future__ import annotations

import sys
from pathlib import Path

EPILOG = """\
SCENE may also be a measured spectral image: a JCGT spectral EXR written by
any tool, an ENVI cube (X.hdr beside its data file), a folder of per-band
PNGs (CAVE: NAME_ms_01.png ... NAME_ms_31.png = 400..700 nm), a MATLAB .mat
cube (v5 or v7.3) or an ISETCam scene file.  It is put on the band grid
(exact 10-nm box means of the linearly interpolated source), not rendered;
--spp, --seed, --variant and --max-depth do not apply (docs/scenes.md)."""


def add_measured_arguments(parser) -> None:
    """The measured-image flags (docs/scenes.md, 'Measured spectral images')."""
    g = parser.add_argument_group("measured spectral images (SCENE a .exr, .hdr or .mat file, or a folder of PNGs)")
    g.add_argument("--illuminant", metavar="NAME|FILE.csv",
                   help="the light: lights a reflectance cube, sets the white of a radiance cube "
                        "(a colour-science name such as D65, A, FL2, or a CSV of nm,power; default: the file's, else D65)")
    g.add_argument("--quantity", choices=("radiance", "reflectance", "photons"),
                   help="what the values are (default: the file's word; else reflectance when --illuminant is given)")
    g.add_argument("--wavelengths", metavar="START:STOP:STEP|NM,NM,...",
                   help="band wavelengths in nm, for files that lack them or to override them")
    g.add_argument("--distance", type=float, metavar="M", help="scene distance in m (default: the file's, else 1.2)")
    g.add_argument("--mat-cube", metavar="VAR", help="MATLAB variable holding the rows x columns x bands cube "
                                                     "(dotted for struct fields; default: ISETCam's scene.data.photons, "
                                                     "else the only 3-D variable)")
    g.add_argument("--mat-wavelengths", metavar="VAR", help="MATLAB variable holding the wavelengths in nm")


_FLAGS = ("illuminant", "quantity", "wavelengths", "distance", "mat_cube", "mat_wavelengths")


def is_measured(args) -> bool:
    """Whether SCENE is a measured image; the measured-image flags are
    refused with any other scene (they would silently do nothing)."""
    from ..errors import CfaMitsubaError
    from ..render.measured import is_measured_image

    if is_measured_image(args.scene):
        return True
    given = [f"--{k.replace('_', '-')}" for k in _FLAGS if getattr(args, k, None) is not None]
    if given:
        raise CfaMitsubaError(f"{', '.join(given)} apply to measured spectral images (a .exr, .hdr or .mat file, "
                              f"or a folder of PNGs), not to {args.scene!r}")
    return False


def run_measured(args) -> int:
    """Convert the measured image to DIR/<name>.exr + .json (+ .png)."""
    from ..errors import CfaMitsubaError
    from ..io import check_writable_dir
    from ..render.measured import measured_cached, measured_image
    from .argtypes import check_out_dir, write_scene_files

    prog = args._prog
    ignored = [f"--{k.replace('_', '-')}" for k in ("spp", "seed", "variant", "max_depth") if getattr(args, k) is not None]
    if ignored:
        sys.stderr.write(f"{prog}: {', '.join(ignored)} ignored: a measured image is converted, not rendered\n")
    options = dict(bands=args.bands, illuminant=args.illuminant, fov=args.fov, distance=args.distance,
                   oversample=args.oversample, wavelengths=args.wavelengths, quantity=args.quantity,
                   mat_cube=args.mat_cube, mat_wavelengths=args.mat_wavelengths, width=args.width, height=args.height)
    out = Path(args.out)
    check_out_dir(out)
    if args.no_cache:
        image = measured_image(args.scene, luminance=args.luminance, **options)
    else:
        image = measured_cached(args.scene, luminance=args.luminance, **options)
    for note in image.meta.get("read_notices", []):
        sys.stderr.write(f"{prog}: {note}\n")
    k = image.meta["oversample"]
    if image.meta["width"] % k or image.meta["height"] % k:
        sys.stderr.write(f"{prog}: note: {image.meta['width']} x {image.meta['height']} is not a multiple of the "
                         f"oversampling factor K = {k}; capture and study will refuse this EXR\n")
    how = "reused the cached conversion" if image.meta.get("cache_reused") else "converted"
    sys.stderr.write(f"{prog}: {how} {image.meta['source']['what']}: {image.meta['width']} x {image.meta['height']} "
                     f"pixels, {len(image.wavelengths)} bands, mean luminance {image.meta['luminance_cd_m2']:g} cd/m^2\n")

    check_writable_dir(out, create=True)
    exr = out / f"{image.meta['scene']}.exr"
    if exr.resolve() == Path(args.scene).resolve():
        raise CfaMitsubaError(f"--out {str(out)!r} would overwrite the input {args.scene!r}: choose another folder")
    written = write_scene_files(exr, image, preview=args.preview)
    for p in written:
        print(p)
    return 0
