"""``[metrics.<name>]`` tables of a study config: keyword options passed to
a metric's function for every evaluation (``version = "1976"`` makes the
CIE 1976 dE*ab the Macbeth headline; ``matrix``, ``samples_per_degree``,
``boundary`` give S-CIELAB ISETCam's settings), checked against the
function's own signature before any work starts."""

from __future__ import annotations

__all__ = ["metric_options", "GEOMETRY_KEYWORDS"]

import inspect

from ..errors import CfaMitsubaError
from .checker import _Checker, _typename

#: Keywords the chain fills from the scene (patches, edge ROI, chirp row and
#: frequencies, grey steps): a config cannot set them.
GEOMETRY_KEYWORDS = frozenset({"patches", "grey_patches", "roi", "row", "steps", "frequency_cy_per_deg",
                               "reference", "pixel_pitch_um"})


def _option(ck: _Checker, param: inspect.Parameter, value, key: str):
    default = param.default
    if isinstance(default, bool):
        return ck.boolean(value, key)
    if isinstance(default, str):
        return ck.string(value, key)
    if isinstance(default, (int, float)) or default is inspect.Parameter.empty:
        if isinstance(default, int) and not isinstance(default, bool) and isinstance(value, int):
            return ck.integer(value, key)
        return ck.number(value, key)
    if isinstance(value, (str, bool, int, float)):
        return value
    return ck.fail(key, f"must be a string, number or boolean, got {_typename(value)}")


def metric_options(ck: _Checker, data) -> dict:
    """{metric: {keyword: value}} from the ``[metrics]`` table: each key a
    computable metric, each option a keyword-only parameter of its function
    that the scene geometry does not supply, of the parameter's type."""
    from ..metrics import get_metric, metric_names

    ck.table(data, "metrics", {m: None for m in metric_names()})
    out = {}
    for name, opts in data.items():
        fn = get_metric(name).function
        params = {p.name: p for p in inspect.signature(fn).parameters.values()
                  if p.kind is inspect.Parameter.KEYWORD_ONLY and p.name not in GEOMETRY_KEYWORDS}
        ck.table(opts, f"metrics.{name}", params)
        out[name] = {k: _option(ck, params[k], v, f"metrics.{name}.{k}") for k, v in opts.items()}
        try:  # issue 27: the values too, by the metric itself, before any work (metrics.dry)
            from ..metrics.dry import check_options

            check_options(name, out[name])
        except CfaMitsubaError as exc:
            ck.fail(f"metrics.{name}", str(exc))
    return out
