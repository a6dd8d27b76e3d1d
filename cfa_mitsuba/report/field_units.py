"""The field's units beside ours in the report's conventions (issue 50):
the scenes' light in lux and the captures' exposure in lux-seconds (from
metrics.csv's ``scene_illuminance_lux`` and ``sensor_exposure_lux_s``),
SNRs in dB, MTF50 in cy/mm, cy/px and LW/PH, the aliasing percentage."""

from __future__ import annotations

__all__ = ["unit_items"]

import html

import numpy as np

from .results import Results


def _light(res: Results) -> str | None:
    m = res.metrics
    lum = res.primary_luminance
    if lum is None or "scene_illuminance_lux" not in m.columns:
        return None
    at = m[(m["luminance"] == lum) & np.isfinite(m["scene_illuminance_lux"].astype(float))]
    if not len(at):
        return None
    per_scene = at.groupby("scene", sort=False)["scene_illuminance_lux"].median()
    scenes = ", ".join(f"{html.escape(str(s))} {v:,.0f} lux" for s, v in per_scene.items())
    text = (f"<b>Light</b>: luminance (cd/m²) is the scene's mean luminance; the same light as the illuminance on "
            f"the scene, π × the luminance of its white (a white diffuser under E lux has E/π cd/m²; the charts "
            f"are lit by D65, the puppy's white is its white panel), at {lum:g} cd/m²: {scenes}.")
    if "sensor_exposure_lux_s" in m.columns:
        h = at["sensor_exposure_lux_s"].astype(float)
        h = h[np.isfinite(h) & (h > 0)]
        if len(h):
            text += (f" The captures' sensor-plane exposure (the pixels' mean illuminance × the exposure time, "
                     f"ISO 12232's H) there: {h.min():.3g} to {h.max():.3g} lux·s. Both are columns of metrics.csv "
                     f"(scene_illuminance_lux, sensor_exposure_lux_s) for every row.")
    return text


def unit_items(res: Results) -> list[str]:
    """Bullet items (HTML) for the report's 'Units and conventions'."""
    items = [_light(res)]
    items.append("<b>SNR</b>: a ratio and, in metrics.csv's value_db / ci_low_db / ci_high_db and snr.csv's "
                 "*_db columns, 20 log10 of it in dB. <b>Dynamic range</b> (ISO 15739, steps.csv): the luminance "
                 "that clips the first channel over the luminance of SNR 1, in dB and stops.")
    items.append("<b>MTF50</b> also in cycles per pixel (mtf50-cy-px; 0.5 is Nyquist) and in line widths per "
                 "picture height (mtf50-lw-ph: 2 × cy/px × the image's height, or [metrics.mtf] "
                 "picture_height_px); the whole curve of each capture is in mtf.csv. <b>Aliasing</b> (mtf-alias): "
                 "ISO 12233's percentage, the luminance MTF's area above Nyquist over its area up to 1 cy/px.")
    return [i for i in items if i]
