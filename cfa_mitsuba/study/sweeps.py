"""``[[sweep]]`` tables of a study config: extra conditions on any axis
(:data:`~.axes.AXES`), crossed."""

from __future__ import annotations

__all__ = ["SweepSpec", "_sweeps"]

from dataclasses import dataclass

from .checker import _Checker, _typename


@dataclass(frozen=True)
class SweepSpec:
    """Extra conditions for some metrics of some scenes: one list of values
    per swept axis (:data:`~.axes.AXES`), crossed (paper: S-CIELAB
    and SSIM on PUPPY at 3 ... 400 cd/m^2).  ``metrics`` empty: every
    metric each scene feeds."""

    scenes: tuple[str, ...]
    metrics: tuple[str, ...]
    values: dict


def _axis_values(ck: _Checker, axis: str, value, key: str) -> tuple:
    """A sweep's list of values for one axis, each checked by the axis's record."""
    from .axes import AXES

    if not isinstance(value, list) or not value:
        ck.fail(key, f"must be a non-empty list of values, got {_typename(value)}")
    out = tuple(AXES[axis].check(ck, v, f"{key}[{i}]") for i, v in enumerate(value))
    if len(set(out)) != len(out):
        ck.fail(key, "lists a value twice")
    return out


def _sweeps(ck: _Checker, sweep_data, scenes) -> list[SweepSpec]:
    """``[[sweep]]`` tables: ``scene`` or ``scenes``, ``metrics`` (default:
    all each scene feeds) and one list per axis (``luminances`` is the old
    name of ``luminance``); several axes in one table are crossed."""
    from .axes import AXES

    if not isinstance(sweep_data, list):
        ck.fail("sweep", "must be an array of tables ([[sweep]])")
    out = []
    for i, sw in enumerate(sweep_data):
        key = f"sweep[{i}]"
        ck.table(sw, key, {"scene": None, "scenes": None, "metrics": None, "luminances": None,
                           **{a: None for a in AXES}})
        if ("scene" in sw) == ("scenes" in sw):
            ck.fail(f"{key}.scene", "give either scene = \"NAME\" or scenes = [...] (exactly one)")
        names = ((ck.string(sw["scene"], f"{key}.scene"),) if "scene" in sw
                 else ck.string_list(sw["scenes"], f"{key}.scenes"))
        specs = []
        for j, sname in enumerate(names):
            spec = next((s for s in scenes if s.name == sname), None)
            if spec is None:
                where = f"{key}.scene" if "scene" in sw else f"{key}.scenes[{j}]"
                ck.fail(where, f"{sname!r} is not one of this study's scenes")
            specs.append(spec)
        fed = [m for s in specs for m in s.metrics]
        ms = ck.string_list(sw["metrics"], f"{key}.metrics") if "metrics" in sw else ()
        for j, m in enumerate(ms):
            if m not in fed:
                ck.fail(f"{key}.metrics[{j}]", f"scene {', '.join(map(repr, names))} does not feed metric {m!r} "
                                               f"(it feeds {', '.join(dict.fromkeys(fed))})")
        if "luminances" in sw and "luminance" in sw:
            ck.fail(f"{key}.luminances", "give luminance or its old name luminances, not both")
        values = {}
        for axis in AXES:
            name = "luminances" if axis == "luminance" and "luminances" in sw else axis
            if name in sw:
                values[axis] = _axis_values(ck, axis, sw[name], f"{key}.{name}")
        if not values:
            ck.fail(key, f"sweeps no axis (give a list for one of: {', '.join(AXES)})")
        out.append(SweepSpec(tuple(names), tuple(ms), values))
    return out
