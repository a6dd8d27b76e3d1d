"""Conditions: the named values a study can sweep, one column each in metrics.csv.

A :class:`Condition` fixes every axis of :data:`AXES` for one evaluation:

==================  ==========================================  ==============
axis                what it sets                                default
==================  ==========================================  ==============
``luminance``       mean scene luminance (cd/m^2)               100
``f_number``        the lens f-number: diffraction OTF *and*    the scene's
                    the thin-lens defocus of a 3D render        own (sidecar)
``pixel_pitch_um``  sensor pixel pitch (um)                     2.2
``exposure``        ``"auto"`` (ISETCam's rule at the           ``"auto"``
                    reference luminance) or seconds
``read_noise_e``    read noise (electrons rms)                  6.2
``seed``            the noise realisation (the study seed)      the study's
``spectra``         the spectra set of every CFA's filters      each layout's
                    (``cfa-mitsuba list spectra``)              family set
``readout``         ``full``, ``remosaic`` or ``bin`` (the      ``[sensor]
                    block layouts; others are read full)        readout``
==================  ==========================================  ==============

A config's base values come from ``[optics]``, ``[sensor]`` and the top-level
``seed``; ``[[sweep]]`` tables cross lists of axis values (see
:mod:`.config`).  Adding an axis is one entry in :data:`AXES` plus where the
chain applies it (:meth:`cfa_mitsuba.study.chain.ChainSettings.for_condition`).
"""

from __future__ import annotations

__all__ = ["AXES", "AXIS_UNITS", "Condition", "cross"]

import itertools
from dataclasses import asdict, dataclass, replace

#: The study axes, in metrics.csv column order.
AXES = ("luminance", "f_number", "pixel_pitch_um", "exposure", "read_noise_e", "seed", "spectra", "readout")
#: Units of the axes, for labels.
AXIS_UNITS = {"luminance": "cd/m²", "f_number": "", "pixel_pitch_um": "µm", "exposure": "s",
              "read_noise_e": "e⁻", "seed": "", "spectra": "", "readout": ""}


@dataclass(frozen=True)
class Condition:
    """The value of every axis for one evaluation.

    ``f_number`` None means the scene's own (a render's sidecar records the
    aperture it modelled; charts: the optics default f/4).  ``exposure`` is
    ``"auto"`` or a time in seconds.  ``spectra`` None means each CFA's
    own spectra set (its family's filters).  ``readout`` is the sensor's
    read-out mode (:data:`cfa_mitsuba.sensor.params.READOUT_MODES`).
    """

    luminance: float = 100.0
    f_number: float | None = None
    pixel_pitch_um: float = 2.2
    exposure: object = "auto"
    read_noise_e: float = 6.2
    seed: int = 0
    spectra: str | None = None
    readout: str = "full"

    def with_(self, **changes) -> "Condition":
        return replace(self, **changes)

    def to_dict(self) -> dict:
        return asdict(self)

    def label(self, base: "Condition | None" = None) -> str:
        """A short text naming the axes that differ from ``base`` (all but
        luminance when no base), e.g. ``L100 f8 seed2``; file-name safe."""
        parts = [f"L{self.luminance:g}"]
        short = {"f_number": "f", "pixel_pitch_um": "p", "exposure": "t", "read_noise_e": "rn", "seed": "seed",
                 "spectra": "s-", "readout": "ro-"}
        for axis in AXES[1:]:
            v = getattr(self, axis)
            if base is not None and v == getattr(base, axis):
                continue
            if base is None and v is None:
                continue
            parts.append(f"{short[axis]}{v:g}" if isinstance(v, (int, float)) else f"{short[axis]}{v}")
        return "_".join(parts)


def cross(base: Condition, values: dict) -> list[Condition]:
    """Every combination of ``values`` ({axis: [v, ...]}) applied to ``base``,
    in the order the lists give (the first axis varies slowest)."""
    axes = [a for a in AXES if a in values]
    return [base.with_(**dict(zip(axes, combo))) for combo in itertools.product(*(values[a] for a in axes))]
