"""``cfa-mitsuba sensor emva``: the EMVA 1288 measurement simulated on a
sensor, analysed by the standard's reference implementation."""

from __future__ import annotations

import argparse

from .argtypes import non_negative_int, positive_float, positive_int

HELP = "sensor characterisation: simulate the EMVA 1288 measurement of a sensor (sensor emva)"

EMVA_HELP = "simulate the EMVA 1288 measurement of a sensor and analyse it with the emva1288 package"

EMVA_DESCRIPTION = """\
Simulate the EMVA 1288 measurement on the sensor model and analyse it with
the standard's reference implementation (the optional package emva1288:
pip install 'cfa-mitsuba[emva]').

  cfa-mitsuba sensor emva --sensor imx363 --out emva-imx363/
  cfa-mitsuba sensor emva --sensor configs/sensors/mt9v024-rgb.toml --out emva-mt9v024/
  cfa-mitsuba sensor emva --cfa bayer --read-noise-e 3 --prnu-percent 1 --out emva-mine/

For each channel: uniform light in one 10-nm band (the channel's peak QE, or
--wavelength-nm), an exposure ramp past saturation with two bright and two
dark images per exposure, and at half saturation L bright and L dark images
for DSNU and PRNU.  Written per channel: DIR/<channel>/EMVA1288descriptor.txt
and DIR/<channel>/images/*.png (the layout emva1288 reads); then
DIR/emva_parameters.csv (every parameter emva1288 computes, beside the
model's set values and the relative error) and DIR/report/ (emva1288's
LaTeX report and its PDF plots; run pdflatex report.tex there for the PDF).

The analog gain is raised, as the standard asks, until the temporal dark
noise reaches 0.5 DN (--keep-gain: measure at the sensor's own gain).
docs/sensor.md, "Bring your own sensor", explains the set values.
"""


def add_arguments(parser) -> None:
    sub = parser.add_subparsers(dest="sensor_command", metavar="SUBCOMMAND", parser_class=type(parser))
    sub.required = True
    e = sub.add_parser("emva", help=EMVA_HELP, description=EMVA_DESCRIPTION,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    _emva_arguments(e)
    e.set_defaults(_prog=e.prog)


def _emva_arguments(parser) -> None:
    from .capture import add_sensor_options

    parser.add_argument("--sensor", metavar="NAME|FILE.toml",
                        help="a sensor preset (cfa-mitsuba list sensors) or a sensor file; its CFA and curves "
                             "unless --cfa / --spectra are given")
    parser.add_argument("--cfa", metavar="NAME|FILE.toml", help="CFA whose channels are measured "
                                                                 "(required unless --sensor gives one)")
    parser.add_argument("--spectra", metavar="SET", help="spectra set of the CFA's filters")
    parser.add_argument("--out", required=True, metavar="DIR", help="output folder")
    parser.add_argument("--size", type=positive_int, default=128, metavar="N",
                        help="each channel's images are N x N pixels (default 128)")
    parser.add_argument("--steps", type=positive_int, default=50, metavar="N",
                        help="exposures of the ramp up to 90 %% of saturation (default 50)")
    parser.add_argument("--fine-steps", type=positive_int, default=20, metavar="N",
                        help="further exposures from 90 %% to 105 %% of saturation (default 20)")
    parser.add_argument("--spatial-frames", type=positive_int, default=16, metavar="L",
                        help="images in each spatial stack (default 16)")
    parser.add_argument("--saturation-exposure-s", type=positive_float, default=1.0, metavar="S",
                        help="exposure at which the light saturates each channel (default 1 s)")
    parser.add_argument("--wavelength-nm", type=positive_float, metavar="NM",
                        help="light band for every channel (default: each channel's peak QE band)")
    parser.add_argument("--keep-gain", action="store_true",
                        help="measure at the sensor's own analog gain, even below 0.5 DN of dark noise")
    parser.add_argument("--seed", type=non_negative_int, default=0, help="temporal noise seed (default 0)")
    parser.add_argument("--sensor-seed", type=non_negative_int, default=None,
                        help="fixed-pattern (DSNU/PRNU) seed (default: the sensor's)")
    parser.add_argument("--no-report", action="store_true", help="skip emva1288's LaTeX report and plots")
    parser.add_argument("--quiet", action="store_true",
                        help="no progress bar or table: print only the parameters table's path")
    add_sensor_options(parser)


def run(args) -> int:
    if args.sensor_command == "emva":
        return _run_emva(args)
    raise AssertionError(args.sensor_command)  # argparse allows only the listed sub-commands


def _run_emva(args) -> int:
    from pathlib import Path

    from ..errors import CfaMitsubaError
    from ..sensor.emva import EmvaSettings, simulate_emva
    from ..sensor.emva_analysis import (PARAMETERS, UNRESOLVED, analyse_channel, parameter_rows,
                                        require_emva1288, write_parameters_csv, write_report)
    from .argtypes import check_out_dir
    from .capture import resolve_sensor

    out = Path(args.out)
    check_out_dir(out)
    require_emva1288()  # before any work
    sensor, cfa = resolve_sensor(args)
    if cfa is None:
        raise CfaMitsubaError("the ideal sensor has no pixel to measure: give a CFA")
    settings = EmvaSettings(size=args.size, steps=args.steps, fine_steps=args.fine_steps,
                            spatial_frames=args.spatial_frames, saturation_exposure_s=args.saturation_exposure_s,
                            wavelength_nm=args.wavelength_nm, analog_gain=sensor.analog_gain if args.keep_gain
                            else None, seed=args.seed)

    from ..io.progress import progress_bar

    bar = progress_bar(len(settings.ramp()) * len(cfa.channels), "emva", enabled=not args.quiet, unit="exposure")

    def progress(channel, done, total):
        bar.set_postfix_str(f"channel {channel}")
        bar.update(1)

    try:
        series = simulate_emva(sensor, cfa, out, settings, progress=progress)
    finally:
        bar.close()
    rows, measured = [], []
    for s in series:
        results, data = analyse_channel(s.folder, pixel_area_um2=sensor.pixel_pitch_um**2)
        rows += parameter_rows(s, results)
        measured.append((s, results, data))
    csv_path = write_parameters_csv(rows, out / "emva_parameters.csv")
    name = args.sensor or cfa.name
    if args.quiet:
        if not args.no_report:
            write_report(out / "report", measured, name, sensor.pixel_pitch_um)
        print(csv_path)
        return 0
    lines = [f"wrote {csv_path} and {len(series)} image series ({', '.join(s.channel for s in series)}) "
             f"under {out}"]
    if not args.no_report:
        tex = write_report(out / "report", measured, name, sensor.pixel_pitch_um)
        lines.append(f"wrote {tex} (emva1288's LaTeX report with its PDF plots; pdflatex makes the PDF)")
    lines.append(f"{'channel':<8}{'nm':>6}  " + "  ".join(f"{k:>22}" for k in PARAMETERS))
    unresolved = False
    for s in series:
        got = {r["parameter"]: r for r in rows if r["channel"] == s.channel}
        cells = []
        for k in PARAMETERS:
            r = got.get(k)
            if r and r["set_value"] != "" and r["measured"] == "":  # not resolved (emva_analysis.UNRESOLVED)
                unresolved = True
                cells.append(f"{'< noise':>10} ({r['set_value']:.4g})")
                continue
            cells.append(f"{r['measured']:>10.4g} ({r['set_value']:.4g})" if r and r["set_value"] != ""
                         else f"{'':>22}")
        lines.append(f"{s.channel:<8}{s.wavelength_nm:>6g}  " + "  ".join(f"{c:>22}" for c in cells))
    lines.append("measured (model's set value): " + ", ".join(f"{k} {u}" for k, (_, u) in PARAMETERS.items()))
    if unresolved:
        lines.append(f"< noise: {UNRESOLVED} (emva1288 gives no value; the CSV leaves it empty)")
    print("\n".join(lines))
    return 0
