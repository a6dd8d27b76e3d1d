"""A metric's options checked before a study starts, by the metric itself.

A study's ``[metrics.<name>]`` options are keywords of the metric's
function.  Their *types* are checked against the signature when the config
is read; their *values* (``version = "1999"``, ``matrix = "xyz3"``) only the
function knows.  :func:`check_options` asks it: the metric runs once on a
small synthetic pair (a slanted edge in XYZ with 2 % noise, the geometry a
chirp or an S-CIELAB viewing would give), with and without the options.
When only the run with the options fails, its error is the options' fault
and is raised; when both fail, the synthetic pair is at fault and the check
says nothing (the study then reports it per row, as before).
"""

from __future__ import annotations

__all__ = ["check_options"]

import numpy as np

from ..errors import CfaMitsubaError, one_line

_WHITE = (95.05, 100.0, 108.9)


def _inputs():
    from .inputs import MetricInputs

    h, w = 48, 64
    yy, xx = np.mgrid[0:h, 0:w]
    edge = (xx - w / 2 + 0.2 * (yy - h / 2) > 0) * 0.7 + 0.1
    reference = edge[..., None] * np.asarray(_WHITE)
    test = reference * (1 + 0.02 * np.random.default_rng(0).standard_normal(reference.shape))
    geometry = {"samples_per_degree": 20.0, "frequency_cy_per_deg": np.linspace(1.0, 10.0, w), "row": h // 2}
    return MetricInputs(reference, test, _WHITE, geometry=geometry, pixel_pitch_um=2.2)


def check_options(name: str, options: dict) -> None:
    """Raise :class:`CfaMitsubaError` with the metric's own message when
    ``options`` make metric ``name`` fail on an input it otherwise measures."""
    from .registry import evaluate

    if not options:
        return
    try:
        evaluate(name, _inputs(), **options)
        return
    except (CfaMitsubaError, ValueError, TypeError, KeyError, IndexError) as exc:
        error = (f"unknown value {exc.args[0]!r}" if isinstance(exc, KeyError) and exc.args
                 else one_line(exc))
    try:
        evaluate(name, _inputs())
    except (CfaMitsubaError, ValueError, TypeError, KeyError, IndexError):
        return  # the synthetic pair does not suit this metric: nothing learnt about the options
    given = ", ".join(f"{k} = {v!r}" for k, v in options.items())
    raise CfaMitsubaError(f"{error} (with {given})")
