"""JCGT spectral channel names (Fichet et al. 2021, s. 3): the one parser
that the EXR writer's module (:mod:`.exr`) and the reader of other tools'
files (:mod:`.jcgt`) share."""

from __future__ import annotations

__all__ = ["parse_spectral_channel"]

import re

from .. import spectra

# JCGT 2021, s. 3: S<stokes>.<value><SI prefix><m|Hz>, comma as decimal mark.
_CHANNEL_RE = re.compile(
    r"^S0\.(?P<value>\d*,?\d*(?:[Ee][+-]?\d+)?)(?P<prefix>Y|Z|E|P|T|G|M|k|h|da|d|c|m|u|n|p)?(?P<unit>m|Hz)$"
)
# SI prefix -> power of ten relative to the unit.
_PREFIX_EXP = {
    "Y": 24, "Z": 21, "E": 18, "P": 15, "T": 12, "G": 9, "M": 6, "k": 3, "h": 2,
    "da": 1, None: 0, "d": -1, "c": -2, "m": -3, "u": -6, "n": -9, "p": -12,
}



def parse_spectral_channel(name: str) -> float | None:
    """Wavelength in nm of a JCGT ``S0`` channel name, or None if ``name`` is
    not one (other Stokes components, reflective ``T.`` channels, R/G/B).

    >>> parse_spectral_channel('S0.550,0nm'), parse_spectral_channel('S0.5.5E-7m')
    (550.0, None)
    >>> parse_spectral_channel('S0.0,55um')
    550.0
    """
    m = _CHANNEL_RE.match(name)
    if m is None or not any(ch.isdigit() for ch in m["value"]):
        return None
    value = float(m["value"].replace(",", "."))
    exp = _PREFIX_EXP[m["prefix"]]
    if m["unit"] == "Hz":
        hertz = value * 10.0**exp
        return spectra.LIGHT_SPEED_M_S / hertz * 1e9 if hertz > 0 else None
    # Scale by an exact power of ten so that 'S0.400,000000nm' gives 400.0 exactly.
    return value * 10.0 ** (exp + 9) if exp + 9 >= 0 else value / 10.0 ** (-(exp + 9))
