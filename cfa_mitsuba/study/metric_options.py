"""``[metrics.<name>]`` tables of a study config: keyword options passed to
a metric's function for every evaluation (``version = "1976"`` makes the
CIE 1976 dE*ab the Macbeth headline; ``matrix``, ``samples_per_degree``,
``boundary`` give S-CIELAB ISETCam's settings), checked against the
function's own signature before any work starts."""

from __future__ import annotations

__all__ = ["metric_options", "function_options"]

import inspect

from ..errors import CfaMitsubaError
from .checker import _Checker, _typename


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


def function_options(ck: _Checker, opts, key: str, params: dict) -> dict:
    """``opts`` (a config table) checked against ``params`` ({name:
    inspect.Parameter}: the options a function takes), each value of the
    parameter's type; an unknown key names the ones allowed."""
    ck.table(opts, key, params)
    return {k: _option(ck, params[k], v, f"{key}.{k}") for k, v in opts.items()}


def metric_options(ck: _Checker, data) -> dict:
    """{metric: {keyword: value}} from the ``[metrics]`` table: each key a
    computable metric, each option a keyword-only parameter of its function
    that the scene geometry does not supply, of the parameter's type."""
    from ..metrics import metric_names, metric_parameters

    ck.table(data, "metrics", {m: None for m in metric_names()})
    out = {name: function_options(ck, opts, f"metrics.{name}", metric_parameters(name))
           for name, opts in data.items()}
    from ..metrics.dry import check_options  # issue 27: the values too, by the metric itself, before any work

    for name, opts in out.items():
        try:
            check_options(name, opts)
        except CfaMitsubaError as exc:
            ck.fail(f"metrics.{name}", str(exc))
    return out
