"""How each denoiser's one tuning constant was chosen, and the data.

Rule (the same for every method, applied once; never per CFA, sensor or
light): the strength, on a grid of 0.25 to 3 predicted noise standard
deviations, that minimises the mean squared error of the denoised raw
mosaic against the noise-free one, summed over nine captures: three
photographs that are not in any evaluation (scikit-image's ``astronaut``,
``coffee`` and ``chelsea``, central 192 x 192 crops, sRGB decoded to
linear) each mosaicked through Bayer and exposed to a mean of 10, 50 and
250 electrons per pixel (Poisson shot noise, the default sensor's 6.2 e-
read noise and 12-bit ADC at gain 1), denoised in the raw domain.  The
grid, the errors and the winner of each method are in
``cfa_mitsuba/data/denoise_tuning.csv``, written by
``benchmarks/tune_denoise.py``; the winners are typed into the methods'
records (``strength``), and tests/isp/test_denoise.py checks that each
record's constant is the data's minimum.
"""

from __future__ import annotations

__all__ = ["TUNING_CSV", "rule", "tuning_table", "best_constant"]

import csv
from pathlib import Path

#: The tuning data (benchmarks/tune_denoise.py writes it).
TUNING_CSV = Path(__file__).resolve().parents[2] / "data" / "denoise_tuning.csv"


def rule(name: str) -> str:
    """The tuning rule of method ``name``, one line, for its record."""
    return (f"{name}: the strength (x the predicted noise sd) minimising the summed MSE of the denoised raw mosaic "
            "against the noise-free one over scikit-image's astronaut, coffee and chelsea (192 x 192, Bayer, "
            "10/50/250 e- mean, default sensor noise); data: cfa_mitsuba/data/denoise_tuning.csv "
            "(benchmarks/tune_denoise.py)")


def tuning_table() -> list[dict]:
    """The rows of :data:`TUNING_CSV`: method, strength, total_mse, and the per-capture errors."""
    with open(TUNING_CSV, newline="") as fh:
        return [dict(r) for r in csv.DictReader(fh)]


def best_constant(name: str) -> float:
    """The strength of the grid with the least summed MSE for ``name``."""
    rows = [r for r in tuning_table() if r["method"] == name]
    return float(min(rows, key=lambda r: float(r["total_mse"]))["strength"])
