"""Measurements behind the 2x2 rediscovery (issue 26; docs/design.md,
tests/design/test_rediscovery.py): why G G / B R and R B / G R tied or
beat Bayer, on ISETCam's RGB filters, under the exposure program.

1. MTF50 of the slanted edge, noise off, through the study's own chain and
   metric call (the scene geometry's ROI), at two render heights: the
   near-vertical edge's value of each tile, and G B / G R (the transpose of
   G G / B R: its near-horizontal edge);
2. the proxy's exact phase-averaged prediction of the same (design/proxy.py),
   on CIE Y and on the MTF metric's luminance (0.3, 0.6, 0.1 of linear sRGB);
3. YSNR at 10 cd/m^2: each channel's electrons on the grey, its weight in Y
   after the colour matrix, the bilinear demosaic's noise gain per channel,
   and the propagated YSNR, per pixel and referred to an area (``ysnr-area``,
   design/noise_area.py), with each channel's area noise gain.

    python benchmarks/design_rediscovery.py          # about a minute on 2 cores
    python benchmarks/design_rediscovery.py --json docs/data/design-rediscovery.json

``--json`` also writes the numbers (docs/design.md quotes them from
docs/data/design-rediscovery.json through report/docs_numbers.py markers):
``mtf50_cy_mm.<render rows>.<tile>`` measured, ``sensor_rows.<render rows>``,
``electrons``, ``y_weight`` and ``luma_share`` per channel (R, G, B), and
``proxy.<tile>``: ``mtf_y``, ``mtf_luma`` (cy/mm), ``ysnr``, ``ysnr_area``,
``pixel_gain`` and ``area_gain`` per channel; tiles keyed ``bayer``,
``RB_GR``, ``GG_BR``, ``GB_GR``.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

TILES = {"bayer": "G R / B G", "RB_GR": "R B / G R", "GG_BR": "G G / B R", "GB_GR": "G B / G R"}
LETTERS = ("R", "G", "B")
#: The MTF metric's luminance weights on linear sRGB, and sRGB's matrix from XYZ (IEC 61966-2-1).
METRIC_LUMA = np.array([0.3, 0.6, 0.1])
SRGB_FROM_XYZ = np.array([[3.2406, -1.5372, -0.4986], [-0.9689, 1.8758, 0.0415], [0.0557, -0.2040, 1.0570]])


def _cfa_files(folder: Path) -> dict:
    out = {}
    for name, text in TILES.items():
        if name == "bayer":
            out[name] = "bayer"
            continue
        p = folder / f"{name}.toml"
        rows = ", ".join(f'"{r.strip()}"' for r in text.split("/"))
        p.write_text(f'name = "{p.stem}"\ntile = [{rows}]\nspectra_set = "isetcam-rgb"\n')
        out[name] = str(p)
    return out


def measured_mtf50(cfas: dict, height: int, width: int = 320) -> dict:
    """{tile: MTF50 cy/mm} noise-free, as a study measures it."""
    from cfa_mitsuba import render
    from cfa_mitsuba.sensor import ExposureProgram
    from cfa_mitsuba.study.chain import CameraChain, ChainSettings

    settings = ChainSettings(exposure_program=ExposureProgram("program"))
    chain = CameraChain(settings)
    image = render.render_cached("slanted-edge", width=width, height=height)
    cond = settings.base_condition(luminance=100.0)
    oi = chain.optical(image, cond, None)
    ideal = chain.ideal(oi, cond, None)
    out = {}
    for name, cfa in cfas.items():
        raw = chain.capture(oi, cfa, cond, 1, noise="off")
        results, _, _ = chain.measure(ideal, chain.process(raw, "bilinear", cond), ["mtf"], cond)
        out[name] = float(results["mtf"].value)
    return out, ideal.xyz.shape[0]


def proxy_numbers() -> dict:
    from cfa_mitsuba import spectra
    from cfa_mitsuba.design import proxy as P
    from cfa_mitsuba.design import responses as R
    from cfa_mitsuba.design.search import fixed_models
    from cfa_mitsuba.sensor import ExposureProgram, get_spectra_set

    settings = P.ProxySettings(exposure=ExposureProgram("program"), luminance_cd_m2=10.0)
    model = fixed_models(get_spectra_set("isetcam-rgb").curves, LETTERS, settings)((0, 1, 2))
    white = spectra.xyz_from_radiance(spectra.illuminant("D65", spectra.DEFAULT_WAVELENGTHS)[None, :],
                                      spectra.DEFAULT_WAVELENGTHS)[0]
    luma = (model.matrix_rel * (white / white[1])[None, :]) @ SRGB_FROM_XYZ.T @ METRIC_LUMA
    electrons = P.grey_electrons(model, settings)
    var = (electrons + settings.read_noise_e ** 2) / electrons ** 2
    per_mm = 1.0 / (settings.pixel_pitch_um * 1e-3)
    rows = {}
    for name, text in TILES.items():
        lay = np.array([[LETTERS.index(c) for c in r.split()] for r in text.split("/")])
        mtf = []
        for column in (model.matrix_rel[:, 1], luma / luma.sum()):
            m = model.matrix_rel.copy()
            m[:, 1] = column
            lsf = R._gains_and_lsf(lay, LETTERS, m, "bilinear", model.lum_weights)[1]
            mtf.append(P.edge_mtf50(lsf, settings.f_number, settings.pixel_pitch_um) * per_mm)
        gains = P.demosaic_noise_gains(lay, LETTERS, model.matrix_rel, "bilinear")[:, 1]
        area = P.demosaic_area_noise_gains(lay, LETTERS, model.matrix_rel, "bilinear")[:, 1]
        rows[name] = {"tile": text, "mtf_y": mtf[0], "mtf_luma": mtf[1], "ysnr": 1.0 / np.sqrt(gains @ var),
                      "ysnr_area": 1.0 / np.sqrt(area @ var),
                      "pixel_gain": gains / model.matrix_rel[:, 1] ** 2, "area_gain": area / model.matrix_rel[:, 1] ** 2}
    return {"electrons": electrons, "y_weight": model.matrix_rel[:, 1], "luma_share": luma / luma.sum(), "rows": rows}


def _channels(v) -> dict:
    return {c: float(x) for c, x in zip(LETTERS, v)}


def _write_json(path: Path, measured: dict, rows: dict, p: dict) -> None:
    from cfa_mitsuba.io import atomic_output

    data = {"mtf50_cy_mm": measured, "sensor_rows": rows, "electrons": _channels(p["electrons"]),
            "y_weight": _channels(p["y_weight"]), "luma_share": _channels(p["luma_share"]),
            "proxy": {name: {k: (_channels(v) if k.endswith("_gain") else v if isinstance(v, str) else float(v))
                             for k, v in r.items()} for name, r in p["rows"].items()}}
    with atomic_output(path) as tmp:
        tmp.write_text(json.dumps(data, indent=1) + "\n")


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--json", type=Path, help="also write the numbers to this JSON file")
    args = parser.parse_args(argv)
    measured, sensor_rows = {}, {}
    with tempfile.TemporaryDirectory() as tmp:
        cfas = _cfa_files(Path(tmp))
        for height in (288, 864):
            got, rows = measured_mtf50(cfas, height)
            measured[str(height)], sensor_rows[str(height)] = got, rows
            print(f"MTF50, noise off, study ROI, render {height} rows ({rows} sensor rows): "
                  + ", ".join(f"{TILES[k]} {v:.1f}" for k, v in got.items()) + " cy/mm")
    p = proxy_numbers()
    print("grey electrons at 10 cd/m^2 (R, G, B): " + ", ".join(f"{v:.1f}" for v in p["electrons"]))
    print("weight in Y after the colour matrix (R, G, B): " + ", ".join(f"{v:.3f}" for v in p["y_weight"]))
    print("share of the MTF metric's luminance (R, G, B): " + ", ".join(f"{v:.3f}" for v in p["luma_share"]))
    for name, r in p["rows"].items():
        print(f"proxy {r['tile']}: MTF50 on Y {r['mtf_y']:.1f}, on the metric's luminance {r['mtf_luma']:.1f} cy/mm; "
              f"YSNR at 10 cd/m^2 {r['ysnr']:.2f} per pixel, {r['ysnr_area']:.2f} area-referred; bilinear noise "
              "gain (R, G, B) per pixel " + ", ".join(f"{g:.4f}" for g in r["pixel_gain"])
              + ", area " + ", ".join(f"{g:.4f}" for g in r["area_gain"]))
    if args.json:
        _write_json(args.json, measured, sensor_rows, p)
        print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
