"""Conditions: one value of every study axis (:mod:`.axes`) for one evaluation.

A :class:`Condition` holds a value for each registered axis (``luminance``,
``f_number``, ``pixel_pitch_um``, ``exposure``, ``read_noise_e``, ``seed``,
``spectra``, ``readout``, ``denoise``, ``sharpen``, and any axis a plug-in registers), read as
attributes (``cond.luminance``).  An axis not given takes its default
(:meth:`.axes.Axis.default_value`: the stage's own parameter default).  A
config's base values come from ``[optics]``, ``[sensor]``, ``[isp]``,
``[metrics.<name>]`` and the top-level ``seed``
(:meth:`.chain.ChainSettings.base_condition`); ``[[sweep]]`` tables cross
lists of axis values (:func:`cross`).
"""

from __future__ import annotations

__all__ = ["AXES", "Condition", "cross"]

import itertools

from .axes import AXES
from .details_layout import safe_label


class Condition:
    """The value of every axis for one evaluation (immutable, hashable).

    ``Condition(100.0)`` or ``Condition(luminance=100.0, readout="bin")``;
    an axis not named takes its default.  ``f_number`` None means the
    scene's own (a render's sidecar records the aperture it modelled;
    charts: the optics default f/4); ``exposure`` is ``"auto"`` or seconds;
    ``spectra`` None means each CFA's own spectra set.
    """

    __slots__ = ("_values",)

    def __init__(self, luminance=None, **values):
        if luminance is not None:
            values["luminance"] = luminance
        unknown = set(values) - set(AXES)
        if unknown:
            raise TypeError(f"Condition has no axis {sorted(unknown)} (axes: {', '.join(AXES)})")
        full = {name: values[name] if name in values else axis.default_value() for name, axis in AXES.items()}
        if isinstance(full["luminance"], int):
            full["luminance"] = float(full["luminance"])
        object.__setattr__(self, "_values", tuple(full.items()))

    def __getattr__(self, name):
        if name.startswith("_"):
            raise AttributeError(name)
        for k, v in object.__getattribute__(self, "_values"):
            if k == name:
                return v
        if name in AXES:  # registered after this condition was made
            return AXES[name].default_value()
        raise AttributeError(f"Condition has no axis {name!r}")

    def __setattr__(self, name, value):
        raise AttributeError("a Condition is immutable; use with_()")

    def __reduce__(self):
        return (_rebuild, (self._values,))

    def __eq__(self, other):
        return isinstance(other, Condition) and self._values == other._values

    def __hash__(self):
        return hash(self._values)

    def __repr__(self):
        return "Condition(" + ", ".join(f"{k}={v!r}" for k, v in self._values) + ")"

    def with_(self, **changes) -> "Condition":
        return Condition(**{**dict(self._values), **changes})

    def to_dict(self) -> dict:
        return dict(self._values)

    def label(self, base: "Condition | None" = None) -> str:
        """A short text naming the axes that differ from ``base`` (all but
        luminance when no base), e.g. ``L100_f8_seed2``; file-name safe."""
        parts = [f"L{self.luminance:g}"]
        for axis, v in self._values:
            if axis == "luminance":
                continue
            if base is not None and v == getattr(base, axis):
                continue
            if base is None and v is None:
                continue
            short = AXES[axis].short if axis in AXES else axis
            parts.append(f"{short}{v:g}" if isinstance(v, (int, float)) else f"{short}{safe_label(v)}")
        return "_".join(parts)


def _rebuild(values):
    c = Condition.__new__(Condition)
    object.__setattr__(c, "_values", tuple(values))
    return c


def cross(base: Condition, values: dict) -> list[Condition]:
    """Every combination of ``values`` ({axis: [v, ...]}) applied to ``base``,
    in the order the lists give (the first axis varies slowest)."""
    axes = [a for a in AXES if a in values]
    return [base.with_(**dict(zip(axes, combo))) for combo in itertools.product(*(values[a] for a in axes))]
