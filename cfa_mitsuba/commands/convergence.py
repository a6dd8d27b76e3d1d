"""``cfa-mitsuba convergence SCENE [--out DIR ...]``: error against run time."""

from __future__ import annotations

from .argtypes import non_negative_int, positive_int

HELP = "error against run time: render spp and POCS iterations against a high-quality reference"

DESCRIPTION = """\
Render SCENE at increasing samples per pixel and report, against a reference
(the mean of two independent renders at --reference-spp each, seeds
SEED+1 and SEED+2; half their difference is the reference's own noise):

  (a) the radiance error per band: rms over the image of (render -
      reference) / mean, and the same over the scene's most uniform window;
  (b) every metric the scene feeds (render -> optics -> capture with --cfa ->
      --demosaic -> metric against the ideal sensor, as a study does),
      as its deviation from the reference's value;

each against the measured wall time of the whole render.  The processing
side: POCS at each of --pocs-iterations against a converged POCS
(--pocs-reference iterations, tolerance 0) on one noisy capture, against
processing time.  For context, each metric's spread across --compare-cfas
and its sensor-noise spread over --noise-seeds seeds.

Writes DIR/convergence_<scene>.csv (tidy: scene, stage, quality, wall_s,
quantity, error, unit, value), .json (reference, fitted rates, checks) and a
log-log plot .png + .svg; prints a short table; progress on stderr.

Defaults: the scene's size (path-traced scenes: a third of it per side),
spp = powers of 4 up to 4x the scene's default plus the default, reference
16x the default spp.  Timings depend on the machine and its load: compare
ratios.  docs/convergence.md has the measured tables for every built-in scene.

Examples:
  cfa-mitsuba convergence macbeth --out results/convergence
  cfa-mitsuba convergence puppy --width 120 --height 106 --spp 1,4,16 --reference-spp 256
  cfa-mitsuba convergence my_scene.xml --spp 4,16,64 --pocs-iterations 1,4,16
"""


def _int_list(text: str) -> list[int]:
    import argparse

    parts = [t.strip() for t in str(text).split(",")]
    try:
        vals = [int(t) for t in parts]
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be comma-separated whole numbers, got {text!r}") from None
    if any(v < 1 for v in vals):
        raise argparse.ArgumentTypeError(f"every value must be at least 1, got {text!r}")
    if any(b <= a for a, b in zip(vals, vals[1:])):
        raise argparse.ArgumentTypeError(f"values must increase strictly, got {text!r}")
    return vals


def _name_list(text: str) -> list[str]:
    if str(text).strip().lower() in ("", "none"):
        return []
    return [t.strip() for t in str(text).split(",") if t.strip()]


def add_arguments(parser) -> None:
    parser.add_argument("scene", metavar="SCENE", help="a built-in scene (cfa-mitsuba list scenes) or FILE.xml")
    parser.add_argument("--out", metavar="DIR", default="results/convergence",
                        help="output directory (default: results/convergence)")
    parser.add_argument("--width", type=positive_int, metavar="W", help="EXR width in pixels")
    parser.add_argument("--height", type=positive_int, metavar="H", help="EXR height in pixels")
    parser.add_argument("--spp", type=_int_list, metavar="N,N,...",
                        help="increasing samples per pixel (rounded up to squares, as the stratified sampler does)")
    parser.add_argument("--reference-spp", type=positive_int, metavar="N",
                        help="spp of each of the two reference renders (default 16x the scene's default)")
    parser.add_argument("--pocs-iterations", type=_int_list, metavar="N,N,...",
                        help="increasing POCS iteration counts (default 1,2,4,8,10,16,32)")
    parser.add_argument("--pocs-reference", type=positive_int, default=50, metavar="N",
                        help="iterations of the converged POCS, tolerance 0 (default 50)")
    parser.add_argument("--cfa", default="bayer", metavar="NAME|FILE.toml", help="CFA (default bayer)")
    parser.add_argument("--demosaic", default="bilinear", metavar="NAME",
                        help="demosaicing method of the render stage (default bilinear)")
    parser.add_argument("--compare-cfas", type=_name_list, default=None, metavar="A,B,...|none",
                        help="CFAs whose metric spread is reported (default bayer,rgb3,cmy1,rgbw1)")
    parser.add_argument("--render-noise", choices=("off", "shot", "all"), default="off",
                        help="sensor noise in the render stage's captures (default off: the sensor's noise "
                             "realisation changes with any change of the signal, see --help's docs)")
    parser.add_argument("--noise-seeds", type=non_negative_int, default=4, metavar="N",
                        help="seeds for each metric's sensor-noise spread (default 4; 0: skip)")
    parser.add_argument("--default-seeds", type=non_negative_int, default=3, metavar="N",
                        help="extra renders of the default spp with other seeds, for the rms deviation the check "
                             "uses (default 3; 0: skip)")
    parser.add_argument("--seed", type=non_negative_int, default=0, metavar="S",
                        help="render seed of the levels (the reference uses S+1 and S+2) and study seed (default 0)")
    parser.add_argument("--luminance", type=float, default=100.0, metavar="CD_M2",
                        help="mean scene luminance, cd/m^2 (default 100)")
    parser.add_argument("--repeat", type=positive_int, default=2, metavar="N",
                        help="runs per level for timing, the fastest counts (default 2: the first compiles)")
    parser.add_argument("--variant", metavar="V", help="Mitsuba variant (default: the best available)")
    parser.add_argument("--formats", type=_name_list, default=["png", "svg"], metavar="png,svg",
                        help="plot formats (default png,svg)")
    parser.add_argument("--quiet", action="store_true",
                        help="no progress bar, log lines or table: print only the paths written")


def run(args) -> int:
    from ..errors import CfaMitsubaError
    from ..io import check_writable_dir
    from ..report.convergence import write_convergence
    from ..study.convergence import DEFAULT_COMPARE_CFAS, format_table, make_plan, run_convergence

    for f in args.formats:
        if f not in ("png", "svg"):
            raise CfaMitsubaError(f"--formats: must be png and/or svg, got {f!r}")
    plan = make_plan(
        args.scene, width=args.width, height=args.height, spp=args.spp, reference_spp=args.reference_spp,
        pocs_iterations=args.pocs_iterations, pocs_reference_iterations=args.pocs_reference, cfa=args.cfa,
        demosaic=args.demosaic, seed=args.seed, luminance=args.luminance, render_noise=args.render_noise,
        repeat=args.repeat, compare_cfas=DEFAULT_COMPARE_CFAS if args.compare_cfas is None else args.compare_cfas,
        noise_seeds=args.noise_seeds, default_seeds=args.default_seeds, variant=args.variant,
    )
    check_writable_dir(args.out)  # before minutes of rendering, not after
    from ..io.progress import stderr_log

    result = run_convergence(plan, log=stderr_log(args.quiet), progress=not args.quiet)
    paths = write_convergence(result, args.out, formats=tuple(args.formats))
    if not args.quiet:
        print(format_table(result))
    for kind in ("csv", "json", *args.formats):
        print(paths[kind])
    return 0
