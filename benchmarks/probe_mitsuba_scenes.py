"""Render other people's scenes: every scene file of a folder (Mitsuba's own
test and docs scenes, issue 27 acceptance 4), each through ``cfa-mitsuba
render`` at a small size, and check the field of view of each render.

    python benchmarks/probe_mitsuba_scenes.py FOLDER [--asset-root DIR]
        [--define spp=16] [--width 32 --height 24 --spp 16] [--out DIR] [--only LIST]

FOLDER is searched recursively for ``*.xml``; files inside folders named
``include`` or ``fragments`` are pieces of other scenes, not scenes, and
are skipped.  Each scene runs in its own ``python -m cfa_mitsuba render``
process (``--no-cache``), so a crash cannot take the probe down; a refusal
must be one line on stderr with exit status 2.

Field of view: the sidecar's ``fov_deg`` is compared with the angle between
the rays Mitsuba's own camera shoots through the middle of the film's left
and right edges (``Sensor.sample_ray``; a perspective camera with the
scene camera's ``fov``, ``fov_axis`` and ``focal_length`` on a film of the
rendered size), which does not use the project's field-of-view code.  More
than ``--fov-tolerance`` (relative, default 1e-4) apart is a failure.

Prints one line per scene (rendered, refused with its line, or failed)
and a summary: scenes, rendered, refused, failures, the share rendered,
and the load average (other processes share the cores).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

_REPO = Path(__file__).resolve().parents[1]
_FOV_KEYS = ("fov", "fov_axis", "focal_length")


def scene_files(folder: Path) -> list[Path]:
    """The scene files under ``folder`` (module docstring)."""
    return sorted(p for p in folder.rglob("*.xml")
                  if not {"include", "fragments"} & set(p.relative_to(folder).parts[:-1]))


def true_fov_deg(xml: Path, defines: list[str], width: int, height: int) -> float:
    """Horizontal field of view (degrees) Mitsuba's camera renders at
    ``width`` x ``height``: the angle between the rays through the middle
    of the film's left and right edges."""
    import mitsuba as mi

    if mi.variant() is None:
        mi.set_variant("scalar_spectral")
    params = dict(d.split("=", 1) for d in defines)
    config = mi.parser.ParserConfig(mi.variant())
    config.unused_parameters = mi.LogLevel.Debug  # the same --define serves every scene
    state = mi.parser.parse_file(config, str(xml), **params)
    mi.parser.transform_upgrade(config, state)
    sensor = next(n for n in state.nodes if n.type == mi.ObjectType.Sensor)
    cam = {"type": "perspective", "film": {"type": "hdrfilm", "width": width, "height": height}}
    for key in _FOV_KEYS:
        if key in sensor.props.keys():
            cam[key] = sensor.props[key]
    s = mi.load_dict(cam)
    dirs = []
    for x in (0.0, 1.0):
        ray, _ = s.sample_ray(0.0, 0.5, mi.Point2f(x, 0.5), mi.Point2f(0.5, 0.5))
        dirs.append([float(v) for v in ray.d])
    cos = sum(a * b for a, b in zip(*dirs)) / math.prod(math.sqrt(sum(v * v for v in d)) for d in dirs)
    return math.degrees(math.acos(max(-1.0, min(1.0, cos))))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("folder", type=Path)
    ap.add_argument("--asset-root", type=Path)
    ap.add_argument("--define", action="append", default=None)
    ap.add_argument("--width", type=int, default=32)
    ap.add_argument("--height", type=int, default=24)
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--timeout", type=float, default=600.0, help="seconds per scene")
    ap.add_argument("--fov-tolerance", type=float, default=1e-4)
    ap.add_argument("--out", type=Path, help="keep the renders here (default: a temporary folder)")
    ap.add_argument("--only", type=Path, metavar="LIST",
                    help="probe only the scene files named in LIST (one path relative to FOLDER per line)")
    args = ap.parse_args(argv)
    defines = args.define if args.define is not None else ["spp=16"]
    files = scene_files(args.folder)
    if args.only is not None:
        wanted = {ln.strip() for ln in args.only.read_text().splitlines() if ln.strip()}
        files = [f for f in files if str(f.relative_to(args.folder)) in wanted]
    out = args.out or Path(tempfile.mkdtemp(prefix="probe-scenes-"))
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(_REPO), os.environ.get("PYTHONPATH", "")])}
    rendered, refused, failed = [], [], []
    t0 = time.time()
    for f in files:
        name = str(f.relative_to(args.folder))
        cmd = [sys.executable, "-m", "cfa_mitsuba", "render", str(f), "--out", str(out / f.stem), "--no-cache",
               "--width", str(args.width), "--height", str(args.height), "--spp", str(args.spp)]
        cmd += [f"--define={d}" for d in defines]
        if args.asset_root:
            cmd += ["--asset-root", str(args.asset_root)]
        try:
            proc = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=args.timeout,
                                  stdin=subprocess.DEVNULL)
        except subprocess.TimeoutExpired:
            failed.append((name, f"timed out after {args.timeout:g} s"))
            print(f"FAILED   {name}: timed out", flush=True)
            continue
        errors = [ln for ln in proc.stderr.splitlines() if "error" in ln.lower() or "Traceback" in ln]
        if proc.returncode == 2 and len(errors) == 1 and "Traceback" not in proc.stderr:
            refused.append((name, errors[0]))
            print(f"REFUSED  {name}: {errors[0]}", flush=True)
            continue
        if proc.returncode != 0:
            failed.append((name, f"exit {proc.returncode}: {proc.stderr.strip().splitlines()[-1:]}"))
            print(f"FAILED   {name}: exit {proc.returncode}: {proc.stderr.strip()[-300:]}", flush=True)
            continue
        meta = json.loads((out / f.stem / f"{f.stem}.json").read_text())
        want = true_fov_deg(f, defines, args.width, args.height)
        got = float(meta["fov_deg"])
        if abs(got - want) > args.fov_tolerance * want:
            failed.append((name, f"sidecar fov {got:.6g} deg, Mitsuba renders {want:.6g} deg"))
            print(f"FAILED   {name}: sidecar fov {got:.6g} deg, Mitsuba renders {want:.6g} deg", flush=True)
            continue
        rendered.append(name)
        print(f"RENDERED {name}: fov {got:.4f} deg (Mitsuba's camera {want:.4f})", flush=True)
    n = len(files)
    print(f"\nscenes {n}, rendered with the right field of view {len(rendered)} ({100 * len(rendered) / max(n, 1):.1f} %), "
          f"refused {len(refused)}, failed {len(failed)}; {time.time() - t0:.0f} s, "
          f"load average {os.getloadavg()[0]:.2f}")
    for name, why in refused:
        print(f"  refused {name}: {why}")
    for name, why in failed:
        print(f"  failed  {name}: {why}")
    return 0 if not failed else 1


if __name__ == "__main__":
    sys.exit(main())
