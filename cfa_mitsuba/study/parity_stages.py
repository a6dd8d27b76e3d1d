"""Our side of docs/isetcam-parity.md's stage-by-stage comparison, written
as a results file that the page (:mod:`cfa_mitsuba.report.parity_doc`) reads.

    python -m cfa_mitsuba.study.parity_stages --isetcam docs/data/isetcam-octave.json \\
        --out docs/data/isetcam-parity-stages.json

For v_icam_pixelMTF's scene (f/4): the optical image's MTF50 and, at the
pitches ISETCam's stage values were taken (``--isetcam``), each pixel
read-out (ISETCam's Gaussian + bilinear, our photodiode box at fill factor
0.75 and 1) in both ISO 12233 conventions; mode ``isetcam`` at every
f-number and pitch ISETCam was run at; and the ``isetcam-default`` preset's
pixel values.  ISETCam's own numbers stay in ``--isetcam``.
"""

from __future__ import annotations

__all__ = ["our_stage_values", "our_sweep", "main"]

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

from ..errors import CfaMitsubaError

_STAGE_ROI_OI = (200, 240, 440, 400)  # the edge's middle on v_icam_pixelMTF's 641 x 641 OI


def _box_read_out(irradiance: np.ndarray, spacing_um: float, pitch_um: float, fill_factor: float, n: int):
    """Our pixel: the mean over a centred square photodiode of side
    sqrt(FF) x pitch (exact in Fourier), at the pixel centres."""
    from ..optics.isetcam import _centres, _linear_weights

    side = math.sqrt(fill_factor) * pitch_um
    h, w = irradiance.shape
    spec = np.fft.fft2(irradiance)
    spec *= np.sinc(side * np.fft.fftfreq(h, d=spacing_um))[:, None] * np.sinc(side * np.fft.fftfreq(w, d=spacing_um))[None]
    blurred = np.real(np.fft.ifft2(spec))
    wy = _linear_weights(_centres(n, pitch_um), h, spacing_um)
    wx = _linear_weights(_centres(n, pitch_um), w, spacing_um)
    return wy @ blurred @ wx.T


def our_stage_values(isetcam: dict) -> dict:
    """Our chain's numbers at each stage of v_icam_pixelMTF (f/4), on
    ISETCam's scene: the optical image's MTF50, then each pixel read-out
    (ISETCam's Gaussian + bilinear; our photodiode box at FF 0.75 and 1) in
    both ISO 12233 conventions."""
    from .. import metrics
    from ..optics import OpticsParams, get_optics_preset
    from ..optics.isetcam import regrid_isetcam
    from .parity_image import ISETCAM_DEFAULTS, isetcam_optical_image, isetcam_slanted_bar

    refl = isetcam_slanted_bar(ISETCAM_DEFAULTS["scene_size_px"], ISETCAM_DEFAULTS["edge_slope"])
    focal_mm = get_optics_preset("isetcam-default").focal_length_mm
    oi, spacing = isetcam_optical_image(refl, ISETCAM_DEFAULTS, OpticsParams(f_number=4.0), focal_mm)
    signal = (oi.irradiance_w_m2_nm * oi.wavelengths).sum(-1)  # photons on a flat QE
    out = {"oi_sample_spacing_um": spacing,
           "oi_mtf50_sfrmat3_cy_mm": float(metrics.mtf(signal, roi=_STAGE_ROI_OI, pixel_pitch_um=spacing))}
    for key in ("2um", "9um"):
        p = float(key[:-2])
        roi = tuple(isetcam["pixel_mtf_stages"][key]["roi_y0_x0_y1_x1"])
        n = int(round(512 / p))
        reads = {"isetcam_read_out": regrid_isetcam(signal[:, :, None], spacing, p, n, n)[..., 0],
                 "box_ff0.75": _box_read_out(signal, spacing, p, 0.75, n),
                 "box_ff1": _box_read_out(signal, spacing, p, 1.0, n)}
        out[key] = {name: {conv: float(metrics.mtf(img, roi=roi, pixel_pitch_um=p, convention=conv))
                           for conv in ("sfrmat3", "isetcam")} for name, img in reads.items()}
        out[key]["cos_edge_angle"] = math.cos(math.atan(1.0 / ISETCAM_DEFAULTS["edge_slope"]))
    return out


def our_sweep(isetcam: dict, template: Path) -> list[dict]:
    """Mode ``isetcam`` at every (f-number, pitch) ISETCam was run at: the
    2 um case file with only those two values changed."""
    from .parity import load_case, run_case

    import tempfile

    text = template.read_text()
    rows = []
    with tempfile.TemporaryDirectory() as folder:  # never beside the committed cases
        for r in isetcam["pixel_mtf_sweep_noise_free"]:
            t = text.replace("f_number = 4\n", f"f_number = {r['f_number']}\n")
            t = t.replace("pixel_pitch_um = 2.0", f"pixel_pitch_um = {r['pixel_pitch_um']}")
            tmp = Path(folder) / f"sweep_{r['f_number']}_{r['pixel_pitch_um']}.toml"
            tmp.write_text(t)
            rows.append({**r, "ours": run_case(load_case(tmp))["value"]})
    return rows


def _preset_values() -> dict:
    from ..sensor import get_sensor_preset

    q = get_sensor_preset("isetcam-default").params
    return {"pixel_pitch_um": q.pixel_pitch_um, "fill_factor": q.fill_factor, "well_capacity_e": q.well_capacity_e,
            "read_noise_e": q.read_noise_e, "dark_current_e_s": q.dark_current_e_s}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m cfa_mitsuba.study.parity_stages", description=__doc__.split("\n")[0])
    ap.add_argument("--isetcam", required=True, help="ISETCam's own values (docs/data/isetcam-octave.json)")
    ap.add_argument("--template", default="tests/parity/isetcam/pixel-mtf-2um.toml",
                    help="the case the f-number/pitch sweep varies")
    ap.add_argument("--out", required=True, help="the JSON file to write")
    args = ap.parse_args(argv)
    try:
        isetcam = json.loads(Path(args.isetcam).read_text())
        out = {"stages": our_stage_values(isetcam), "sweep": our_sweep(isetcam, Path(args.template)),
               "isetcam_default_preset": _preset_values()}
    except (OSError, ValueError, KeyError, CfaMitsubaError) as exc:
        print(f"parity_stages: error: {exc}", file=sys.stderr)
        return 2
    from ..io.atomic import atomic_output

    with atomic_output(args.out) as tmp:
        tmp.write_text(json.dumps(out, indent=1) + "\n")
    print(args.out)
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
