"""The conditions an answer holds under, stated beside it (issue 46): at the
base luminance, each CFA family's exposure regime (exposure time and
analogue gain over the scenes, from metrics.csv's ``exposure_s`` and
``analog_gain``: the exposure program's choice) and the f-number of each
scene (metrics.csv's ``f_number``: the one the optics used).

The report's summary prints :func:`condition_lines`; README's ranking quotes
the same lines through the ``@conditions`` generator
(report/docs_tables_pages.py).
"""

from __future__ import annotations

__all__ = ["family_regimes", "f_numbers", "condition_lines", "exposure_words", "exposure_policy_sentence"]

import math


def _fraction(seconds: float) -> str:
    """1/30 s for 0.0333 s; 2 s as it is."""
    if seconds >= 1 or seconds <= 0:
        return f"{seconds:.3g} s"
    return f"1/{1 / seconds:.0f} s"


def _base_rows(metrics, luminance):
    m = metrics
    if "base" in m.columns:
        m = m[m["base"].astype(str).str.lower().isin(("true", "1"))]
    if luminance is None:
        luminance = float(m["luminance"].astype(float).min()) if len(m) else None
    return m[m["luminance"].astype(float) == luminance] if luminance is not None else m.iloc[0:0], luminance


def _family(cfa: str, facts: dict) -> str:
    """The paper's family for its CFAs (RGB, CMY, RGBW), else the filter letters' family."""
    from .paper_data import family
    from .tiles import family_of

    if family(cfa):
        return family(cfa)
    channels = (facts.get(cfa) or {}).get("channels")
    return family_of(channels) if channels else cfa


def family_regimes(metrics, cfa_facts: dict | None = None, luminance=None) -> list[tuple]:
    """[(family, CFAs, (shortest, longest exposure s), (lowest, highest analogue gain))]
    at the base ``luminance`` (None: the lowest base level), over every scene."""
    rows, _ = _base_rows(metrics, luminance)
    if not len(rows) or not {"exposure_s", "analog_gain"} <= set(rows.columns):
        return []
    facts = cfa_facts or {}
    out: dict = {}
    for cfa, g in rows.groupby("cfa", sort=False):
        t = g["exposure_s"].astype(float)
        a = g["analog_gain"].astype(float)
        if not (t.notna().any() and a.notna().any()):
            continue
        fam = _family(str(cfa), facts)
        got = out.setdefault(fam, [[], [math.inf, -math.inf], [math.inf, -math.inf]])
        got[0].append(str(cfa))
        got[1] = [min(got[1][0], t.min()), max(got[1][1], t.max())]
        got[2] = [min(got[2][0], a.min()), max(got[2][1], a.max())]
    return [(fam, cfas, tuple(t), tuple(a)) for fam, (cfas, t, a) in out.items()]


def exposure_words(t: tuple, a: tuple, cap: float | None = None) -> str:
    """'1/30 s, analogue gain 1.29-5.01' style words for one family."""
    time = _fraction(t[0]) if abs(t[1] - t[0]) <= 1e-9 * max(t) else f"{_fraction(t[0])} to {_fraction(t[1])}"
    if cap and abs(t[0] - cap) <= 1e-6 * cap and abs(t[1] - cap) <= 1e-6 * cap:
        time += " (the program's cap) on every scene"
    gain = f"{a[0]:.2f}" if abs(a[1] - a[0]) < 0.005 else f"{a[0]:.2f}-{a[1]:.2f}"
    return f"{time}, analogue gain {gain}"


def f_numbers(metrics, luminance=None) -> dict:
    """{scene: [f-numbers]} at the base luminance (metrics.csv's ``f_number``)."""
    rows, _ = _base_rows(metrics, luminance)
    if "f_number" not in rows.columns:
        return {}
    return {str(s): sorted(set(g["f_number"].astype(float).dropna())) for s, g in rows.groupby("scene", sort=False)}


def condition_lines(metrics, cfa_facts: dict | None = None, config: dict | None = None, luminance=None) -> list[str]:
    """The sentences: each family's exposure regime, then the f-number of every scene."""
    _, lum = _base_rows(metrics, luminance)
    from ..study.config import exposure_program_of

    program = exposure_program_of(config)
    cap = program.max_exposure_s if program.policy == "program" else None
    out = []
    regimes = family_regimes(metrics, cfa_facts, luminance)
    if regimes and lum is not None:
        parts = [f"{fam} ({len(cfas)} CFA{'s' if len(cfas) != 1 else ''}): {exposure_words(t, a, cap)}"
                 for fam, cfas, t, a in regimes]
        out.append(f"Exposure at {lum:g} cd/m² (the base condition), over the scenes: " + "; ".join(parts) + ".")
    fn = f_numbers(metrics, luminance)
    if fn:
        values = {tuple(v) for v in fn.values()}
        if len(values) == 1 and len(next(iter(values))) == 1:
            out.append(f"Lens: f/{next(iter(values))[0]:g} for every scene.")
        else:
            out.append("Lens: " + "; ".join(f"{s} f/{', f/'.join(f'{x:g}' for x in v)}" for s, v in fn.items()) + ".")
    return out


def exposure_policy_sentence(config: dict | None) -> str:
    """What the study's exposure policy did at each luminance (config.json's
    ``capture``; docs/study.md, "Exposure policies")."""
    from ..study.config import exposure_program_of

    cfg = config or {}
    cap = {**(cfg.get("sensor") or {}), **(cfg.get("capture") or {})}
    if str(cap.get("exposure", "auto")) != "auto":
        return f"Every capture used the fixed exposure {cap.get('exposure')} s, no gain."
    program = exposure_program_of(cfg)  # the program's own defaults where config.json names none
    policy, t_max, g_max, ref = (program.policy, program.max_exposure_s, program.max_analog_gain,
                                 program.reference_luminance_cd_m2)
    return {
        "program": f"Each CFA was metered at each luminance by the exposure program: the time grows as light "
                   f"falls up to {_fraction(t_max)}, then the analogue gain up to {g_max:g}, then digital gain, so "
                   "below the level where the time reaches its cap each CFA collects fewer photons and shows "
                   "more noise (metrics.csv's exposure_s and analog_gain say where).",
        "bayer": "Every CFA was captured at the time and gains the exposure program gives Bayer at the same "
                 "scene and luminance (clear pixels may clip in bright light).",
        "reference": f"The exposure was chosen at the reference luminance ({ref} cd/m²) and kept at every level, "
                     "so darker scenes give fewer photons and brighter ones can saturate pixels.",
        "each": "ISETCam's auto exposure was chosen anew at each luminance, without a cap on the time.",
    }.get(policy, f"Exposure policy {policy!r}.")
