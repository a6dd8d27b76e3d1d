"""A user's sensor in a file: TOML with its QE curves in CSV beside it
(docs/sensor.md, "Bring your own sensor").

A file gives what a sensor datasheet or an EMVA 1288 report gives: the
quantum efficiency of each channel against wavelength, and either the
datasheet's pixel numbers or the EMVA 1288 results::

    name = "mt9v024-rgb-file"         # optional: the file's stem
    description = "..."               # optional, one line each
    source = "..."
    cfa = "bayer"                     # a named layout (cfa-mitsuba list cfas), or
    # tile = "G R / B G"              # a tile of the channel letters
    qe = "mt9v024-rgb-qe.csv"         # wavelength_nm, one column per channel
    # [qe]                            # or one two-column CSV per channel:
    # R = "red.csv"

    [pixel]                           # any SensorParams field (docs/sensor.md s. 3)
    pixel_pitch_um = 6.0
    adc_bits = 10

    [datasheet]                       # datasheet numbers, electrons ...
    well_capacity_e = 25455.0         # ... or the volt-domain ones:
    # conversion_gain_uv_per_e, voltage_swing_v, read_noise_mv, dark_voltage_mv_s

    [emva]                            # or EMVA 1288 results (one operating point)
    system_gain_dn_per_e = 0.0377     # K
    saturation_capacity_e = 25455.0   # mu_e.sat
    temporal_dark_noise_e = 9.09      # sigma_d
    dark_current_e_s = 9.09           # mu_I
    dsnu_e = 0.0                      # DSNU_1288
    prnu_percent = 0.0                # PRNU_1288

QE is the whole pixel's (filter, silicon, micro-lens and any IR-cut
filter), electrons per photon, referred to the pixel area as EMVA 1288
gives it (so ``fill_factor`` stays 1 unless the curves are the
photodiode's).  The EMVA numbers map onto the model (:mod:`.params`) as

    well_capacity_e = saturation_capacity_e
    analog_gain     = K x saturation_capacity_e / (2^bits - 1 - black level)
    read_noise_e    = temporal_dark_noise_e

so that the model's DN per electron is K and a full well reaches the top
code at that K (EMVA 1288 release 4.0, s. 4: K in DN/e-, the saturation
capacity where the camera's output saturates).  The volt-domain datasheet
keys are converted as the presets' ISETCam values (:mod:`.presets`).

A file is refused, in one line naming the key, for an unknown key, a
value that is not a number, a negative or zero gain, a negative QE, a
channel of the tile without a curve, or a quantity given twice.
"""

from __future__ import annotations

__all__ = ["read_sensor_file", "is_sensor_file", "sensor_file_curves", "volts_to_electrons", "EMVA_KEYS",
           "DATASHEET_KEYS"]

import math
import numbers
from dataclasses import fields
from pathlib import Path

import numpy as np

from ..errors import CfaMitsubaError
from .params import SensorParams, check_channel_names

#: [emva] keys -> the SensorParams field each sets (K and the saturation
#: capacity together set the well and the analog gain).
EMVA_KEYS = {"system_gain_dn_per_e": None, "saturation_capacity_e": "well_capacity_e",
             "temporal_dark_noise_e": "read_noise_e", "dark_current_e_s": "dark_current_e_s",
             "dsnu_e": "dsnu_e", "prnu_percent": "prnu_percent"}
#: [datasheet] keys: electrons, or ISETCam's volt-domain pixel values.
DATASHEET_KEYS = ("well_capacity_e", "read_noise_e", "dark_current_e_s", "dsnu_e", "prnu_percent",
                  "conversion_gain_uv_per_e", "voltage_swing_v", "read_noise_mv", "dark_voltage_mv_s")
_TOP = {"name", "description", "source", "cfa", "tile", "qe", "pixel", "datasheet", "emva", "notes"}
_STRINGS = ("readout", "binning", "ir_cut")
_GAINS = ("system_gain_dn_per_e", "conversion_gain_uv_per_e", "analog_gain")


_VOLT_KEYS = {"conversion_gain_uv_per_e", "voltage_swing_v", "read_noise_mv", "dark_voltage_mv_s"}


def volts_to_electrons(values: dict, where: str) -> dict:
    """ISETCam's volt-domain pixel values in electrons: well = swing /
    conversion gain, read noise = volts / gain, dark current = volts per
    second / gain (the presets' ``isetcam`` table and ``[datasheet]``)."""
    unknown = set(values) - _VOLT_KEYS
    if unknown:
        raise CfaMitsubaError(f"{where}: unknown ISETCam key {sorted(unknown)[0]!r}")
    cg_v = values["conversion_gain_uv_per_e"] * 1e-6
    out = {"voltage_swing_v": values["voltage_swing_v"], "well_capacity_e": values["voltage_swing_v"] / cg_v}
    if "read_noise_mv" in values:
        out["read_noise_e"] = values["read_noise_mv"] * 1e-3 / cg_v
    if "dark_voltage_mv_s" in values:
        out["dark_current_e_s"] = values["dark_voltage_mv_s"] * 1e-3 / cg_v
    return out


def is_sensor_file(path) -> bool:
    """Whether a ``.toml`` path is a sensor file (it has a ``qe`` key) rather
    than a CFA file; False for anything unreadable (the CFA reader then says why)."""
    from ..io.guard import read_toml

    try:  # regular file, bounded: a FIFO named as a CFA file must not block here (issue 51)
        return "qe" in read_toml(path, "sensor file")
    except CfaMitsubaError:
        return False


def _number(where: str, key: str, v, *, positive: bool = False) -> float:
    ok = isinstance(v, numbers.Real) and not isinstance(v, bool) and math.isfinite(v)
    if not ok:
        raise CfaMitsubaError(f"{where}: {key} must be a number, got {v!r}")
    if positive and v <= 0:
        raise CfaMitsubaError(f"{where}: {key} must be positive, got {v!r}")
    if v < 0:
        raise CfaMitsubaError(f"{where}: {key} must not be negative, got {v!r}")
    return v


def _table(data: dict, key: str, where: str) -> dict:
    t = data.get(key, {})
    if not isinstance(t, dict):
        raise CfaMitsubaError(f"{where}: {key} must be a table ([{key}])")
    return t


def _pixel_values(data: dict, where: str) -> dict:
    """SensorParams values from [pixel], [datasheet] and [emva]."""
    known = {f.name for f in fields(SensorParams)}
    values: dict = {}
    given_by: dict = {}

    def put(field, v, key):
        if field in values:
            raise CfaMitsubaError(f"{where}: {key} sets {field}, already given by {given_by[field]}")
        values[field], given_by[field] = v, key

    for k, v in _table(data, "pixel", where).items():
        key = f"pixel.{k}"
        if k not in known:
            raise CfaMitsubaError(f"{where}: unknown key {key!r} (SensorParams fields: {', '.join(sorted(known))})")
        if k in _STRINGS or k in ("channel_well_e", "channel_gain"):
            put(k, v, key)
            continue
        put(k, _number(where, key, v, positive=k in _GAINS), key)
    sheet = _table(data, "datasheet", where)
    volts = {}
    for k, v in sheet.items():
        key = f"datasheet.{k}"
        if k not in DATASHEET_KEYS:
            raise CfaMitsubaError(f"{where}: unknown key {key!r} (known: {', '.join(DATASHEET_KEYS)})")
        v = _number(where, key, v, positive=k in _GAINS or k in ("voltage_swing_v", "well_capacity_e"))
        if k in ("conversion_gain_uv_per_e", "voltage_swing_v", "read_noise_mv", "dark_voltage_mv_s"):
            volts[k] = v
        else:
            put(k, v, key)
    if volts:
        if not {"conversion_gain_uv_per_e", "voltage_swing_v"} <= set(volts):
            missing = sorted({"conversion_gain_uv_per_e", "voltage_swing_v"} - set(volts))[0]
            raise CfaMitsubaError(f"{where}: datasheet.{missing} is needed with the volt-domain keys")
        for k, v in volts_to_electrons(volts, where).items():
            put(k, v, "datasheet (volts)")
    emva = _table(data, "emva", where)
    for k, v in emva.items():
        if k not in EMVA_KEYS:
            raise CfaMitsubaError(f"{where}: unknown key 'emva.{k}' (known: {', '.join(EMVA_KEYS)})")
        _number(where, f"emva.{k}", v, positive=k in _GAINS or k == "saturation_capacity_e")
    if ("system_gain_dn_per_e" in emva) != ("saturation_capacity_e" in emva):
        missing = "saturation_capacity_e" if "system_gain_dn_per_e" in emva else "system_gain_dn_per_e"
        raise CfaMitsubaError(f"{where}: emva.{missing} is needed with the other (K and the saturation "
                              "capacity set the well and the gain together)")
    for k, field in EMVA_KEYS.items():
        if field and k in emva:
            put(field, float(emva[k]), f"emva.{k}")
    if "system_gain_dn_per_e" in emva:
        swing = float(emva["system_gain_dn_per_e"]) * float(emva["saturation_capacity_e"])
        if swing < 1.0:  # EMVA 1288 (release 4.0, s. 4): the saturation capacity is where the output saturates
            raise CfaMitsubaError(f"{where}: emva.system_gain_dn_per_e x emva.saturation_capacity_e = {swing:.3g} DN: "
                                  "from dark to saturation the output would span less than one digital number, "
                                  "which no camera measured by EMVA 1288 does (at least 1 DN)")
        bits = int(values.get("adc_bits", SensorParams.adc_bits))
        black = float(values.get("black_level_dn", SensorParams.black_level_dn))
        span = 2**bits - 1 - black
        if span <= 0:
            raise CfaMitsubaError(f"{where}: black level {black:g} DN leaves no room in a {bits}-bit ADC")
        put("analog_gain", float(emva["system_gain_dn_per_e"]) * float(emva["saturation_capacity_e"]) / span,
            "emva.system_gain_dn_per_e")
    if "adc_bits" in values:
        if float(values["adc_bits"]) != int(values["adc_bits"]):
            raise CfaMitsubaError(f"{where}: pixel.adc_bits must be a whole number, got {values['adc_bits']!r}")
        values["adc_bits"] = int(values["adc_bits"])
    if "sensor_seed" in values:
        values["sensor_seed"] = int(values["sensor_seed"])
    return values


def sensor_file_curves(data: dict, base: Path, where: str, channels) -> dict:
    """{channel: (wavelengths_nm, qe)} from the file's ``qe`` (one CSV with
    a column per channel, or a table of per-channel CSVs), every channel of
    the tile present."""
    from .spectra_sets import read_curve_csv

    spec = data["qe"]
    curves = {}
    if isinstance(spec, str):
        cols = read_curve_csv(base / spec, where=f"{where}: qe")
        for c in channels:
            if c not in cols:
                raise CfaMitsubaError(f"{where}: qe: {spec} has no column for channel {c!r} "
                                      f"(it has {', '.join(cols)})")
            curves[c] = cols[c]
        extra = sorted(set(cols) - set(channels))
        if extra:
            raise CfaMitsubaError(f"{where}: qe: column {extra[0]!r} is not a channel of the tile")
        return curves
    if not isinstance(spec, dict):
        raise CfaMitsubaError(f"{where}: qe must be a CSV file name or a table of channel = CSV file")
    for c in channels:
        if c not in spec:
            raise CfaMitsubaError(f"{where}: qe.{c} is missing (the tile has channel {c!r})")
    for c, f in spec.items():
        if c not in channels:
            raise CfaMitsubaError(f"{where}: qe.{c} is not a channel of the tile ({', '.join(channels)})")
        if not isinstance(f, str):
            raise CfaMitsubaError(f"{where}: qe.{c} must be a CSV file name, got {f!r}")
        cols = read_curve_csv(base / f, where=f"{where}: qe.{c}")
        curves[c] = next(iter(cols.values()))
    return curves


def _read(path: Path) -> dict:
    from ..io.guard import read_toml

    return read_toml(path, "sensor file")  # regular file, bounded, UTF-8, nesting the parser survives


def read_sensor_file(path) -> dict:
    """Read and check a sensor file (module doc for the format): a dict of
    ``name``, ``description``, ``source``, ``notes`` (tuple), ``params``
    (:class:`SensorParams`), ``cfa`` (the layout with the file's own QE
    curves, named as the sensor), ``layout`` (the named layout, or the
    tile) and ``path`` (absolute).  ``get_sensor_preset(path)`` wraps it
    in a :class:`~.presets.SensorPreset`."""
    from .cfa import _order_channels, _parse_tile, layout_info, make_cfa

    p = Path(path)
    where = str(p)
    data = _read(p)
    unknown = sorted(set(data) - _TOP)
    if unknown:
        raise CfaMitsubaError(f"{where}: unknown key {unknown[0]!r} (expected {', '.join(sorted(_TOP))})")
    for k in ("name", "description", "source", "cfa"):
        if k in data and not isinstance(data[k], str):
            raise CfaMitsubaError(f"{where}: {k} must be a string, got {data[k]!r}")
    if "qe" not in data:
        raise CfaMitsubaError(f"{where}: qe is missing (a CSV of wavelength_nm and one column per channel)")
    if ("cfa" in data) == ("tile" in data):
        raise CfaMitsubaError(f"{where}: give either cfa (a named layout) or tile (e.g. 'G R / B G')")
    layout = data.get("cfa")
    tile = layout_info(layout)["tile"] if layout else data["tile"]
    channels = _order_channels(_parse_tile(tile, where))
    curves = sensor_file_curves(data, p.parent, where, channels)
    for c, (wl, qe) in curves.items():
        if np.any(np.asarray(qe) < 0):
            raise CfaMitsubaError(f"{where}: qe.{c} has a negative quantum efficiency")
    name = data.get("name", p.stem)
    cfa = make_cfa(name, tile, curves, str(data.get("description", "")), where)
    try:
        values = _pixel_values(data, where)
        check_channel_names(values, channels, "the file's tile")
        params = SensorParams(**values)
    except CfaMitsubaError as exc:
        text = str(exc)
        raise CfaMitsubaError(text if text.startswith(where) else f"{where}: {text}") from None
    notes = data.get("notes", [])
    if not isinstance(notes, list) or not all(isinstance(n, str) for n in notes):
        raise CfaMitsubaError(f"{where}: notes must be a list of strings")
    return {"name": name, "description": str(data.get("description", "")), "source": str(data.get("source", "")),
            "notes": tuple(notes), "params": params, "cfa": cfa, "layout": layout or cfa.tile_text(),
            "path": str(p.resolve())}
