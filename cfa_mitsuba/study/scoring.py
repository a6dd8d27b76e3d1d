"""Normalisation, combination and ranking of the eight metrics (Bae 2020
s. 2.2.9, eq. 8, Tables 2-3, Figs 16-17).

Each metric value v is mapped linearly onto a score with the paper's eq. 8,

    score = (v - worst) / (best - worst),

where (worst, best) is (max, min) for the lower-is-better metrics (dE, S-CIELAB,
AR error, MDSI) and (min, max) for the higher-is-better ones (SSIM, MTF50,
MSP, HaarPSI).  A CFA's score for a demosaic is the mean of its normalised
metrics; CFAs are ranked per demosaic (Table 3 rows, Fig 17 a-d) and over
all demosaics by the mean of those means (Table 3 "Total", Fig 17e).

Scores are **clipped to [0, 1]** by default, as the paper normalises "with
the dynamic range of [0, 1]": otherwise one value far outside a range (a
camera whose chirp never shows moire reports the chirp's top frequency, many
times the MSP range) would outweigh the other seven metrics in the mean.
The unclipped eq. 8 value is kept as ``raw_score`` and ``out_of_range``
flags the rows where clipping acted, which shows that a range no longer
spans the CFAs compared (the paper chose its ranges "by considering the
distribution of the measured values").  ``clip=False`` ranks on the raw
scores.

Default ranges: the paper's, except the MSP (see :func:`default_ranges`).
"""

from __future__ import annotations

__all__ = [
    "ScoreRange", "DEFAULT_RANGES", "METRIC_COLUMNS", "PAPER_PIXEL_PITCH_UM", "CHIRP_SAMPLES_PER_DEGREE",
    "default_ranges", "msp_range_cpd", "normalise", "score", "rank_table",
]

from dataclasses import dataclass

import numpy as np

from ..errors import CfaMitsubaError, require

#: Columns of a tidy metrics table (metrics.csv).
METRIC_COLUMNS = ("scene", "cfa", "demosaic", "luminance", "metric", "value", "unit")
#: The paper's pixel pitch: its Nyquist of 227.27 cy/mm is 1 / (2 x 2.2 um).
PAPER_PIXEL_PITCH_UM = 2.2


@dataclass(frozen=True)
class ScoreRange:
    """The values that score 0 (``worst``) and 1 (``best``), and the units they are in."""

    worst: float
    best: float
    units: tuple[str, ...] = ()

    def __post_init__(self):
        require(np.isfinite(self.worst) and np.isfinite(self.best) and self.worst != self.best,
                f"a score range needs two different finite ends, got worst={self.worst}, best={self.best}")

    def normalise(self, value):
        """Eq. 8: (value - worst) / (best - worst)."""
        return (np.asarray(value, dtype=np.float64) - self.worst) / (self.best - self.worst)


def msp_range_cpd(samples_per_degree: float, *, worst_cy_px: float = 0.04, best_cy_px: float = 0.30) -> ScoreRange:
    """An MSP score range in cycles per degree for a chirp sampled at ``samples_per_degree``.

    The paper's MSP range, 20..150, is a pixel position along its 500-px
    chirp (ISETCam reports a column index under the name "cpd").  For a
    linear chirp rising to twice Nyquist (1 cy/px) at the far end, column p
    is at p / 500 cy/px, so 20..150 is 0.04..0.30 cy/px: Bayer's MSP of 120
    is then 0.24 cy/px, just below the 0.25 cy/px Nyquist of its R and B
    planes, where colour aliasing is expected to start.  In cycles per degree
    that is 0.04..0.30 x samples per degree.

    Examples
    --------
    >>> msp_range_cpd(50.0)  # 500 px over 10 deg, the paper's chirp
    ScoreRange(worst=2.0, best=15.0, units=('cy/deg',))
    """
    require(np.isfinite(samples_per_degree) and samples_per_degree > 0,
            f"samples per degree must be positive, got {samples_per_degree}")
    return ScoreRange(round(worst_cy_px * samples_per_degree, 12), round(best_cy_px * samples_per_degree, 12),
                      ("cy/deg",))


#: Samples per degree of our chirp as rendered by default: 500 EXR pixels at
#: oversampling K = 2 over 10 degrees -> a 250-px camera image, 25 px/deg.
CHIRP_SAMPLES_PER_DEGREE = 25.0


def default_ranges(*, chirp_samples_per_degree: float = CHIRP_SAMPLES_PER_DEGREE,
                   pixel_pitch_um: float | None = None) -> dict[str, ScoreRange]:
    """Eq. 8's ranges for a study's geometry, from the metric records
    (:data:`cfa_mitsuba.metrics.METRICS`, ``score_range``).

    The paper's values, except where a record's ``range_scaling`` says:

    - ``moire`` (``'chirp_cy_px'``): the paper's 20..150 is a pixel position
      on its chirp; ours is in true cycles per degree, :func:`msp_range_cpd`
      at the chirp camera image's samples per degree (default 25: 1.0..7.5
      cy/deg);
    - ``mtf`` (``'pixel_pitch'``): 30..110 cy/mm as the paper (its 2.2 um
      pitch); with ``pixel_pitch_um`` the range is moved to that pitch so
      that the same cycles per pixel (0.066..0.242) score the same.

    The dE ranges apply to either dE formula (the paper's numbers).
    """
    from ..metrics import METRICS

    out = {}
    for r in METRICS.values():
        if not r.scored:
            continue
        worst, best = r.score_range
        units = tuple(r.range_units or (r.unit,))
        if r.range_scaling == "chirp_cy_px":
            out[r.name] = msp_range_cpd(chirp_samples_per_degree, worst_cy_px=worst, best_cy_px=best)
            continue
        if r.range_scaling == "pixel_pitch" and pixel_pitch_um is not None:
            require(np.isfinite(pixel_pitch_um) and pixel_pitch_um > 0,
                    f"pixel pitch must be positive, got {pixel_pitch_um}")
            k = PAPER_PIXEL_PITCH_UM / float(pixel_pitch_um)
            worst, best = worst * k, best * k
        out[r.name] = ScoreRange(worst, best, units)
    return out


#: :func:`default_ranges` for our default renders (chirp 25 px/deg; MTF50 in
#: cy/mm as the paper).  For a table in cy/px pass
#: ``ScoreRange(0.066, 0.242, ('cy/px',))`` (the paper's range at 2.2 um).
DEFAULT_RANGES: dict[str, ScoreRange] = default_ranges()


def _ranges(ranges) -> dict[str, ScoreRange]:
    out = dict(DEFAULT_RANGES)
    for name, r in (ranges or {}).items():
        if isinstance(r, ScoreRange):
            out[name] = r
        else:
            try:
                worst, best = (float(v) for v in r)
            except (TypeError, ValueError):
                raise CfaMitsubaError(f"range for {name!r} must be (worst, best), got {r!r}") from None
            out[name] = ScoreRange(worst, best, ())
    return out


def _check_table(metrics):
    import pandas as pd

    require(isinstance(metrics, pd.DataFrame), "metrics must be a pandas DataFrame")
    missing = [c for c in METRIC_COLUMNS if c not in metrics.columns]
    require(not missing, f"metrics table lacks column(s) {', '.join(missing)} (needs {', '.join(METRIC_COLUMNS)})")
    require(len(metrics) > 0, "metrics table is empty")
    values = pd.to_numeric(metrics["value"], errors="coerce")
    bad = metrics[~np.isfinite(values.to_numpy(dtype=float))]
    require(bad.empty, "metric values must be finite numbers; bad row(s): "
            + "; ".join(f"{r.cfa}/{r.demosaic}/{r.metric}={r.value!r}" for r in bad.head(3).itertuples()))
    keys = ["scene", "cfa", "demosaic", "luminance", "metric"]
    dup = metrics.duplicated(keys)
    require(not dup.any(), f"{int(dup.sum())} duplicate (scene, cfa, demosaic, luminance, metric) row(s)")


def normalise(metrics, ranges=None, *, clip: bool = True):
    """Add ``worst``, ``best``, ``raw_score`` (eq. 8), ``out_of_range`` and
    ``score`` (clipped to [0, 1] unless ``clip=False``) to a tidy metrics table.

    Parameters
    ----------
    metrics : DataFrame with columns ``scene, cfa, demosaic, luminance,
        metric, value, unit`` (one row per measurement).
    ranges : ``{metric: ScoreRange | (worst, best)}`` overriding
        :data:`DEFAULT_RANGES` (see :func:`default_ranges` for a study's
        own chirp sampling and pixel pitch); a ``ScoreRange`` with units is checked
        against each row's ``unit``.
    clip : clip ``score`` to [0, 1] (default True: see the module docstring).

    Returns
    -------
    DataFrame: a copy with ``worst``, ``best``, ``raw_score``,
    ``out_of_range``, ``score``.

    Examples
    --------
    >>> import pandas as pd
    >>> t = pd.DataFrame([dict(scene="puppy", cfa="bayer", demosaic="bilinear", luminance=100,
    ...                        metric="ssim", value=0.75, unit="")])
    >>> float(normalise(t)["score"].iloc[0])
    0.75
    """
    _check_table(metrics)
    rng = _ranges(ranges)
    out = metrics.copy()
    out["value"] = out["value"].astype(float)
    out["unit"] = out["unit"].fillna("").astype(str)
    worst, best = np.empty(len(out)), np.empty(len(out))
    for i, (name, unit) in enumerate(zip(out["metric"], out["unit"])):
        require(name in rng, f"no score range for metric {name!r} (give one in ranges=)")
        r = rng[name]
        require(not r.units or unit in r.units,
                f"metric {name!r} is in {unit!r} but its score range is in {' or '.join(repr(u) for u in r.units)}; "
                "record it in that unit or pass a range in yours")
        worst[i], best[i] = r.worst, r.best
    out["worst"], out["best"] = worst, best
    s = (out["value"].to_numpy() - worst) / (best - worst)
    out["raw_score"] = s
    out["out_of_range"] = (s < 0.0) | (s > 1.0)
    out["score"] = np.clip(s, 0.0, 1.0) if clip else s
    return out


def score(metrics, ranges=None, *, clip: bool = True):
    """Normalised scores and ranks, as one tidy table (scores.csv).

    Each input row gets ``worst``, ``best``, ``raw_score``, ``out_of_range``,
    ``score`` (see :func:`normalise`) and:

    - ``metric_rank``: the CFA's rank on this metric among the CFAs with the
      same demosaic and luminance (1 = best; the paper's red boxes, Table 2),
      ranked on ``raw_score`` so that clipping does not tie values beyond a
      range's best end;
    - ``mean_score``, ``n_metrics``: the mean of the CFA's scores for this
      demosaic and luminance (Table 3 rows) and how many metrics it averages;
    - ``demosaic_rank``: rank of ``mean_score`` among the CFAs (Fig 17 a-d);
    - ``total_score``: the mean over demosaics of ``mean_score`` at this
      luminance (Table 3 "Total"); ``total_rank``: its rank (Fig 17e).

    Ranks use the lowest rank for ties ('min').  Means are taken over the
    metrics present; compare CFAs only where ``n_metrics`` agree.

    Examples
    --------
    >>> import pandas as pd
    >>> rows = [dict(scene="puppy", cfa=c, demosaic="bilinear", luminance=100, metric="ssim", value=v, unit="")
    ...         for c, v in [("bayer", 0.75), ("rgbw1", 0.80)]]
    >>> score(pd.DataFrame(rows))[["cfa", "score", "demosaic_rank", "total_rank"]].to_dict("records")
    [{'cfa': 'bayer', 'score': 0.75, 'demosaic_rank': 2, 'total_rank': 2}, {'cfa': 'rgbw1', 'score': 0.8, 'demosaic_rank': 1, 'total_rank': 1}]
    """
    out = normalise(metrics, ranges, clip=clip)
    group = ["demosaic", "luminance"]
    # on the unclipped score: values past a range's best end still rank apart
    out["metric_rank"] = out.groupby(group + ["metric"])["raw_score"].rank(ascending=False, method="min").astype(int)
    per = (out.groupby(["cfa"] + group)["score"].agg(mean_score="mean", n_metrics="count").reset_index())
    per["demosaic_rank"] = per.groupby(group)["mean_score"].rank(ascending=False, method="min").astype(int)
    total = per.groupby(["cfa", "luminance"])["mean_score"].mean().rename("total_score").reset_index()
    total["total_rank"] = total.groupby("luminance")["total_score"].rank(ascending=False, method="min").astype(int)
    out = out.merge(per, on=["cfa"] + group, how="left").merge(total, on=["cfa", "luminance"], how="left")
    return out


def rank_table(scores, *, luminance=None, value: str = "mean_score"):
    """The paper's Table 3 (``value='mean_score'``) or Fig 17 (``'demosaic_rank'``)
    as a wide table: one row per demosaic plus ``'total'``, one column per CFA.

    ``scores`` is the output of :func:`score`; ``luminance`` picks one level
    (required when the table holds several).
    """
    require(value in ("mean_score", "demosaic_rank"), f"value must be 'mean_score' or 'demosaic_rank', got {value!r}")
    levels = sorted(scores["luminance"].unique())
    if luminance is None:
        require(len(levels) == 1, f"scores hold luminances {levels}: pick one with luminance=")
        luminance = levels[0]
    s = scores[scores["luminance"] == luminance]
    require(len(s) > 0, f"no scores at luminance {luminance!r} (have {levels})")
    per = s.drop_duplicates(["cfa", "demosaic"])
    wide = per.pivot(index="demosaic", columns="cfa", values=value)
    tot = per.drop_duplicates("cfa").set_index("cfa")["total_score" if value == "mean_score" else "total_rank"]
    wide.loc["total"] = tot
    return wide
