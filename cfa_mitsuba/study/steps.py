"""``steps.csv``: the luminance SNR on every step of the gray bar (ISO
15739 reads noise on each step of a grey scale) and the dynamic range read
from it, per CFA, demosaic and condition.

One row per (scene, CFA, demosaic, condition, step): ``step`` (1 = white
... 10 = black), the ideal's ``reflectance`` (Y / Yw of the step),
``luminance_cd_m2`` (reflectance x the white's luminance, scene illuminance
/ pi), the camera's ``signal_rel`` and ``noise_rel`` (mean Y and the rms of
its noise, both / Yw; the noise is what differs from the ideal, as the
``ysnr`` metric defines it), ``snr`` = signal / noise and ``snr_db``
(20 log10).  Then, the same on each step row of a capture, its dynamic
range (ISO 15739: the ratio of the luminance that saturates the output to
the luminance where SNR = 1), by this stated method:

1. saturation: the scene Y / Yw at which the capture's first channel clips
   on a neutral on the axis, ``saturation_rel`` = the clip level in
   electrons (the full well or the ADC's top code, the lower) over the
   most electrons any channel collects from the white (the capture's
   ``saturation_rel``, :func:`cfa_mitsuba.sensor.photometry.saturation_rel`);
2. SNR = 1: the steps' noise fitted, by non-negative least squares in
   relative terms (each step weighted by 1 / noise^2), with the noise model
   of a linear camera, noise^2 = a + b S + c S^2 (read and dark noise, shot
   noise, fixed-pattern gain noise; S the signal / Yw), then solved for
   S = noise(S): ``snr1_rel`` = [b + sqrt(b^2 + 4 a (1 - c))] / (2 (1 - c));
   ``snr1_extrapolated`` says it lies below the darkest step measured;
3. ``dynamic_range`` = saturation_rel / snr1_rel (a luminance ratio: the
   camera is linear), ``dynamic_range_db`` (20 log10) and
   ``dynamic_range_ev`` (log2, stops); ``saturation_luminance_cd_m2`` and
   ``snr1_luminance_cd_m2`` the two luminances.

The noise is total noise (temporal and fixed pattern) of one capture after
demosaicing and the colour matrix, per pixel; one realisation, the first
(:mod:`.detail_index`).

References: ISO 15739:2017 (2023), Photography -- Electronic still-picture
imaging -- Noise measurements (s. 6: SNR on the steps of an OECF chart;
dynamic range); EMVA 1288 4.0 s. 6 (the linear camera's noise model).
"""

from __future__ import annotations

__all__ = ["dynamic_range", "step_rows", "write_steps_csv", "STEP_COLUMNS"]

import math
from pathlib import Path

import numpy as np

from .detail_index import KEY_COLUMNS, detail_entries, write_table

STEP_COLUMNS = [*KEY_COLUMNS, "step", "reflectance", "luminance_cd_m2", "signal_rel", "noise_rel", "snr", "snr_db",
                "saturation_rel", "snr1_rel", "snr1_extrapolated", "dynamic_range", "dynamic_range_db",
                "dynamic_range_ev", "saturation_luminance_cd_m2", "snr1_luminance_cd_m2"]


def dynamic_range(signal, noise, saturation: float | None) -> dict:
    """The module's steps 2 and 3 on one capture's steps: ``signal`` and
    ``noise`` (relative to the white, steps without a value left out) and
    ``saturation`` (the capture's ``saturation_rel``).  Returns ``snr1_rel``,
    ``snr1_extrapolated``, ``dynamic_range``, ``dynamic_range_db``,
    ``dynamic_range_ev`` and the model's ``a``, ``b``, ``c``; None values
    where there are fewer than three steps or SNR 1 is never reached."""
    from scipy.optimize import nnls

    out = {"snr1_rel": None, "snr1_extrapolated": None, "dynamic_range": None, "dynamic_range_db": None,
           "dynamic_range_ev": None, "a": None, "b": None, "c": None}
    s = np.asarray([v for v, n in zip(signal, noise) if v is not None and n is not None and v > 0 and n > 0])
    n = np.asarray([n for v, n in zip(signal, noise) if v is not None and n is not None and v > 0 and n > 0])
    if s.size < 3:
        return out
    var = n ** 2
    design = np.stack([np.ones_like(s), s, s ** 2], axis=1) / var[:, None]
    (a, b, c), _ = nnls(design, np.ones_like(s))
    out.update(a=float(a), b=float(b), c=float(c))
    if c >= 1.0 or (a <= 0 and b <= 0):
        return out
    s1 = (b + math.sqrt(b * b + 4.0 * a * (1.0 - c))) / (2.0 * (1.0 - c))
    if not s1 > 0:
        return out
    out.update(snr1_rel=float(s1), snr1_extrapolated=bool(s1 < float(s.min())))
    if saturation:
        dr = float(saturation) / s1
        out.update(dynamic_range=dr, dynamic_range_db=20.0 * math.log10(dr), dynamic_range_ev=math.log2(dr))
    return out


def step_rows(entries) -> list[dict]:
    """The rows of :data:`STEP_COLUMNS` for the camera outputs that hold a
    ``ysnr`` result with per-step values."""
    rows = []
    for e in entries:
        res = e.data.get("ysnr")
        steps = res.get("steps") if isinstance(res, dict) else None
        if e.cfa == "ideal" or not isinstance(steps, list) or not steps:
            continue
        extra = e.data.get("extra") or {}
        lux = extra.get("scene_illuminance_lux")
        white_l = float(lux) / math.pi if lux else None
        sat = extra.get("saturation_rel")
        dr = dynamic_range([st.get("signal_rel") for st in steps], [st.get("noise_rel") for st in steps], sat)
        common = {"saturation_rel": sat, **{k: dr[k] for k in ("snr1_rel", "snr1_extrapolated", "dynamic_range",
                                                                 "dynamic_range_db", "dynamic_range_ev")},
                  "saturation_luminance_cd_m2": sat * white_l if sat and white_l else None,
                  "snr1_luminance_cd_m2": dr["snr1_rel"] * white_l if dr["snr1_rel"] and white_l else None}
        for i, st in enumerate(steps):
            refl, snr = st.get("reflectance"), st.get("snr")
            rows.append({**e.key(), "step": i + 1, "reflectance": refl,
                         "luminance_cd_m2": refl * white_l if refl is not None and white_l else None,
                         "signal_rel": st.get("signal_rel"), "noise_rel": st.get("noise_rel"), "snr": snr,
                         "snr_db": 20.0 * math.log10(snr) if snr else None, **common})
    return rows


def write_steps_csv(out_dir: Path, tasks, details_dir) -> Path | None:
    """Write ``out_dir/steps.csv`` from the study's details (no gray-bar SNR: no file)."""
    return write_table(Path(out_dir) / "steps.csv", step_rows(detail_entries(tasks, details_dir, ideal=False)),
                       STEP_COLUMNS)
