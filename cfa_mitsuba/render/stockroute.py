"""Users' scenes the all-band integrator cannot render exactly, and the
Mitsuba integrator that renders them instead.

The all-band integrator (:mod:`.integrator`) traces surfaces only, and
draws one direction per path for every band, which is exact only for BSDFs
whose sampling does not depend on wavelength (:data:`.userxml.SUPPORTED_BSDFS`).
Two kinds of scene file fall outside it:

- participating media (a ``<medium>``, with its ``<phase>`` and ``<volume>``);
- a BSDF whose sampling depends on the wavelengths a path carries (``hair``
  picks its lobe by the luminance of its attenuations at those
  wavelengths).

They are rendered by Mitsuba's own path tracers, band by band: one render
per band with a single-band ``specfilm`` whose box sensitivity spans the
band, so every wavelength a path carries is drawn inside that band and the
pixel value is an unbiased estimate of the band mean, the quantity the
all-band route estimates (:mod:`.engine`).  This holds whatever the medium
or the BSDF does with wavelength, because the estimator is Mitsuba's own;
the price is one scene load and render per band (31 by default).  A BSDF
whose *value* depends on the wavelengths drawn together (a tinted
``principled``, :data:`.userxml.TINTED_BSDFS`) is still refused: no render
band by band reproduces it.

The integrator: with media, the scene's own where it names a volumetric
one (``volpath``, ``volpathmis`` or ``prbvolpath``, also when nested inside
a ``moment`` or ``aov`` integrator, as Mitsuba's test scenes do), else
``volpath`` (Mitsuba's ``path`` ignores media, so a scene with media is
never rendered without them); without media, ``path``.
"""

from __future__ import annotations

__all__ = ["VOLUME_INTEGRATORS", "DEFAULT_VOLUME_INTEGRATOR", "SURFACE_INTEGRATOR", "has_media", "stock_route"]

#: Mitsuba 3 integrators that render participating media.
VOLUME_INTEGRATORS = ("volpath", "volpathmis", "prbvolpath")
#: The one used when a scene with media names none of them.
DEFAULT_VOLUME_INTEGRATOR = "volpath"
#: The one used for a wavelength-dependent BSDF in a scene without media.
SURFACE_INTEGRATOR = "path"


def has_media(mi, nodes) -> bool:
    """Whether the parsed scene (``mitsuba.parser.ParserState.nodes``) holds
    a medium, a phase function or a volume."""
    kinds = (mi.ObjectType.Medium, mi.ObjectType.PhaseFunction, mi.ObjectType.Volume)
    return any(n.type in kinds for n in nodes)


def stock_route(mi, nodes, integrators, supported_bsdfs) -> tuple[str, str] | None:
    """``(integrator, reason)`` for a scene that needs Mitsuba's own
    integrator (module docstring), or None for the all-band route.

    ``integrators``: indices into ``nodes`` of the scene's integrator and
    the integrators nested in it, outermost first; ``supported_bsdfs``:
    the BSDF plugins the all-band integrator renders exactly.  ``reason``
    is one phrase for the sidecar."""
    if has_media(mi, nodes):
        names = [nodes[j].props.plugin_name() for j in integrators]
        return next((n for n in names if n in VOLUME_INTEGRATORS), DEFAULT_VOLUME_INTEGRATOR), "participating media"
    other = sorted({n.props.plugin_name() for n in nodes
                    if n.type == mi.ObjectType.BSDF and n.props.plugin_name() not in supported_bsdfs})
    if other:
        return SURFACE_INTEGRATOR, f"BSDF {', '.join(other)}: sampling depends on wavelength"
    return None
