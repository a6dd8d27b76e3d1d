"""Measured sensor presets: pixel parameters plus a default CFA and spectra
set, read from ``cfa_mitsuba/data/sensors.toml``.

``get_sensor_preset("mt9v024-rgb")`` gives a :class:`SensorPreset` whose
``params`` is a :class:`~cfa_mitsuba.sensor.params.SensorParams` and whose
``cfa()`` is the CFA with the preset's spectra.  ISETCam stores pixels in
volts; a preset may give ISETCam's values under ``isetcam`` and they are
converted to electrons with the conversion gain (well = swing / gain, read
noise = volts / gain, dark current = volts per second / gain).
"""

from __future__ import annotations

__all__ = ["SensorPreset", "get_sensor_preset", "list_sensor_presets"]

import functools
from dataclasses import dataclass, field, fields

from ..errors import CfaMitsubaError
from .params import SensorParams
from .spectra_sets import read_data_toml

_ISETCAM_KEYS = {"conversion_gain_uv_per_e", "voltage_swing_v", "read_noise_mv", "dark_voltage_mv_s"}


@dataclass(frozen=True)
class SensorPreset:
    """A named sensor.

    Attributes
    ----------
    name, description, source : registry name and two lines of provenance.
    params : the pixel and read-out chain.
    cfa_name : the default layout (``cfa-mitsuba list cfas``).
    spectra : the default spectra set (``cfa-mitsuba list spectra``).
    notes : where and why a value departs from its source.
    """

    name: str
    description: str
    source: str
    params: SensorParams
    cfa_name: str
    spectra: str
    notes: tuple[str, ...] = field(default=())

    def cfa(self, name: str | None = None):
        """The preset's CFA, or another layout with the preset's spectra."""
        from .catalogue import get_cfa

        return get_cfa(name or self.cfa_name, spectra=self.spectra)


@functools.lru_cache(maxsize=1)
def _definitions() -> dict:
    return read_data_toml("sensors.toml", "sensor presets")


def _from_isetcam(values: dict, where: str) -> dict:
    unknown = set(values) - _ISETCAM_KEYS
    if unknown:
        raise CfaMitsubaError(f"{where}: unknown ISETCam key {sorted(unknown)[0]!r}")
    cg_v = values["conversion_gain_uv_per_e"] * 1e-6
    out = {"voltage_swing_v": values["voltage_swing_v"], "well_capacity_e": values["voltage_swing_v"] / cg_v}
    if "read_noise_mv" in values:
        out["read_noise_e"] = values["read_noise_mv"] * 1e-3 / cg_v
    if "dark_voltage_mv_s" in values:
        out["dark_current_e_s"] = values["dark_voltage_mv_s"] * 1e-3 / cg_v
    return out


def list_sensor_presets() -> list[str]:
    """Names of the shipped presets (``cfa-mitsuba list sensors``)."""
    return list(_definitions())


@functools.lru_cache(maxsize=None)
def get_sensor_preset(name: str) -> SensorPreset:
    """A preset by name, or a one-line error listing the known ones."""
    defs = _definitions()
    if name not in defs:
        raise CfaMitsubaError(f"unknown sensor preset {name!r} (known: {', '.join(defs)})")
    entry = dict(defs[name])
    where = f"sensor preset {name!r}"
    meta = {k: entry.pop(k, "") for k in ("description", "source", "cfa", "spectra")}
    notes = tuple(entry.pop("notes", ()))
    values = _from_isetcam(entry.pop("isetcam"), where) if "isetcam" in entry else {}
    known = {f.name for f in fields(SensorParams)}
    unknown = sorted(set(entry) - known)
    if unknown:
        raise CfaMitsubaError(f"{where}: unknown key {unknown[0]!r}")
    values.update(entry)
    return SensorPreset(name=name, description=meta["description"], source=meta["source"],
                        params=SensorParams(**values), cfa_name=meta["cfa"], spectra=meta["spectra"], notes=notes)
