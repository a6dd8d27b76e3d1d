"""A design's search, sized before it starts and refused above the limits.

Candidates per tile size: every raw layout (alphabet ** pixels) for the
exhaustive engine, population x generations evaluations for NSGA-II.  Time
from the measured throughputs (docs/design.md, ``benchmarks/bench_design.py``
on 2 cores: 43,046,721 raw 4x4 layouts enumerated and folded in 54.2 s;
7,238 candidates/s end to end before issue 26), plus the demosaic impulse
responses of every distinct candidate for each demosaic the proxy takes
(:data:`IMPULSE_S_PER_CANDIDATE`); peak memory of NSGA-II from pymoo's
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

#: Seconds per raw layout of the exhaustive engine's enumeration and folding
#: (54.2 s / 43,046,721 for 4x4 tiles of three letters).
EXHAUSTIVE_S_PER_RAW = 54.2 / 43_046_721
#: Seconds per NSGA-II evaluation without the demosaic impulse responses (1 / 7,238 per second end to end).
NSGA2_S_PER_EVALUATION = 1 / 7238
#: Seconds per distinct candidate and demosaic for the proxy's impulse
#: responses (issue 26: 28 ms measured for 4x4 tiles, 19 ms for 3x3, at a
#: load average of 11 on 2 cores; an upper bound on an idle machine).
IMPULSE_S_PER_CANDIDATE = 0.028
#: Seconds per L-BFGS-B iteration of the gradient method (about 1.3 evaluations
#: of the differentiable proxy and its gradient, 3 channels; measured on this
#: 2-core machine, loaded).
GRADIENT_S_PER_ITERATION = 0.03
#: Bytes per NSGA-II population member (1.7 kB per individual x 3 populations).
NSGA2_BYTES_PER_INDIVIDUAL = 3 * 1700
_FIXED_BYTES = 400 * 2**20


def design_size(config) -> tuple[int, float, int, str]:
    """(candidates, estimated search seconds, peak bytes, per-tile text)."""
    from .search import proxy_settings

    if config.method == "gradient":  # weights x starts L-BFGS-B runs of at most max_iter iterations
        g = config.gradient
        n = len(g.weights) * g.starts * g.max_iter
        return (n, n * GRADIENT_S_PER_ITERATION, _FIXED_BYTES,
                f"gradient: {len(g.weights)} weights x {g.starts} starts x at most {g.max_iter} L-BFGS-B iterations")
    per_candidate = IMPULSE_S_PER_CANDIDATE * len(proxy_settings(config).demosaics)
    candidates, seconds, peak, parts = 0, 0.0, _FIXED_BYTES, []
    for h, w in config.tiles:
        if config.engine[(h, w)] == "exhaustive":
            n = len(config.alphabet) ** (h * w)
            # translations and mirrors fold about 2 h w raw tiles into one distinct candidate
            seconds += n * EXHAUSTIVE_S_PER_RAW + n / (2 * h * w) * per_candidate
            parts.append(f"{h}x{w} exhaustive {n:.3g} raw layouts")
        else:
            n = config.population * config.generations
            seconds += n * (NSGA2_S_PER_EVALUATION + per_candidate)
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
