"""SNR against light: a study's ``snr.csv`` and ``snr10.csv``.

From metrics.csv's ``ysnr`` and ``chroma_snr`` rows (the metric
:func:`cfa_mitsuba.metrics.ysnr`, on the gray bar's mid-grey after the whole
image processor; each the mean over the noise realisations with its 95 %
interval):

``snr.csv``
    ``cfa``, ``demosaic``, ``luminance`` (mean scene luminance, cd/m^2),
    ``ysnr``, ``ysnr_low``, ``ysnr_high``, ``chroma_snr``, and the chroma
    interval ``chroma_snr_low``, ``chroma_snr_high``; one row per CFA,
    demosaic, processing setting and luminance: a study with ISP axes
    (``denoise``, ``sharpen``: :mod:`.isp_settings`) has their columns last
    and a curve per setting, each other axis at the study's own value (the
    first condition of a luminance in the study's order, when one is
    reached twice).

``snr10.csv``
    ``cfa``, ``demosaic``, ``snr10_cd_m2`` (and the ISP axes' columns last,
    one row per setting): the scene luminance at which
    YSNR reaches 10 (ISO 12232's 'acceptable' SNR for luminance; the
    low-light figure of merit of sensor data sheets), interpolated linearly
    in log luminance against log YSNR between the two luminances of the sweep
    that bracket it; ``ci_low`` and ``ci_high`` the same crossing of the
    interval's upper and lower curves (more SNR reaches 10 at less light);
    ``note`` says why a value is missing (the sweep never reaches, or starts
    above, YSNR 10), so an empty cell is never silent; ``snr10_lux`` the
    same crossing as the scene's illuminance (lux per cd/m^2 of the sweep).

References
----------
ISO 12232:2019, Photography -- Digital still cameras -- Determination of
exposure index, ISO speed ratings, standard output sensitivity, and
recommended exposure index (noise-based speed: the exposure at SNR 10).
"""

from __future__ import annotations

__all__ = ["SNR_COLUMNS", "SNR10_COLUMNS", "SNR_TARGET", "snr_table", "snr10_table", "crossing", "write_snr_tables"]

import math
from pathlib import Path

import numpy as np

SNR_COLUMNS = ["cfa", "demosaic", "luminance", "ysnr", "ysnr_low", "ysnr_high", "chroma_snr",
               "chroma_snr_low", "chroma_snr_high", "ysnr_db", "chroma_snr_db", "scene_illuminance_lux"]
SNR10_COLUMNS = ["cfa", "demosaic", "snr10_cd_m2", "ci_low", "ci_high", "note", "snr10_lux"]
#: The YSNR whose luminance ``snr10.csv`` gives.
SNR_TARGET = 10.0


def snr_table(metrics, metric: str = "ysnr"):
    """``snr.csv`` (module doc) from a metrics.csv table; empty when the study has no ``ysnr``.

    ``metric``: the rows read into the ``ysnr`` columns: ``'ysnr'`` (per
    pixel, the study's snr.csv) or ``'ysnr-area'`` (the noise referred to an
    area, which a demosaic's smoothing does not raise; metrics/snr.py)."""
    import pandas as pd

    from .isp_settings import isp_axes

    settings = isp_axes(metrics.columns)
    if settings and "base" in metrics.columns:  # every axis but luminance and the ISP's at the study's own value
        metrics = metrics[_own_but(metrics, settings)]
    y = metrics[metrics["metric"] == metric]
    if y.empty:
        return pd.DataFrame(columns=SNR_COLUMNS + settings)
    keys = ["cfa", "demosaic", "luminance", *settings]
    y = y.drop_duplicates(keys, keep="first")
    c = metrics[metrics["metric"] == "chroma_snr"].drop_duplicates(keys, keep="first")
    c = c[keys + ["value", "ci_low", "ci_high"]].rename(
        columns={"value": "chroma_snr", "ci_low": "chroma_snr_low", "ci_high": "chroma_snr_high"})
    lux = y["scene_illuminance_lux"] if "scene_illuminance_lux" in y.columns else np.nan
    out = y[keys + ["value", "ci_low", "ci_high"]].assign(scene_illuminance_lux=lux).rename(
        columns={"value": "ysnr", "ci_low": "ysnr_low", "ci_high": "ysnr_high"}).merge(c, on=keys, how="left")
    out["luminance"] = out["luminance"].astype(float)
    with np.errstate(divide="ignore", invalid="ignore"):
        for col in ("ysnr", "chroma_snr"):
            v = out[col].to_numpy(dtype=float)
            out[f"{col}_db"] = np.where(v > 0, 20.0 * np.log10(np.where(v > 0, v, 1.0)), np.nan)
    order = []
    for col in ("cfa", "demosaic", *settings):
        rank = {v: i for i, v in enumerate(dict.fromkeys(y[col]))}
        out[f"_{col}"] = out[col].map(rank)
        order.append(f"_{col}")
    return out.sort_values([*order, "luminance"], kind="stable")[SNR_COLUMNS + settings].reset_index(drop=True)


def _own_but(metrics, settings) -> np.ndarray:
    """Rows whose axes other than luminance and ``settings`` are at the study's own values."""
    from .isp_settings import _base_values, _matching, other_axes

    axes = other_axes(metrics.columns, *settings)
    return _matching(metrics, axes, _base_values(metrics, axes))


def crossing(luminance, snr, target: float = SNR_TARGET) -> float | None:
    """The luminance at which ``snr`` first reaches ``target`` as light
    rises, interpolated linearly in (log luminance, log SNR) between the two
    bracketing points; None when the sweep never reaches it or starts above it.

    Examples
    --------
    >>> round(crossing([1, 10, 100], [2.0, 6.0, 20.0]), 3)  # between 10 and 100 cd/m^2
    26.563
    """
    lum = np.asarray(luminance, dtype=np.float64)
    s = np.asarray(snr, dtype=np.float64)
    order = np.argsort(lum)
    lum, s = lum[order], s[order]
    ok = np.isfinite(s) & (s > 0)
    lum, s = lum[ok], s[ok]
    if s.size == 0 or s[0] >= target:
        return None
    above = np.flatnonzero(s >= target)
    if above.size == 0:
        return None
    i = int(above[0])
    x0, x1, y0, y1 = math.log(lum[i - 1]), math.log(lum[i]), math.log(s[i - 1]), math.log(s[i])
    return float(math.exp(x0 + (math.log(target) - y0) * (x1 - x0) / (y1 - y0)))


def _note(lum, snr) -> str:
    s = np.asarray(snr, dtype=np.float64)
    if s.size and np.nanmin(s) >= SNR_TARGET:
        return f"YSNR is already {np.nanmin(s):.3g} at the lowest luminance, {min(lum):g} cd/m^2"
    return f"YSNR stays below {SNR_TARGET:g} up to {max(lum):g} cd/m^2 (at most {np.nanmax(s):.3g})"


def snr10_table(snr):
    """``snr10.csv`` (module doc) from :func:`snr_table`."""
    import pandas as pd

    from .isp_settings import isp_axes

    settings = isp_axes(snr.columns)
    rows = []
    for key, g in snr.groupby(["cfa", "demosaic", *settings], sort=False):
        lum = g["luminance"].to_numpy(float)
        mid, lo, hi = (crossing(lum, g[col]) for col in ("ysnr", "ysnr_high", "ysnr_low"))
        per = (g["scene_illuminance_lux"].to_numpy(float) / lum) if "scene_illuminance_lux" in g.columns else None
        lux_per = float(np.nanmean(per)) if per is not None and np.isfinite(per).any() else None
        rows.append({"cfa": key[0], "demosaic": key[1], "snr10_cd_m2": mid, "ci_low": lo, "ci_high": hi,
                     "note": "" if mid is not None else _note(lum, g["ysnr"].to_numpy(float)),
                     "snr10_lux": mid * lux_per if mid is not None and lux_per else None,
                     **dict(zip(settings, key[2:]))})
    return pd.DataFrame(rows, columns=SNR10_COLUMNS + settings)


def write_snr_tables(out_dir, metrics) -> list[Path]:
    """Write ``snr.csv`` and ``snr10.csv`` when the study measured ``ysnr``
    at two luminances or more (a stale pair is removed otherwise)."""
    from ..io import atomic_output

    out = Path(out_dir)
    snr = snr_table(metrics)
    paths = [out / "snr.csv", out / "snr10.csv"]
    if snr.empty or snr.groupby(["cfa", "demosaic"])["luminance"].nunique().max() < 2:
        for p in paths:
            p.unlink(missing_ok=True)
        return []
    for path, df in zip(paths, (snr, snr10_table(snr))):
        with atomic_output(path) as tmp:
            df.to_csv(tmp, index=False, float_format="%.6g")
    return paths
