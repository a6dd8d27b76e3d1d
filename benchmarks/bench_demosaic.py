"""Demosaicing benchmark: PSNR and time of every method on every CFA, and
speed against colour-demosaicing on a 636 x 720 Bayer mosaic.

    python benchmarks/bench_demosaic.py [--quick] [--repeat N] [--new-layouts-only] [--scielab-only]
        [--bayer-only] [--cfas A,B,...] [--json PATH]

``--json PATH`` also writes the measured numbers (PSNR per CFA, method and
photograph, the speed table, load average, code commit) to PATH: README.md
takes its demosaicing numbers from the committed docs/data/bench_demosaic.json
(``python benchmarks/bench_demosaic.py --bayer-only --json
docs/data/bench_demosaic.json``, about a minute); ``--cfas A,B,...`` (PSNR
tables of those CFAs only) and ``--scielab-only`` add their numbers to an
existing PATH, so the full tables of docs/isp.md are filled in runs of a
few minutes each.

Images: scikit-image's bundled photographs (astronaut, coffee, chelsea,
rocket), 8-bit sRGB values / 255 taken as the scene, as the demosaicing
literature does with Kodak; an 8-pixel border is excluded from PSNR.
RGB CFAs are scored on R, G, B; the CMY and RGBW CFAs on their own
white-balanced channels (``cm.isp.channels_from_rgb``).  The layouts of
today's sensors (quad-bayer ... mono, issue 16) are scored the same way:
the RGB ones on R, G, B, the others on their own channels.  Times are the
minimum over ``--repeat`` runs (wall clock, one process): compare ratios
within one run, since other processes share the machine.

S-CIELAB section (Bayer): the photographs decoded from sRGB to linear
light and taken to CIE XYZ (colour-science), mosaicked, demosaicked, and
compared with the original by S-CIELAB (CIEDE2000, D65 white) at two viewing
geometries: 23 samples per degree (a 720-pixel image seen over 31 degrees,
or the quick study's 240 pixels over 10) and 72 (the paper's PUPPY, 720
pixels over 10 degrees).  At 72 samples per degree S-CIELAB's filters
remove detail finer than about 10 pixels, where demosaicking errors live:
docs/scenes.md uses this table to explain the puppy's S-CIELAB ranking.
"""

from __future__ import annotations

import argparse
import os
import platform
import time
import warnings

import numpy as np

warnings.simplefilter("ignore")

import cfa_mitsuba as cm  # noqa: E402

METHODS = ("bilinear", "laplacian", "adaptive-laplacian", "pocs")
PHOTOS = ("astronaut", "coffee", "chelsea", "rocket")
RGB_CFAS = ("bayer", "rgb1", "rgb2", "rgb3", "rgb4", "rgb5")
OTHER_CFAS = ("cmy1", "cmy2", "cmy3", "rgbw1", "rgbw2", "rgbw3")
NEW_RGB_CFAS = ("quad-bayer", "nona", "tetra2", "xtrans")
NEW_OTHER_CFAS = ("ryyb", "rccb", "rccc", "kodak-cfa3", "sony-rgbw")  # mono: nothing to demosaic
BORDER = 8
#: the suffix of a speed row timed with ``precision='single'``
SINGLE = ", single precision"


def best_time(fn, repeat):
    from cfa_mitsuba.isp._memo import clear_all

    fn()  # warm caches (stencils, colour data)
    times = []
    for _ in range(repeat):
        clear_all()  # each method on its own: not the bilinear image or reference a previous call kept
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return min(times)


def psnr(truth, out):
    from skimage.metrics import peak_signal_noise_ratio

    b = BORDER
    return peak_signal_noise_ratio(truth[b:-b, b:-b], out[b:-b, b:-b], data_range=1.0)


def photos(quick):
    import skimage.data

    imgs = {n: getattr(skimage.data, n)() / 255.0 for n in PHOTOS}
    if quick:
        imgs = {n: im[:192, :192] for n, im in imgs.items()}
    return imgs


#: what --json writes: filled by the tables as they print
RESULTS: dict = {"psnr_db": {}, "time_per_image_s": {}, "speed_s": {}}


def quality_table(cfas, imgs, repeat, rgb: bool):
    print(f"| CFA | method | {' | '.join(imgs)} | mean PSNR (dB) | time per image (s) |")
    print("|---|---|" + "---|" * len(imgs) + "---|---|")
    for name in cfas:
        cfa = cm.sensor.get_cfa(name)
        truths = {n: (im if rgb else cm.isp.channels_from_rgb(im, cfa)) for n, im in imgs.items()}
        raws = {n: cm.isp.mosaic_image(t, cfa) for n, t in truths.items()}
        for method in METHODS:
            vals, times = [], []
            for n in imgs:
                out = cm.isp.demosaic(raws[n], cfa, method)
                vals.append(psnr(truths[n], out))
                times.append(best_time(lambda: cm.isp.demosaic(raws[n], cfa, method), repeat))
            print(f"| {name} | {method} | " + " | ".join(f"{v:.2f}" for v in vals)
                  + f" | {np.mean(vals):.2f} | {np.mean(times):.3f} |")
            RESULTS["psnr_db"].setdefault(name, {})[method] = {**dict(zip(imgs, vals)), "mean": float(np.mean(vals))}
            RESULTS["time_per_image_s"].setdefault(name, {})[method] = float(np.mean(times))
        if name == "bayer" and rgb:
            import colour_demosaicing as cdm

            for label, fn in (("colour-demosaicing Malvar2004", cdm.demosaicing_CFA_Bayer_Malvar2004),
                              ("colour-demosaicing Menon2007", cdm.demosaicing_CFA_Bayer_Menon2007)):
                vals = [psnr(im, fn(raws[n], "GRBG")) for n, im in imgs.items()]
                RESULTS.setdefault("library_psnr_db", {})[label] = {**dict(zip(imgs, vals)), "mean": float(np.mean(vals))}
                print(f"| {name} | *{label}* | " + " | ".join(f"{v:.2f}" for v in vals) + f" | {np.mean(vals):.2f} | |")


def scielab_table(imgs):
    import colour

    from cfa_mitsuba.metrics.scielab import scielab

    white = 100.0 * colour.xy_to_XYZ(colour.CCS_ILLUMINANTS["CIE 1931 2 Degree Standard Observer"]["D65"])
    print(f"| method | spd | {' | '.join(imgs)} | mean dE00 | rank of bilinear |")
    print("|---|---|" + "---|" * len(imgs) + "---|---|")
    refs, outs = [], {m: [] for m in METHODS}  # XYZ of each photograph and of each method's output
    for im in imgs.values():
        linear = colour.cctf_decoding(im[..., :3], "sRGB")
        refs.append(100.0 * colour.RGB_to_XYZ(linear, "sRGB"))
        raw = cm.isp.mosaic_image(linear, "bayer")
        for method in METHODS:
            out = np.clip(cm.isp.demosaic(raw, "bayer", method), 0.0, None)
            outs[method].append(100.0 * colour.RGB_to_XYZ(out, "sRGB"))
    for spd in (23, 72):
        table = {m: [float(scielab(r, o, white, samples_per_degree=spd).value) for r, o in zip(refs, outs[m])]
                 for m in METHODS}
        RESULTS.setdefault("scielab_de00", {})[str(spd)] = {m: {**dict(zip(imgs, v)), "mean": float(np.mean(v))}
                                                            for m, v in table.items()}
        ranks = [1 + sum(table[m][k] < table["bilinear"][k] for m in METHODS) for k in range(len(refs))]
        for method in METHODS:
            vals = table[method]
            note = " ".join(f"{r}/{len(METHODS)}" for r in ranks) if method == "bilinear" else ""
            print(f"| {method} | {spd} | " + " | ".join(f"{v:.3f}" for v in vals) + f" | {np.mean(vals):.3f} | {note} |")


def speed_table(repeat):
    import colour_demosaicing as cdm
    import skimage.data
    from skimage.transform import resize

    img = resize(skimage.data.coffee() / 255.0, (636, 720), order=1, anti_aliasing=False)
    raw = cm.isp.mosaic_image(img, "bayer")
    rows = {
        "bilinear": lambda: cm.isp.demosaic(raw, "bayer", "bilinear"),
        "colour-demosaicing bilinear": lambda: cdm.demosaicing_CFA_Bayer_bilinear(raw, "GRBG"),
        "laplacian": lambda: cm.isp.demosaic(raw, "bayer", "laplacian"),
        "colour-demosaicing Malvar2004": lambda: cdm.demosaicing_CFA_Bayer_Malvar2004(raw, "GRBG"),
        "adaptive-laplacian": lambda: cm.isp.demosaic(raw, "bayer", "adaptive-laplacian"),
        "pocs": lambda: cm.isp.demosaic(raw, "bayer", "pocs"),
        "pocs, 10 iterations (tolerance 0)": lambda: cm.isp.demosaic(raw, "bayer", "pocs", tolerance=0.0),
        "colour-demosaicing Menon2007": lambda: cdm.demosaicing_CFA_Bayer_Menon2007(raw, "GRBG"),
    }
    for m in METHODS:  # the same methods computing in float32 (a study's default, [isp] demosaic_precision)
        rows[f"{m}{SINGLE}"] = (lambda m=m: cm.isp.demosaic(raw, "bayer", m, precision="single"))
    t = {k: best_time(f, repeat) for k, f in rows.items()}
    info = {}
    cm.isp.demosaic(raw, "bayer", "pocs", info=info)
    RESULTS["speed_s"] = t
    RESULTS["speedup"] = {k: t[v] / t[k] for k, v in (("bilinear", "colour-demosaicing bilinear"),
                                                       ("laplacian", "colour-demosaicing Malvar2004"))}
    RESULTS["pocs_iterations"] = info["iterations"]
    print("| 636 x 720 Bayer mosaic | time (s) | ratio |")
    print("|---|---|---|")
    pairs = {"bilinear": "colour-demosaicing bilinear", "laplacian": "colour-demosaicing Malvar2004"}
    for k, v in t.items():
        ratio = f"{t[pairs[k]] / v:.1f}x faster than {pairs[k]}" if k in pairs else ""
        if k.endswith(SINGLE):
            ratio = f"{t[k[:-len(SINGLE)]] / v:.1f}x faster than double precision"
        if k == "pocs":
            ratio = f"{info['iterations']} iterations to tolerance 1e-3"
        print(f"| {k} | {v:.4f} | {ratio} |")
    return t


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="192 x 192 crops, one repeat")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--new-layouts-only", action="store_true", help="only the layouts of today's sensors")
    ap.add_argument("--scielab-only", action="store_true", help="only S-CIELAB of the four methods on Bayer")
    ap.add_argument("--bayer-only", action="store_true", help="only the speed table and Bayer's PSNR (no S-CIELAB)")
    ap.add_argument("--cfas", metavar="A,B,...", help="only the PSNR tables of these CFAs (added to --json's file)")
    ap.add_argument("--json", metavar="PATH", help="also write the measured numbers to PATH (JSON)")
    args = ap.parse_args()
    repeat = 1 if args.quick else args.repeat
    load = os.getloadavg() if hasattr(os, "getloadavg") else ("?",)
    print(f"# bench_demosaic: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"load average {load[0]:.2f} at start; numpy {np.__version__}\n")
    imgs = photos(args.quick)
    if args.bayer_only:
        print("## Speed (Bayer)\n")
        speed_table(repeat)
        print("\n## Bayer: PSNR on R, G, B\n")
        quality_table(("bayer",), imgs, repeat, rgb=True)
        return write_json(args, repeat)
    if args.cfas:
        for name in args.cfas.split(","):
            rgb = name in RGB_CFAS + NEW_RGB_CFAS
            print(f"\n## {name}: PSNR on {'R, G, B' if rgb else 'its own white-balanced channels'}\n")
            quality_table((name,), imgs, repeat, rgb=rgb)
        return write_json(args, repeat, merge=True)
    print("## S-CIELAB on the photographs (Bayer; rank 4/4 = worst)\n")
    scielab_table(imgs)
    if args.scielab_only:
        return write_json(args, repeat, merge=True)
    if not args.new_layouts_only:
        print("## Speed (Bayer)\n")
        speed_table(repeat)
        print("\n## RGB CFAs: PSNR on R, G, B\n")
        quality_table(RGB_CFAS, imgs, repeat, rgb=True)
        print("\n## CMY and RGBW CFAs: PSNR on the CFA's own white-balanced channels\n")
        quality_table(OTHER_CFAS, imgs, repeat, rgb=False)
    print("\n## Layouts of today's sensors, RGB: PSNR on R, G, B\n")
    quality_table(NEW_RGB_CFAS, imgs, repeat, rgb=True)
    print("\n## Layouts of today's sensors, others: PSNR on the CFA's own white-balanced channels\n")
    quality_table(NEW_OTHER_CFAS, imgs, repeat, rgb=False)
    write_json(args, repeat)


def write_json(args, repeat, merge=False):
    """Print the load average; with --json, write RESULTS and how they were measured (``merge``: added
    to the tables already in the file, whose speed table and header stay; each run listed in ``runs``)."""
    import json
    import subprocess
    from datetime import datetime, timezone
    from pathlib import Path

    load = os.getloadavg() if hasattr(os, "getloadavg") else ("?",)
    print(f"\nload average {load[0]:.2f} at the end")
    if not args.json:
        return
    try:
        commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                                cwd=Path(__file__).parent).stdout.strip()
    except OSError:
        commit = ""
    run = {"load_average_end": load[0], "date": datetime.now(timezone.utc).strftime("%Y-%m-%d"), "commit": commit,
           "cfas": args.cfas or ("scielab" if args.scielab_only else "bayer, speed" if args.bayer_only else "all")}
    out = {**RESULTS, "photos": list(PHOTOS), "quick": args.quick, "repeat": repeat, "cpus": os.cpu_count(), **run,
           "runs": [run]}
    if merge and Path(args.json).is_file():
        out = json.loads(Path(args.json).read_text())
        for key in ("psnr_db", "time_per_image_s", "library_psnr_db", "scielab_de00"):
            out.setdefault(key, {}).update(RESULTS.get(key, {}))
        out["runs"] = [*out.get("runs", []), run]
    tmp = Path(args.json).with_suffix(".tmp")
    tmp.write_text(json.dumps(out, indent=1) + "\n")
    tmp.replace(args.json)
    print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
