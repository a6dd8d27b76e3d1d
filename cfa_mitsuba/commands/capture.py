"""``cfa-mitsuba capture``: a spectral EXR through the lens and a sensor to a
raw mosaic (or the ideal XYZ image) in a ``.npz``."""

from __future__ import annotations

import argparse
import math
import sys

from ..errors import one_line
from .argtypes import non_negative_float, non_negative_int, positive_float, positive_int

HELP = "capture a spectral EXR with a CFA sensor (or the ideal XYZ sensor) into a raw .npz"

DESCRIPTION = """\
Capture a spectral EXR (JCGT layout; its sidecar JSON is used when present)
through a diffraction-limited lens and a sensor with the given CFA.

  cfa-mitsuba capture scene.exr --cfa bayer --out bayer.npz
  cfa-mitsuba capture scene.exr --cfa ideal --out ideal.npz
  cfa-mitsuba capture scene.exr --cfa my_cfa.toml --luminance 12 --noise all --out dim.npz
  cfa-mitsuba capture scene.exr --sensor imx363 --out imx363.npz
  cfa-mitsuba capture scene.exr --cfa cmy1 --spectra nikon-d5100 --out cmy1_nikon.npz

--sensor NAME starts from a measured preset (cfa-mitsuba list sensors): its
pixel, its CFA unless --cfa is given, and its spectra set unless --spectra
is given; the sensor options below override single values.  --sensor
FILE.toml reads a sensor file (QE curves in CSV plus datasheet or EMVA 1288
numbers; docs/sensor.md, "Bring your own sensor") the same way.

Without --luminance the EXR's radiance is kept.  --exposure auto runs the
exposure program (--exposure-policy program, the default): the brightest
pixel's well to 95 % at the captured luminance, the time capped at
--max-exposure-s, then analogue gain up to --max-analog-gain, then digital
gain (defaults in --help).  --exposure-policy reference (or --reference-luminance)
chooses ISETCam's exposure at the reference luminance (see --help) and keeps
it at any --luminance; each: ISETCam's at the captured luminance; bayer:
the program's time and gains for Bayer (docs/sensor.md s. 3.2).  The lens (field of view, distance, f-number) and the
oversampling come from the options, else from the sidecar, else from the
documented defaults (docs/sensor.md).  --oversample must divide the EXR's
width and height (a remainder is refused, not cropped).
"""


def _exposure(text: str):
    if text.strip().lower() == "auto":
        return "auto"
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a time in seconds or 'auto', got {text!r}") from None
    if not (math.isfinite(v) and v > 0):
        raise argparse.ArgumentTypeError(f"must be a positive time in seconds or 'auto', got {text!r}")
    return v


def _distance(text: str) -> float:
    if text.strip().lower() in ("inf", "infinity"):
        return math.inf
    return positive_float(text)


def add_arguments(parser) -> None:
    parser.add_argument("exr", metavar="EXR", help="spectral EXR (JCGT layout), sidecar JSON beside it optional")
    parser.add_argument("--cfa", metavar="NAME|FILE.toml|ideal",
                        help="a built-in CFA (cfa-mitsuba list cfas), a CFA TOML file, or 'ideal' (XYZ reference); "
                             "required unless --sensor gives one")
    parser.add_argument("--spectra", metavar="SET",
                        help="spectra set of the CFA's filters (cfa-mitsuba list spectra; default: the CFA's own, "
                             "or the --sensor preset's)")
    parser.add_argument("--sensor", metavar="NAME|FILE.toml",
                        help="a measured sensor preset (cfa-mitsuba list sensors) or a sensor file "
                             "(docs/sensor.md, 'Bring your own sensor'): pixel, CFA and spectra")
    parser.add_argument("--out", required=True, metavar="RAW.npz", help="output raw file (.npz), written atomically")
    parser.add_argument("--luminance", type=positive_float, metavar="CD_M2",
                        help="scale the scene to this mean luminance (default: keep the EXR's radiance)")
    parser.add_argument("--exposure", type=_exposure, default="auto", metavar="S|auto",
                        help="exposure in seconds, or auto (default)")
    # the policies and the program's defaults are ExposureProgram's (checked when the command runs, so that
    # building the parser imports no stage)
    parser.add_argument("--reference-luminance", type=positive_float, default=None, metavar="CD_M2",
                        help="for --exposure-policy reference: the mean luminance at which auto exposure is chosen "
                             "(default: the exposure program's; giving it selects that policy)")
    parser.add_argument("--exposure-policy", default=None, metavar="POLICY",
                        help="how --exposure auto chooses the time and gains: program (the default), bayer, "
                             "reference or each (docs/sensor.md s. 3.2)")
    parser.add_argument("--max-exposure-s", type=positive_float, default=None, metavar="S",
                        help="the program's longest exposure (default: a 30 frame/s video frame)")
    parser.add_argument("--max-analog-gain", type=positive_float, default=None, metavar="G",
                        help="the program's highest analogue gain, >= 1 (default: ISO 100 -> 1600)")
    parser.add_argument("--noise", choices=("off", "shot", "all"), default="all",
                        help="off: none; shot: photon noise only, no ADC; all (default): the full sensor")
    parser.add_argument("--oversample", type=positive_int, metavar="K",
                        help="EXR pixels per sensor pixel along each axis (default: the sidecar's, else 1)")
    parser.add_argument("--seed", type=non_negative_int, default=0, help="temporal noise seed (default 0)")
    parser.add_argument("--illuminant", metavar="NAME|FILE.csv",
                        help="light of an EXR without our sidecar (another tool's): its white reference, and the light "
                             "of a reflective (T.) file; a colour-science name or a CSV of nm,power (default: the "
                             "file's 'illuminant' attribute, else D65; stderr says which)")
    parser.add_argument("--sensor-seed", type=non_negative_int, default=None,
                        help="fixed-pattern (DSNU/PRNU) seed: one seed is one sensor (default 0)")
    g = parser.add_argument_group("lens (defaults: f/4, T = 1, relative illumination and diffraction on)")
    g.add_argument("--f-number", type=positive_float, metavar="N",
                   help="f-number (overrides the sidecar's f_number; default 4)")
    g.add_argument("--lens-transmittance", type=positive_float, default=1.0, metavar="T", help="in (0, 1]")
    g.add_argument("--no-relative-illumination", action="store_true", help="no off-axis falloff")
    g.add_argument("--no-diffraction", action="store_true", help="no diffraction OTF")
    g.add_argument("--fov-deg", type=positive_float, metavar="DEG",
                   help="horizontal field of view (overrides the sidecar; default 10)")
    g.add_argument("--scene-distance-m", type=_distance, metavar="M",
                   help="scene distance, or inf (overrides the sidecar; default 1.2)")
    add_sensor_options(parser)


def add_sensor_options(parser) -> None:
    """The pixel and read-out options (each overrides one SensorParams value;
    shared with ``sensor emva``)."""
    s = parser.add_argument_group("sensor (defaults in docs/sensor.md)")
    s.add_argument("--pixel-pitch-um", type=positive_float, metavar="UM", help="default 2.2")
    s.add_argument("--fill-factor", type=positive_float, metavar="F", help="in (0, 1], default 1")
    s.add_argument("--well-capacity-e", type=positive_float, metavar="E", help="default 6200")
    s.add_argument("--read-noise-e", type=non_negative_float, metavar="E", help="rms, default 6.2")
    s.add_argument("--dark-current-e-s", type=non_negative_float, metavar="E_S", help="default 6.2")
    s.add_argument("--dsnu-e", type=non_negative_float, metavar="E", help="rms, default 0")
    s.add_argument("--prnu-percent", type=non_negative_float, metavar="PCT", help="rms, default 0")
    s.add_argument("--analog-gain", type=positive_float, metavar="G", help="default 1")
    s.add_argument("--adc-bits", type=positive_int, metavar="BITS", help="default 12")
    s.add_argument("--black-level-dn", type=non_negative_float, metavar="DN", help="default 64")
    s.add_argument("--readout", choices=("full", "remosaic", "bin"),
                   help="full (default), remosaic (the ISP rearranges to Bayer), bin (one pixel per same-colour "
                        "block); remosaic and bin need a block layout (quad-bayer, nona, tetra2)")
    s.add_argument("--binning", choices=("charge", "digital"), help="for --readout bin: charge (default) or digital")
    s.add_argument("--crosstalk", type=non_negative_float, metavar="FRACTION",
                   help="fraction of each pixel's electrons that lands in its 4 neighbours (default 0)")
    s.add_argument("--ir-cut", metavar="none|FILE.csv",
                   help="IR-cut filter in place of the spectra set's common one (default: the set's own)")


_SENSOR_OPTIONS = ("pixel_pitch_um", "fill_factor", "well_capacity_e", "read_noise_e", "dark_current_e_s", "dsnu_e",
                   "prnu_percent", "analog_gain", "adc_bits", "black_level_dn", "sensor_seed", "readout", "binning",
                   "crosstalk", "ir_cut")


def resolve_sensor(args):
    """(SensorParams, CFA or None for 'ideal') from ``--sensor`` (a preset
    name or a sensor file), ``--cfa``, ``--spectra`` and the sensor options;
    a bad CFA fails here, before any file is read."""
    from ..errors import CfaMitsubaError
    from ..sensor import SensorParams, get_cfa, get_sensor_preset

    preset = get_sensor_preset(args.sensor) if args.sensor else None
    base = preset.params if preset else SensorParams()
    sensor = base.with_(**{k: getattr(args, k) for k in _SENSOR_OPTIONS})
    cfa_name = args.cfa or (preset.cfa_name if preset else None)
    if cfa_name is None:
        raise CfaMitsubaError("--cfa is required (or --sensor NAME, whose CFA is used)")
    if cfa_name == "ideal":
        if args.spectra:
            raise CfaMitsubaError("--spectra does not apply to the ideal sensor (CIE 1931 XYZ)")
        return sensor, None
    own = preset is not None and preset.own_cfa is not None and not args.spectra \
        and not str(args.cfa or "").lower().endswith(".toml")  # a sensor file's own QE curves
    if own:
        return sensor, preset.cfa(args.cfa)
    return sensor, get_cfa(cfa_name, spectra=args.spectra or (preset.spectra if preset else None) or None)


def _check_output(out, given: str) -> None:
    """Refuse an output that cannot be written, before any work and without
    creating anything (the atomic writer creates missing folders later)."""
    import os

    from ..errors import CfaMitsubaError

    if out.suffix.lower() != ".npz":
        raise CfaMitsubaError(f"--out {given!r} must end with .npz")
    if out.is_dir():
        raise CfaMitsubaError(f"--out {given!r} is a directory")
    parent = out.parent if str(out.parent) else out.__class__(".")
    probe = parent
    while not probe.exists():
        if probe.parent == probe:
            break
        probe = probe.parent
    if not probe.is_dir():
        raise CfaMitsubaError(f"--out {given!r}: {str(probe)!r} is not a directory")
    if not os.access(probe, os.W_OK | os.X_OK):
        raise CfaMitsubaError(f"--out {given!r}: directory {str(probe)!r} is not writable")


def run(args) -> int:
    import warnings
    from pathlib import Path

    from ..errors import CfaMitsubaError
    from ..io.raw_npz import save_raw_npz
    from ..optics import OpticsParams, compute_optics
    from ..sensor import ExposureProgram, capture, capture_ideal

    out = Path(args.out)
    _check_output(out, args.out)

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        sensor, cfa = resolve_sensor(args)
        ideal = cfa is None
        optics = OpticsParams(f_number=args.f_number, lens_transmittance=args.lens_transmittance,
                              relative_illumination=not args.no_relative_illumination,
                              diffraction=not args.no_diffraction, fov_deg=args.fov_deg,
                              scene_distance_m=args.scene_distance_m)
        try:
            from ..io import read_spectral_exr
        except ImportError:  # the render stage's reader (cfa_mitsuba/io/exr.py)
            raise CfaMitsubaError("reading spectral EXRs needs cfa_mitsuba.io.read_spectral_exr, "
                                  "which this installation lacks") from None
        from ..io.exr import check_capture_file
        from ..io.illuminant import resolve_illuminant

        check_capture_file(args.exr)  # memory, from the EXR's header, before the cube is read
        light = resolve_illuminant(args.illuminant) if args.illuminant else None
        scene = read_spectral_exr(args.exr, illuminant=light)
        oi = compute_optics(scene, optics, pixel_pitch_um=sensor.pixel_pitch_um, oversample=args.oversample,
                            fill_factor=sensor.fill_factor)
        if ideal:
            raw = capture_ideal(oi, luminance_cd_m2=args.luminance, exposure_s=args.exposure, sensor=sensor)
        else:
            program = ExposureProgram.from_keywords(
                args.exposure_policy, args.reference_luminance, reference_given=args.reference_luminance is not None,
                max_exposure_s=args.max_exposure_s, max_analog_gain=args.max_analog_gain)
            raw = capture(oi, cfa, luminance_cd_m2=args.luminance, exposure_s=args.exposure, noise=args.noise,
                          seed=args.seed, sensor=sensor, exposure_program=program)
        save_raw_npz(out, raw)
    for w in caught:
        sys.stderr.write(f"{args._prog}: warning: {one_line(w.message)}\n")

    st, meta, opt = raw.settings, raw.meta, raw.meta["optics"]
    h, w = raw.raw.shape[:2]
    k = meta["oversample"]
    spec = f", spectra {st['cfa']['spectra']}" if st["cfa"].get("spectra") else ""
    lines = [f"wrote {out}: {st['cfa']['name']} ({st['cfa']['tile']}{spec}), {w} x {h} pixels of "
             f"{sensor.pixel_pitch_um:g} um from {w * k} x {h * k} EXR pixels (K = {k}, {meta['oversample_source']})"]
    lens = (f"lens f/{opt['f_number']:g} ({opt['f_number_source']}; working f/{opt['working_f_number']:.4g}), "
            f"focal length "
            f"{opt['focal_length_mm']:.4g} mm, FOV {opt['fov_deg']:g} deg ({opt['fov_source']}), "
            f"distance {opt['scene_distance_m']} m ({opt['scene_distance_source']})")
    lines.append("  " + lens)
    if args.sensor:
        lines.append(f"  sensor preset {args.sensor}: {sensor.pixel_pitch_um:g} um, well {sensor.well_capacity_e:.0f} e-, "
                     f"read noise {sensor.read_noise_e:.3g} e-, {sensor.adc_bits} bit")
    if ideal:
        y = raw.raw[..., 1]
        lines.append(f"  luminance {meta['luminance_cd_m2']:.4g} cd/m^2{_lux(meta)}; XYZ absolute (Y cd/m^2): "
                     f"mean Y {y.mean():.4g}, max Y {y.max():.4g}")
    else:
        mode = "fixed" if st["exposure_mode"] != "auto" else (
            f"auto at {st['reference_luminance_cd_m2']:g} cd/m^2" if st["exposure_policy"] == "reference" else
            f"{st['exposure_policy']}: analogue gain {st['analog_gain']:.3g}, digital gain {st['digital_gain']:.3g}")
        clipped = 100.0 * meta["saturated_fraction"]
        lines.append(f"  luminance {meta['luminance_cd_m2']:.4g} cd/m^2{_lux(meta)}, exposure {raw.exposure_s * 1e3:.4g} "
                     f"ms ({mode}), {meta['sensor_exposure_lux_s']:.4g} lux s on the sensor, noise {args.noise}, "
                     f"seed {raw.seed}")
        lines.append(f"  raw {raw.raw.min():.6g}..{raw.raw.max():.6g} DN (black level {raw.black_level_dn:g}, "
                     f"{raw.dn_per_electron:.4g} DN/e-), {clipped:.2f} % of wells full")
    print("\n".join(lines))
    return 0


def _lux(meta: dict) -> str:
    """The scene's illuminance beside its luminance: pi x the white's
    luminance (sensor/photometry.py)."""
    lux = meta.get("scene_illuminance_lux")
    return f" (scene illuminance {lux:.4g} lux)" if lux else ""
