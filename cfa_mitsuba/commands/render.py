"""``cfa-mitsuba render SCENE --out DIR``: a scene to a spectral EXR + sidecar."""

from __future__ import annotations

import os
import sys
from pathlib import Path

from . import render_measured
from .argtypes import check_out_dir, write_scene_files

HELP = "render a scene to a spectral EXR (JCGT layout) and a sidecar JSON"

DESCRIPTION = """\
Render SCENE with Mitsuba 3 to DIR/<name>.exr (band-mean spectral radiance in
W/(m^2 sr nm), float32 channels S0.<nm>nm, exactly --width x --height) and
DIR/<name>.json (the sidecar: units, wavelengths, field of view, settings,
the scene's geometry).  SCENE is one of slanted-edge, macbeth, chirp,
gray-bar, puppy (see `cfa-mitsuba list scenes`) or a Mitsuba 3 scene FILE.xml.

Renders are cached (~/.cache/cfa-mitsuba, or $CFA_MITSUBA_CACHE) by a hash of
everything that determines them; --luminance only rescales, so it reuses the
cache.  The Mitsuba variant is cuda_ad_spectral > llvm_ad_spectral >
scalar_spectral, whichever runs here first; $CFA_MITSUBA_THREADS caps the
render's threads.  A render beyond 2^32 - 1 samples (width x height x spp),
a film beyond Dr.Jit's 2^32 - 1 values, or one whose estimated memory
exceeds the memory available ($CFA_MITSUBA_MEMORY_LIMIT, the cgroup limit or
the physical memory, whichever is smallest) is refused before Mitsuba
starts (docs/stability.md, section 11).

A scene FILE.xml is read as Mitsuba reads it (includes, <path> folders,
<default> parameters; --define NAME=VALUE sets one, as Mitsuba's -D); every
file it names must lie inside its folder or the --asset-root folder, unless
--allow-outside-paths (which opens every path).  The sidecar's field of view
is the one Mitsuba renders at --width x --height (its fov_axis applied to
that aspect ratio).  The sidecar's white_radiance is a perfect white in the
scene (--white-from; docs/scenes.md has the rule).

""" + render_measured.EPILOG


def add_arguments(parser) -> None:
    parser.add_argument("scene", metavar="SCENE", help="built-in scene name or a Mitsuba 3 scene FILE.xml")
    parser.add_argument("--out", required=True, metavar="DIR", help="output directory (created if missing)")
    parser.add_argument("--width", type=int, metavar="W", help="EXR width in pixels (default: the scene's)")
    parser.add_argument("--height", type=int, metavar="H", help="EXR height in pixels (default: the scene's)")
    parser.add_argument("--spp", type=int, metavar="N",
                        help="samples per pixel, rounded up to a square (default: the scene's)")
    parser.add_argument("--luminance", type=float, metavar="CD_M2",
                        help="mean luminance of the image in cd/m^2 (default 100)")
    parser.add_argument("--variant", metavar="V",
                        help="Mitsuba variant: cuda_ad_spectral, llvm_ad_spectral or scalar_spectral (default: best available)")
    parser.add_argument("--seed", type=int, metavar="S", help="sampler seed (default 0)")
    parser.add_argument("--bands", metavar="START:STOP:STEP", help="band centres in nm (default 400:700:10)")
    parser.add_argument("--oversample", type=int, metavar="K",
                        help="EXR pixels per sensor pixel along each axis (default: the scene's; "
                             f"{_oversampled_scenes()})")
    parser.add_argument("--fov", type=float, metavar="DEG", help="horizontal field of view of a built-in scene (degrees)")
    parser.add_argument("--max-depth", type=int, metavar="N", help="path length of a 3D scene (2: direct light only)")
    parser.add_argument("--f-number", type=float, metavar="N",
                        help="lens f-number: a 3D scene's thin lens renders with aperture radius f / 2N (default: "
                             "puppy f/2, a scene file's own aperture); recorded in the sidecar as f_number")
    parser.add_argument("--white-from", metavar="panel|illuminant|X,Y,Z", default=None,
                        help="white reference: panel (default: a perfect white panel in the scene's light), "
                             "illuminant (the panel's spectrum at the image's 99th-percentile luminance), or "
                             "X,Y,Z in cd/m^2")
    parser.add_argument("--allow-outside-paths", action="store_true",
                        help="let a scene FILE.xml name files outside its folder (refused by default)")
    parser.add_argument("--asset-root", metavar="DIR",
                        help="one shared folder a scene FILE.xml may also name files in (e.g. Mitsuba's common/)")
    parser.add_argument("--define", action="append", metavar="NAME=VALUE",
                        help="a scene FILE.xml's parameter $NAME (repeatable; as Mitsuba's -D)")
    parser.add_argument("--preview", action="store_true", help="also write DIR/<name>.png, an sRGB preview")
    parser.add_argument("--no-cache", action="store_true", help="render even if a cached render exists, and do not store it")
    parser.add_argument("--quiet", action="store_true",
                        help="no progress bar or notes on stderr: print only the files written")
    render_measured.add_measured_arguments(parser)


def _oversampled_scenes() -> str:
    """The built-in scenes rendered finer than the sensor, from the scene
    registry (never typed here: the help once said 4 for a chirp of 2)."""
    from ..render import get_scene, list_scenes

    over = [(name, get_scene(name).oversample) for name, _ in list_scenes()]
    return ", ".join(f"{k} for {name}" for name, k in over if k > 1) or "1 for every built-in scene"


def run(args) -> int:
    from ..errors import CfaMitsubaError
    from ..io import check_writable_dir
    from ..render import engine, variant

    if render_measured.is_measured(args):  # a measured spectral image: converted, not rendered
        return render_measured.run_measured(args)
    settings = dict(width=args.width, height=args.height, spp=args.spp, luminance=args.luminance,
                    variant=args.variant, seed=args.seed, bands=args.bands, oversample=args.oversample,
                    fov=args.fov, max_depth=args.max_depth, f_number=args.f_number, white_from=args.white_from,
                    allow_outside_paths=args.allow_outside_paths, defines=args.define, asset_root=args.asset_root)
    out = Path(args.out)
    check_out_dir(out)
    sc, cfg = engine.resolve_settings(args.scene, **settings)
    prog = "cfa-mitsuba render"
    lib = os.environ.get("DRJIT_LIBLLVM_PATH")
    where = f" (libLLVM {lib})" if cfg.variant.startswith("llvm") and lib else ""
    if not args.quiet:
        sys.stderr.write(f"{prog}: Mitsuba variant {cfg.variant}{where}\n")
    if cfg.variant.startswith("scalar") and args.variant is None:
        notice = variant.llvm_notice()
        if notice:
            sys.stderr.write(f"{prog}: {notice}\n")
    if cfg.width % cfg.oversample or cfg.height % cfg.oversample:
        sys.stderr.write(f"{prog}: note: {cfg.width} x {cfg.height} is not a multiple of the oversampling factor "
                         f"K = {cfg.oversample}; capture and study will refuse this EXR (the optics stage needs a whole "
                         f"number of K x K blocks per sensor pixel): pick a size divisible by {cfg.oversample}\n")
    if args.spp is not None and cfg.spp != args.spp:
        sys.stderr.write(f"{prog}: --spp {args.spp} rounded up to {cfg.spp} (the stratified sampler needs a square)\n")

    from ..io.progress import progress_bar

    bar = progress_bar(None, f"render {sc.name}", enabled=not args.quiet)

    def progress(stage: str, done: int, total: int) -> None:  # the render's stages (engine._render_canonical)
        bar.total = total
        bar.n = done
        bar.set_postfix_str(stage)

    try:
        if args.no_cache:
            image = engine.render(sc, progress=progress, **settings)
        else:
            image = engine.render_cached(sc, progress=progress, **settings)
    finally:
        bar.close()
    if args.quiet:
        pass
    elif args.no_cache:
        sys.stderr.write(f"{prog}: rendered {sc.name} in {image.meta['render_time_s']:.1f} s (cache not used)\n")
    elif image.meta.get("cache_reused"):
        sys.stderr.write(f"{prog}: reused cached render {image.meta['cache_key']} (rendered earlier in "
                         f"{image.meta['render_time_s']:.1f} s)\n")
    else:
        sys.stderr.write(f"{prog}: rendered {sc.name} in {image.meta['render_time_s']:.1f} s, cached as "
                         f"{image.meta['cache_key']}\n")

    check_writable_dir(out, create=True)
    exr = out / f"{sc.name}.exr"
    written = write_scene_files(exr, image, preview=args.preview)
    for p in written:
        print(p)
    if not exr.exists():  # pragma: no cover
        raise CfaMitsubaError(f"failed to write {str(exr)!r}")
    return 0
