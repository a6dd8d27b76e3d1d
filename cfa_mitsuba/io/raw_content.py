"""A raw capture's pixel data checked against its own metadata, at the
point of entry (``load_raw_npz``), so ``process`` never turns an impossible
file into plausible output.

:func:`~cfa_mitsuba.io.validate.check_raw_arrays` checks each array for
physical sense on its own; this checks what the arrays and the recorded
settings say together:

* the shape of ``raw`` follows the tile: a CFA's mosaic is 2-D, only the
  ideal sensor (tile ``[['XYZ']]``) stores a 3-D (H, W, 3) XYZ image (a 3-D
  Bayer raw would otherwise be read as XYZ);
* every DN is finite and inside what the recorded read-out can give: an ADC
  (noise ``all``) gives integer codes 0 .. 2^bits - 1 (sensor/noise.py,
  step 5); noise ``off`` and ``shot`` give electrons x DN per electron,
  never negative and at most the fullest well times the gain;
* the scalars the arrays hold (``black_level_dn``, ``dn_per_electron``,
  ``exposure_s``) equal the settings recorded beside them (a black level of
  1e9 DN on a 12-bit sensor would give XYZ of about -2e8).
"""

from __future__ import annotations

__all__ = ["check_raw_content"]

import math

import numpy as np

from ..errors import CfaMitsubaError

#: The widest ADC the sensor parameters allow (SensorParams: adc_bits 1..32):
#: the bound on DN of a file whose settings do not say its ADC.
_MAX_ADC_BITS = 32


def _number(value) -> float | None:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    return float(value) if math.isfinite(value) else None


def _same(a: float, b: float) -> bool:
    return abs(a - b) <= 1e-9 * max(abs(a), abs(b), 1e-300)


def _gains(sensor: dict, key: str) -> list[float]:
    table = sensor.get(key)
    vals = [_number(v) for v in table.values()] if isinstance(table, dict) else []
    return [v for v in vals if v is not None and v > 0]


def check_raw_content(d: dict, settings: dict, where: str) -> None:
    """Refuse (one :class:`CfaMitsubaError` starting with ``where``) a raw
    capture whose pixel array contradicts its tile or its settings (module
    docstring).  ``d``: name -> array as :mod:`.raw_npz` stores them;
    ``settings``: the parsed ``settings_json``."""
    def fail(msg):
        raise CfaMitsubaError(f"{where}: {msg}")

    raw = np.asarray(d["raw"])
    names = [[str(v) for v in row] for row in np.asarray(d["pattern"]).tolist()]
    tile = " / ".join(" ".join(row) for row in names)
    if names == [["XYZ"]]:
        if raw.ndim != 3 or raw.shape[2] != 3:
            fail(f"the ideal sensor's raw must be an (H, W, 3) XYZ image, got shape {raw.shape}")
    elif raw.ndim != 2:
        fail(f"a CFA capture (tile {tile!r}) must hold a 2-D mosaic, got shape {raw.shape} "
             "(only the ideal sensor stores a 3-D XYZ image)")
    bad = int(raw.size - np.count_nonzero(np.isfinite(raw)))
    if bad:
        fail(f"raw holds {bad} NaN or infinite value(s)")
    if names == [["XYZ"]] or raw.size == 0:
        return
    sensor = settings.get("sensor") if isinstance(settings.get("sensor"), dict) else {}
    noise = settings.get("noise")
    black, gain, exposure = (float(np.asarray(d[k]).reshape(-1)[0]) for k in
                             ("black_level_dn", "dn_per_electron", "exposure_s"))
    bits = sensor.get("adc_bits")
    bits = bits if isinstance(bits, int) and not isinstance(bits, bool) and 1 <= bits <= _MAX_ADC_BITS \
        else _MAX_ADC_BITS
    top = float(2**bits - 1)
    if black >= top:
        fail(f"black_level_dn {black:g} is not below the {bits}-bit ADC's top code {top:g}")
    recorded = {"black_level_dn": _number(sensor.get("black_level_dn")) if noise == "all" else 0.0,
                "dn_per_electron": _number(sensor.get("dn_per_electron")),
                "exposure_s": _number(settings.get("exposure_s"))}
    if noise not in ("all", "off", "shot"):
        recorded["black_level_dn"] = None  # a hand-made file: nothing recorded to compare with
    for key, value in (("black_level_dn", black), ("dn_per_electron", gain), ("exposure_s", exposure)):
        want = recorded[key]
        if want is not None and not _same(value, want):
            fail(f"{key} {value:g} contradicts its settings ({want:g}"
                 + (", no black level without ADC noise" if key == "black_level_dn" and noise != "all" else "")
                 + ")")
    lo, hi = float(raw.min()), float(raw.max())
    if lo < 0:
        fail(f"raw holds negative DN (lowest {lo:g}): an ADC's codes and collected electrons are never negative")
    if noise in ("off", "shot"):
        wells = [w for w in [_number(sensor.get("well_capacity_e")), *_gains(sensor, "channel_well_e")] if w]
        ceiling = max(wells) * gain * max([1.0, *_gains(sensor, "channel_gain")]) * (1 + 1e-9) if wells else top
        what = f"the fullest well ({max(wells):g} e-) times the gain" if wells else f"the {bits}-bit ADC's top code"
    else:
        ceiling, what = top, f"the {bits}-bit ADC's top code"
    if hi > ceiling:
        fail(f"raw reaches {hi:g} DN, above {what} ({ceiling:g} DN)")
