"""The EMVA 1288 analysis of the simulated series, by the standard's
reference implementation (``emva1288`` on PyPI, LGPL-3.0, an optional
dependency: ``pip install cfa-mitsuba[emva]``).

Each channel's folder (:func:`cfa_mitsuba.sensor.emva.simulate_emva`) is
read as the package reads a camera's: ``ParseEmvaDescriptorFile`` ->
``LoadImageData`` -> ``Data1288`` -> ``Results1288``; its parameters go to
one tidy CSV beside the model's values, and its report (``Report1288``: a
LaTeX document with its PDF plots, one operating point per channel) to
``report/``.  The package writes the report's ``.tex``; making the PDF
needs a LaTeX installation (``pdflatex report.tex`` in that folder).
"""

from __future__ import annotations

__all__ = ["PARAMETERS", "require_emva1288", "analyse_channel", "parameter_rows", "write_parameters_csv",
           "write_report", "CSV_COLUMNS"]

import csv
import logging
import math
import os
import types
from pathlib import Path

import numpy as np

from ..errors import CfaMitsubaError

#: The parameters set in the model and compared (key: ``Results1288``
#: attribute), with their unit as the CSV writes it.
PARAMETERS = {
    "K": ("system gain", "DN/e-"),
    "QE": ("quantum efficiency", "%"),
    "sigma_d": ("temporal dark noise", "e-"),
    "u_e_sat": ("saturation capacity", "e-"),
    "DSNU1288": ("DSNU", "e-"),
    "PRNU1288": ("PRNU", "%"),
    "u_I_mean": ("dark current (from the mean)", "e-/s"),
    "u_I_var": ("dark current (from the variance)", "e-/s"),
}
#: What a non-uniformity emva1288 returns as NaN is: its spatial variance,
#: less the temporal noise's share (sigma^2 / L), came out negative, so
#: the square root has no value: the non-uniformity is below what the L
#: frames of the spatial stack resolve (EMVA 1288 4.0 s. 8.2).
UNRESOLVED = "below what the spatial stack resolves: its variance estimate, less the temporal noise's share, is negative"

CSV_COLUMNS = ("channel", "wavelength_nm", "parameter", "description", "unit", "measured", "set_value",
               "relative_error", "section")
_QUIET = logging.WARNING


class _NumpyCompat(types.ModuleType):
    """numpy as ``emva1288`` 1.0.2 expects it: its ``process/routines.py``
    calls ``np.asfarray`` and ``np.int``, removed in NumPy 2.0; this proxy
    gives that one module both (as NumPy 1.x defined them) and passes every
    other name to numpy, which itself is left unchanged."""

    int = int

    def __init__(self):
        super().__init__("numpy")

    @staticmethod
    def asfarray(a, dtype=np.float64):
        return np.asarray(a, dtype=dtype if np.issubdtype(np.dtype(dtype), np.inexact) else np.float64)

    def __getattr__(self, name):
        return getattr(np, name)


def require_emva1288():
    """The ``emva1288`` package, or a one-line error saying how to install it."""
    try:
        import emva1288.process as proc  # noqa: F401
        from emva1288.process import routines
    except ImportError:
        raise CfaMitsubaError("sensor emva needs the optional package emva1288 (the EMVA 1288 reference "
                              "implementation): pip install 'cfa-mitsuba[emva]'") from None
    if not hasattr(np, "asfarray") and not isinstance(routines.np, _NumpyCompat):
        routines.np = _NumpyCompat()
    return proc


def analyse_channel(folder, pixel_area_um2: float | None = None):
    """``emva1288``'s ``Results1288`` for one channel's folder (and the
    ``Data1288`` data it was computed from)."""
    from .emva import DESCRIPTOR

    proc = require_emva1288()
    parser = proc.ParseEmvaDescriptorFile(os.fspath(Path(folder) / DESCRIPTOR), loglevel=_QUIET)
    loaded = proc.LoadImageData(parser.images, loglevel=_QUIET)
    data = proc.Data1288(loaded.data, loglevel=_QUIET)
    return proc.Results1288(data.data, pixel_area=pixel_area_um2, loglevel=_QUIET), data.data


def _value(results, name):
    v = getattr(results, name)
    v = v() if callable(v) else v
    try:
        return float(v)
    except (TypeError, ValueError):
        return None


def parameter_rows(series, results) -> list[dict]:
    """CSV rows of one channel: every parameter ``emva1288`` computes (its
    own units and sections), with the model's value and the relative error
    for the :data:`PARAMETERS`."""
    rows = []
    with np.errstate(invalid="ignore", divide="ignore"):  # a NaN for a non-uniformity whose estimate is below 0
        info = results.results_by_section  # {section: {attribute: {value, unit, short, ...}}}
    for section, attributes in info.items():
        for name, meta in attributes.items():
            if "value" not in meta:
                continue
            try:
                measured = float(meta["value"])
            except (TypeError, ValueError):
                continue  # histograms, linearity tables
            expected = series.expected.get(name)
            desc, unit = PARAMETERS.get(name, (meta.get("short") or name, meta.get("unit") or ""))
            err = ""
            if expected is not None and expected != 0 and math.isfinite(measured):
                err = (measured - expected) / expected
            if not math.isfinite(measured):  # never a silent NaN: emva1288's estimate had no root
                measured, desc = "", f"{desc} ({UNRESOLVED})"
            rows.append({"channel": series.channel, "wavelength_nm": series.wavelength_nm, "parameter": name,
                         "description": desc, "unit": _plain_unit(unit), "measured": measured,
                         "set_value": "" if expected is None else expected, "relative_error": err,
                         "section": section})
    for name, desc, unit in (("clip_e", "signal clip: full well, or the ADC's top code (model)", "e-"),
                             ("analog_gain", "analog gain of the operating point (model)", ""),
                             ("dsnu_nominal_e", "DSNU set rms (model; DSNU1288's set value is its realisation)",
                              "e-"),
                             ("prnu_nominal_percent", "PRNU set rms (model; PRNU1288's set value is its "
                                                      "realisation)", "%")):
        rows.append({"channel": series.channel, "wavelength_nm": series.wavelength_nm, "parameter": name,
                     "description": desc, "unit": unit, "measured": "", "set_value": series.expected[name],
                     "relative_error": "", "section": "model"})
    rows.sort(key=lambda r: (r["parameter"] not in PARAMETERS,
                             list(PARAMETERS).index(r["parameter"]) if r["parameter"] in PARAMETERS else 0))
    return rows


def _plain_unit(unit: str) -> str:
    """emva1288's LaTeX units as text (``$e^-$`` -> ``e-``, ``\\%`` -> ``%``)."""
    return (str(unit).replace("$", "").replace("\\%", "%").replace("^-", "-").replace("\\mu m", "um")
            .replace("^2", "2").replace("{", "").replace("}", ""))


def write_parameters_csv(rows: list[dict], path) -> Path:
    """The tidy parameters table, written atomically (temporary file + rename)."""
    path = Path(path)
    tmp = path.with_name(f".{path.name}.tmp")
    with tmp.open("w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=CSV_COLUMNS)
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{v:.9g}" if isinstance(v, float) else v) for k, v in r.items()})
    os.replace(tmp, path)
    return path


def write_report(out_dir, measured: list[tuple], sensor_name: str, pixel_pitch_um: float) -> Path:
    """``emva1288``'s report (``Report1288``): ``report.tex``, its style and
    the PDF plots of each channel's operating point, in ``out_dir``.
    ``measured``: (ChannelSeries, Results1288, data) per channel."""
    import contextlib
    import io

    import matplotlib

    matplotlib.use("Agg")
    require_emva1288()
    from emva1288.report import info_basic, info_op, info_setup, Report1288

    basic = info_basic(vendor="cfa-mitsuba (simulated)", model=sensor_name, data_type="simulated",
                       pixel_size=f"{pixel_pitch_um:g} um")
    setup = info_setup(**{"Light source": "uniform, monochromatic (one 10-nm band)",
                          "Light source non uniformity": "0 %", "Standard version": "4.0"})
    with contextlib.redirect_stdout(io.StringIO()), np.errstate(invalid="ignore", divide="ignore"):
        # (the package prints its output folder; NaN non-uniformities as in parameter_rows)
        report = Report1288(os.fspath(out_dir), basic=basic, setup=setup)
        for series, results, data in measured:
            op = info_op()
            op["name"] = f"channel {series.channel} at {series.wavelength_nm:g} nm"
            op["camera_settings"]["Analog gain"] = f"{series.expected.get('analog_gain', '')}"
            op["test_parameters"]["Wavelength"] = f"{series.wavelength_nm:g} nm"
            report.add(op, data, results=results)
        report.latex()
    return Path(out_dir) / "report.tex"
