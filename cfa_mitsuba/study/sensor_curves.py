"""``sensor_curves.csv``: the quantum efficiency of every compared CFA's
channels as the study captured them, so that the report (which reads
results, never the sensor stage) can plot each sensor's curves and say
when the compared CFAs use different spectra sets.

One row per (cfa, channel, wavelength): ``cfa`` (the label metrics.csv
uses), ``spectra`` (the spectra set in effect under the study's own
condition: the CFA's own, or the ``[sensor.spectra_sets]`` replacement;
``own`` for curves a CFA or sensor file gives itself), ``sensor`` (the
study's sensor preset or file, ``default`` when none), ``channel``,
``wavelength_nm`` (band centres of the capture grid) and ``qe`` (band-mean
quantum efficiency, electrons per photon, the IR-cut choice applied):
exactly ``cfa.sensitivities`` as :meth:`~.chain.Chain.capture` uses it.
"""

from __future__ import annotations

__all__ = ["SENSOR_CURVES", "sensor_curve_rows", "write_sensor_curves"]

import csv
from pathlib import Path

from .. import spectra as _spectra
from ..io import atomic_output

SENSOR_CURVES = "sensor_curves.csv"
_COLUMNS = ("cfa", "spectra", "sensor", "channel", "wavelength_nm", "qe")


def sensor_curve_rows(config) -> list[dict]:
    """The rows of ``sensor_curves.csv`` for a :class:`~.config.StudyConfig`."""
    from ..sensor import get_cfa
    from ..sensor.physics import with_ir_cut

    settings = config.chain_settings()
    cond = config.base_condition()
    _, sensor = settings.for_condition(cond)
    preset = config.capture.get("sensor_preset") or "default"
    wl = _spectra.DEFAULT_WAVELENGTHS
    rows = []
    for c in config.cfas:
        chosen = settings.spectra_for(c, cond)
        cfa = get_cfa(c, spectra=chosen) if chosen is not None else get_cfa(c)
        if cfa.spectra:
            cfa = with_ir_cut(cfa, sensor.ir_cut)
        qe = cfa.sensitivities(wl)
        label = cfa.name if str(c).lower().endswith(".toml") else str(c)  # as metrics.csv (runner._cfa_label)
        for i, ch in enumerate(cfa.channels):
            rows += [{"cfa": label, "spectra": cfa.spectra or "own", "sensor": preset, "channel": ch,
                      "wavelength_nm": float(w), "qe": float(q)} for w, q in zip(wl, qe[i])]
    return rows


def write_sensor_curves(config, out_dir) -> Path:
    """Write ``out_dir/sensor_curves.csv`` atomically; returns its path."""
    path = Path(out_dir) / SENSOR_CURVES
    rows = sensor_curve_rows(config)
    with atomic_output(path) as tmp:
        with open(tmp, "w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=_COLUMNS)
            w.writeheader()
            for r in rows:
                w.writerow({**r, "wavelength_nm": f"{r['wavelength_nm']:g}", "qe": f"{r['qe']:.9g}"})
    return path
