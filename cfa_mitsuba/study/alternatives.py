"""The conventions a study's scores rest on, and the alternatives a reader
could reasonably choose instead (issue 46): each range policy
(:data:`.ranking.POLICIES`), each convention for censored values
(:data:`.censored.CONVENTIONS`) and each metric left out in turn.

:class:`ScoringSetup` holds what scoring needs (the paper's ranges, the
ideal sensor's values, the study's policy, the config's own ranges, the
clipping and the censored convention) and scores a study's realisations
under any policy and convention; :func:`score_alternatives` gives the
study's own scoring first and then every alternative that changes the
scores, each as per-realisation scored rows, so that study/decisions.py
recomputes each decision under each and says which change the answer.
The alternative exposure protocol is not among them: a study runs one
exposure policy (docs/study.md, "Exposure policies"), so no study holds
the rows to decide under another; a second study under the other policy
does (docs/low-light/).
"""

from __future__ import annotations

__all__ = ["ScoringSetup", "Alternative", "score_alternatives", "METRIC_OUT"]

from dataclasses import dataclass, field

from .censored import CONVENTIONS, DEFAULT_CONVENTION, convention_label, values_for_scoring

#: The label of a metric left out (decisions.csv's ``depends_on``).
METRIC_OUT = "without {metric}"
_COLS = ["scene", "cfa", "demosaic", "luminance", "metric", "value", "unit", "realisation"]


@dataclass(frozen=True)
class ScoringSetup:
    """What scoring a study needs besides its rows: ``paper`` (the paper's
    ranges for this study's geometry), ``ideal`` ({metric: the ideal
    sensor's value}), ``policy`` (the study's range policy), ``overrides``
    ({metric: (worst, best)}, the config's own ranges, which win under every
    policy), ``clip`` and ``convention`` (how a bound is scored)."""

    paper: dict
    ideal: dict
    policy: str
    overrides: dict = field(default_factory=dict)
    clip: bool = True
    convention: str = DEFAULT_CONVENTION

    def ranges(self, policy: str, means) -> tuple[dict, list[str]]:
        """({metric: ScoreRange}, [constant metrics]) of ``policy`` on the
        mean values ``means``, the config's own ranges applied on top."""
        from .ranking import policy_ranges
        from .scoring import ScoreRange

        ranges, constant = policy_ranges(policy, means, self.paper, self.ideal)
        for m, (worst, best) in self.overrides.items():  # the config's own ranges win
            ranges[m] = ScoreRange(worst, best, ())
            if m in constant and worst != best:
                constant.remove(m)
        return ranges, constant

    def every(self, real, ranges: dict, constant=(), convention: str | None = None):
        """Per-realisation scored rows of ``real`` (the scored metrics'
        realisations, ``censored`` included) under ``ranges``, bounds scored
        by ``convention`` (default: the study's), constant metrics left out."""
        from .ranking import _realisation_scores

        cols = _COLS + (["render_seed"] if "render_seed" in real.columns else [])
        kept = real[~real["metric"].isin(list(constant))]
        if kept.empty:
            return kept
        scored = values_for_scoring(kept, ranges, convention or self.convention)
        return _realisation_scores(scored[cols], ranges, self.clip)


@dataclass
class Alternative:
    """One way of scoring: its ``label`` (``""`` for the study's own),
    ``every`` (per-realisation scored rows) and ``ranges``."""

    label: str
    every: object
    ranges: dict


def score_alternatives(setup: ScoringSetup, real, means, own=None) -> list[Alternative]:
    """The study's scoring, then each other range policy and each other
    censored-value convention (only when some realisation is a bound), as
    :class:`Alternative`; ``own``: (ranges, constant, every) already made
    for the study's own scoring."""
    from .censored import is_bound
    from .ranking import POLICIES

    if own is None:
        ranges, constant = setup.ranges(setup.policy, means)
        own = (ranges, constant, setup.every(real, ranges, constant))
    out = [Alternative("", own[2], own[0])]
    for policy in POLICIES:
        if policy == setup.policy:
            continue
        ranges, constant = setup.ranges(policy, means)
        out.append(Alternative(f"ranges: {policy}", setup.every(real, ranges, constant), ranges))
    if "censored" in real.columns and is_bound(real["censored"]).any():
        for conv in CONVENTIONS:
            if conv != setup.convention:
                out.append(Alternative(convention_label(conv), setup.every(real, own[0], own[1], conv), own[0]))
    return out
