"""Finding a CFA by name or file: the registered layouts and CFAs of
:mod:`.cfa` and the users' TOML files of :mod:`.cfa_toml`, behind one
:func:`get_cfa` (kept apart from both so neither imports the other)."""

from __future__ import annotations

__all__ = ["get_cfa", "load_cfa_toml"]

from ..errors import CfaMitsubaError
from .cfa import _REGISTRY, CFA, _builtin, _layouts, list_cfas
from .cfa_toml import load_cfa_toml as _load_toml
from .spectra_sets import get_spectra_set


def get_cfa(name, spectra: str | None = None) -> CFA:
    """A CFA by registry name (``"bayer"``, ``"rgbw2"``, ...) or from a TOML
    file (a path ending in ``.toml``).

    ``spectra`` names a spectra set (``cfa-mitsuba list spectra``) to use
    instead of the layout's default (for a TOML file: instead of its
    ``spectra_set``, for the filters it does not give under ``[spectra]``).
    """
    if isinstance(name, CFA):
        if spectra is not None and spectra != name.spectra:
            raise CfaMitsubaError(f"CFA {name.name!r} is already built; give its name to choose spectra set "
                                  f"{spectra!r}")
        return name
    key = str(name)
    if spectra is not None:
        get_spectra_set(spectra)  # an unknown set is refused first, by name
    if key.lower().endswith(".toml"):
        return load_cfa_toml(key, spectra=spectra)
    if key in _REGISTRY:
        if spectra is not None and spectra != _REGISTRY[key].spectra:
            raise CfaMitsubaError(f"CFA {key!r} was registered with its own curves; a spectra set applies to "
                                  "the named layouts and TOML files")
        return _REGISTRY[key]
    if key in _layouts():
        return _builtin(key, spectra)
    if key == "ideal":
        raise CfaMitsubaError("'ideal' is not a CFA: it is the XYZ reference sensor (sensor.capture_ideal)")
    raise CfaMitsubaError(f"unknown CFA {key!r} (known: {', '.join(list_cfas())}; or a FILE.toml)")


def load_cfa_toml(path, spectra: str | None = None) -> CFA:
    """Read a user CFA (:func:`cfa_mitsuba.sensor.cfa_toml.load_cfa_toml`),
    or the CFA of a sensor file (:mod:`.sensor_file`: its layout with its own
    QE curves; a spectra set does not apply to it)."""
    from .sensor_file import is_sensor_file, read_sensor_file

    if is_sensor_file(path):
        if spectra is not None:
            raise CfaMitsubaError(f"{path}: a sensor file carries its own QE curves; a spectra set does not apply")
        return read_sensor_file(path)["cfa"]
    return _load_toml(path, spectra=spectra)
