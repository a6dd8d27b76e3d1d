"""How far a designed filter is from a real one (docs/design.md,
"Manufacturability"): per free letter, the smoothness of its curve (the
largest change per 10 nm), its peak, and the nearest measured filter in
the project's spectra sets by spectral angle.

The spectral angle between two band QE curves a and b (the study's 31
bands) is arccos(a.b / (|a| |b|)) in degrees (Kruse et al. 1993, the
spectral angle mapper): 0 for the same shape at any scale.  The nearest
*set* is the one whose same letters (R to R, G to G, ...) are nearest on
average: how far the design is from a filter set that exists as a whole.

The curve judged is the dye's transmittance for ``spline`` letters (what a
dye or interference-filter maker would make) and the QE for ``mixture``
letters (mixtures of whole-pixel curves).  Hand-written: a few lines of
numpy, no library computes these for filter sets.

References
----------
F. A. Kruse et al., "The spectral image processing system (SIPS)", Remote
Sensing of Environment 44 (1993) 145-163 (the spectral angle).
"""

from __future__ import annotations

__all__ = ["spectral_angle_deg", "curve_stats", "nearest_filters", "manufacturability"]

import functools
import json

import numpy as np

from .. import spectra as _spectra


def spectral_angle_deg(a, b) -> float:
    """The angle (degrees) between two non-negative curves on one grid.

    >>> round(spectral_angle_deg([1, 0], [0, 1]), 6), round(spectral_angle_deg([1, 2], [2, 4]), 6)
    (90.0, 0.0)
    """
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    c = float(a @ b / max(np.linalg.norm(a) * np.linalg.norm(b), 1e-300))
    return float(np.degrees(np.arccos(np.clip(c, -1.0, 1.0))))


def curve_stats(wavelengths_nm, curve) -> tuple[float, float]:
    """(largest |change| per 10 nm, peak) of a tabulated curve (fraction)."""
    x, y = np.asarray(wavelengths_nm, dtype=np.float64), np.asarray(curve, dtype=np.float64)
    return float(np.max(np.abs(np.diff(y) / np.diff(x))) * 10.0), float(y.max())


@functools.lru_cache(maxsize=1)
def _measured() -> dict:
    """{set: {letter: band QE}} of every shipped spectra set's single-letter curves."""
    from ..sensor.spectra_sets import get_spectra_set, list_spectra_sets

    wl = _spectra.DEFAULT_WAVELENGTHS
    out = {}
    for name in list_spectra_sets():
        sset = get_spectra_set(name)
        out[name] = {c: _spectra.band_average(*sset.curves[c], wl) for c in sset.letters if len(c) == 1}
    return out


def nearest_filters(curves: dict) -> dict:
    """For ``{letter: band QE (31,)}``: per letter its nearest measured curve
    (``set:letter``, angle) among every set's same letter, and the nearest
    set over all the letters (mean angle)."""
    per, sets = {}, []
    for name, letters in _measured().items():
        if all(a in letters for a in curves):
            angles = [spectral_angle_deg(q, letters[a]) for a, q in curves.items()]
            sets.append((float(np.mean(angles)), name))
        for a, q in curves.items():
            if a in letters:
                ang = spectral_angle_deg(q, letters[a])
                if a not in per or ang < per[a][1]:
                    per[a] = (f"{name}:{a}", ang)
    best = min(sets) if sets else (float("nan"), "")
    return {"per_letter": per, "set": best[1], "set_angle_deg": best[0]}


def manufacturability(config, params: list[dict]) -> dict:
    """The candidates.csv columns of one candidate's free letters:
    ``max_slope_per_10nm`` and ``peak`` (the worst letter), ``nearest_set``
    and ``nearest_set_angle_deg``, and ``manufacturability`` (JSON per
    letter: curve judged, slope, peak, nearest measured curve and angle)."""
    from .spectra import GRID_NM, letter_curves, spline_basis

    spec = config.spectra
    curves = letter_curves(config.alphabet, config.spectra_set, spec, params)
    wl = _spectra.DEFAULT_WAVELENGTHS
    free = dict(zip(spec.letters, params))
    bands = {a: _spectra.band_average(*curves[a], wl) for a in free}
    near = nearest_filters(bands)
    per = {}
    for a, p in free.items():
        if spec.family == "spline":
            what, y = "transmittance", spline_basis(len(p["coefficients"])) @ np.asarray(p["coefficients"])
        else:
            what, y = "qe", curves[a][1]
        slope, peak = curve_stats(GRID_NM, y)
        nl, ang = near["per_letter"].get(a, ("", float("nan")))
        per[a] = {"curve": what, "max_slope_per_10nm": round(slope, 4), "peak": round(peak, 4), "nearest": nl,
                  "angle_deg": round(ang, 2)}
    return {"max_slope_per_10nm": max(v["max_slope_per_10nm"] for v in per.values()),
            "peak": max(v["peak"] for v in per.values()), "nearest_set": near["set"],
            "nearest_set_angle_deg": near["set_angle_deg"], "manufacturability": json.dumps(per)}
