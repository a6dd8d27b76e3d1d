"""A design's search, sized before it starts and refused above the limits.

Candidates per tile size: every raw layout (alphabet ** pixels) for the
exhaustive engine, population x generations evaluations for NSGA-II.  Time
from the measured throughputs (docs/design.md, ``benchmarks/bench_design.py``
on 2 cores: 43,046,721 raw 4x4 layouts enumerated, folded and scored in
97.8 s; 7,238 candidates/s end to end); peak memory of NSGA-II from pymoo's
population objects (measured: 1.7 kB per individual in one ``Population``;
parents, offspring and their merge are alive at once).

Refused (before anything is written) when the search would take more than
:data:`~cfa_mitsuba.study.sizing.MAX_HOURS` unless ``--force``, and always
when its population does not fit in memory (docs/design.md).
"""

from __future__ import annotations

__all__ = ["design_size", "check_design_size"]

from pathlib import Path

from ..errors import CfaMitsubaError

#: Seconds per raw layout of the exhaustive engine (97.8 s / 43,046,721).
EXHAUSTIVE_S_PER_RAW = 97.8 / 43_046_721
#: Seconds per NSGA-II evaluation (1 / 7,238 candidates per second end to end).
NSGA2_S_PER_EVALUATION = 1 / 7238
#: Bytes per NSGA-II population member (1.7 kB per individual x 3 populations).
NSGA2_BYTES_PER_INDIVIDUAL = 3 * 1700
_FIXED_BYTES = 400 * 2**20


def design_size(config) -> tuple[int, float, int, str]:
    """(candidates, estimated search seconds, peak bytes, per-tile text)."""
    candidates, seconds, peak, parts = 0, 0.0, _FIXED_BYTES, []
    for h, w in config.tiles:
        if config.engine[(h, w)] == "exhaustive":
            n = len(config.alphabet) ** (h * w)
            seconds += n * EXHAUSTIVE_S_PER_RAW
            parts.append(f"{h}x{w} exhaustive {n:.3g} raw layouts")
        else:
            n = config.population * config.generations
            seconds += n * NSGA2_S_PER_EVALUATION
            peak = max(peak, _FIXED_BYTES + config.population * NSGA2_BYTES_PER_INDIVIDUAL)
            parts.append(f"{h}x{w} NSGA-II {config.population:,} x {config.generations:,} generations")
        candidates += n
    return candidates, seconds, peak, "; ".join(parts)


def check_design_size(config, *, force: bool = False, log=None) -> None:
    """State a design's search size (one log line); refuse it (one
    :class:`CfaMitsubaError` with the estimate) above the limits."""
    from ..io.limits import available_memory_bytes, format_bytes
    from ..study.sizing import MAX_HOURS, _duration

    candidates, seconds, peak, parts = design_size(config)
    where = f"{Path(config.path).name}: " if config.path else ""
    text = (f"search: {candidates:.3g} candidate evaluation(s) ({parts}); about {_duration(seconds)}, "
            f"peak memory about {format_bytes(peak)}")
    have, source = available_memory_bytes()
    if have is not None and peak > have:
        raise CfaMitsubaError(f"{where}{text}: more than the {format_bytes(have)} available ({source}); "
                              "lower search.population")
    if seconds > MAX_HOURS * 3600 and not force:
        raise CfaMitsubaError(f"{where}{text}: more than the {MAX_HOURS:g} h limit (lower search.max_exhaustive, "
                              "population or generations; or --force to run it anyway)")
    if log is not None:
        log(text)
