"""Measured sensor presets: pixel parameters plus a default CFA and spectra
set, read from ``cfa_mitsuba/data/sensors.toml``.

``get_sensor_preset("mt9v024-rgb")`` gives a :class:`SensorPreset` whose
``params`` is a :class:`~cfa_mitsuba.sensor.params.SensorParams` and whose
``cfa()`` is the CFA with the preset's spectra.  ISETCam stores pixels in
volts; a preset may give ISETCam's values under ``isetcam`` and they are
converted to electrons with the conversion gain (well = swing / gain, read
noise = volts / gain, dark current = volts per second / gain).

A user's sensor is a file (:mod:`.sensor_file`): ``get_sensor_preset``
takes its path (``*.toml``) as well as a name, and ``list_sensor_presets``
adds the files found in the folders of the ``CFA_MITSUBA_SENSORS``
environment variable (separated as ``PATH`` is).
"""

from __future__ import annotations

__all__ = ["SensorPreset", "get_sensor_preset", "list_sensor_presets", "user_sensor_files", "SENSORS_ENV"]

import functools
import os
from pathlib import Path
from dataclasses import dataclass, field, fields

from ..errors import CfaMitsubaError
from .params import SensorParams
from .sensor_file import volts_to_electrons as _from_isetcam
from .spectra_sets import read_data_toml

#: Folders (os.pathsep-separated) whose ``*.toml`` sensor files ``cfa-mitsuba
#: list sensors`` shows beside the presets.
SENSORS_ENV = "CFA_MITSUBA_SENSORS"


@dataclass(frozen=True)
class SensorPreset:
    """A named sensor.

    Attributes
    ----------
    name, description, source : registry name and two lines of provenance.
    params : the pixel and read-out chain.
    cfa_name : the default layout (``cfa-mitsuba list cfas``; a sensor
        file's tile text when it gives a tile, not a named layout).
    spectra : the default spectra set (``cfa-mitsuba list spectra``).
    notes : where and why a value departs from its source.
    path : the sensor file's absolute path ("" for a shipped preset).
    own_cfa : a sensor file's CFA with its own QE curves (None for a preset).
    """

    name: str
    description: str
    source: str
    params: SensorParams
    cfa_name: str
    spectra: str
    notes: tuple[str, ...] = field(default=())
    path: str = ""
    own_cfa: object = field(default=None, repr=False, compare=False)

    def cfa(self, name: str | None = None):
        """The preset's CFA, or another layout with the preset's spectra (a
        sensor file's: with its own curves, for the letters it has)."""
        from .catalogue import get_cfa

        if self.own_cfa is None:
            return get_cfa(name or self.cfa_name, spectra=self.spectra)
        if name is None or name in (self.own_cfa.name, self.own_cfa.tile_text()):
            return self.own_cfa
        from .cfa import layout_info, make_cfa

        return make_cfa(name, layout_info(name)["tile"], self.own_cfa.curves, self.own_cfa.description,
                        where=f"CFA {name!r} with the curves of sensor file {self.path!r}")


@functools.lru_cache(maxsize=1)
def _definitions() -> dict:
    return read_data_toml("sensors.toml", "sensor presets")


def list_sensor_presets() -> list[str]:
    """Names of the shipped presets (``cfa-mitsuba list sensors`` adds
    :func:`user_sensor_files`)."""
    return list(_definitions())


def user_sensor_files() -> list[str]:
    """The ``*.toml`` files in the folders named by ``CFA_MITSUBA_SENSORS``
    (sorted per folder; folders that do not exist are skipped)."""
    out = []
    for folder in os.environ.get(SENSORS_ENV, "").split(os.pathsep):
        if folder and Path(folder).is_dir():
            out += [str(p) for p in sorted(Path(folder).glob("*.toml"))]
    return out


def get_sensor_preset(name) -> SensorPreset:
    """A preset by name, or a sensor file by path (``*.toml``,
    :mod:`.sensor_file`), or a one-line error listing the known ones."""
    if str(name).lower().endswith(".toml"):
        from .sensor_file import read_sensor_file

        f = read_sensor_file(name)
        return SensorPreset(name=f["name"], description=f["description"], source=f["source"], params=f["params"],
                            cfa_name=f["layout"], spectra="", notes=f["notes"], path=f["path"], own_cfa=f["cfa"])
    return _named_preset(str(name))


@functools.lru_cache(maxsize=None)
def _named_preset(name: str) -> SensorPreset:
    defs = _definitions()
    if name not in defs:
        raise CfaMitsubaError(f"unknown sensor preset {name!r} (known: {', '.join(defs)}; or a FILE.toml)")
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
