"""A canonical render scaled to the luminance asked for, with its white set
by the stated rule: shared by the render engine and the measured-image
scenes (neither imports the other for it)."""

from __future__ import annotations

__all__ = ["DEFAULT_LUMINANCE_CD_M2", "scale_to_luminance"]

import numpy as np

from .. import spectra
from ..errors import CfaMitsubaError
from ..values import SpectralImage
from . import white as _white

#: Mean scene luminance of a render when none is asked for (cd/m^2).
DEFAULT_LUMINANCE_CD_M2 = 100.0


def scale_to_luminance(canonical: SpectralImage, luminance_cd_m2: float, *, white_from="panel",
                       f_number: float | None = None) -> SpectralImage:
    """Scale a canonical render so that its mean luminance is
    ``luminance_cd_m2`` (ISETCam sceneAdjustLuminance, 'mean'), and set its
    white by the rule ``white_from`` (:mod:`.white`; the panel white scales
    with the image, so reflectances are preserved).  ``f_number``, when
    given, is recorded as the sidecar's ``f_number``."""
    wl = canonical.wavelengths
    mean = float(spectra.luminance_cd_m2(canonical.data, wl).mean())
    if not mean > 0:
        raise CfaMitsubaError(
            f"scene {canonical.meta.get('scene')!r} renders black (mean luminance 0): no light reaches the camera"
        )
    factor = float(luminance_cd_m2) / mean
    meta = dict(canonical.meta)
    data = canonical.data * factor
    rule = _white.parse_white_from(white_from)
    white, level = _white.scaled_white(rule, meta.pop("canonical_white_radiance"),
                                       bool(meta.get("white_exact", True)), data, wl, factor)
    meta.update({
        "luminance_cd_m2": float(luminance_cd_m2),
        "white_radiance": white.tolist(),
        "white_luminance_cd_m2": float(spectra.luminance_cd_m2(white, wl)),
        "white_from": "xyz" if isinstance(rule, tuple) else rule,
        "white_level": level,
        "scale_from_canonical": factor,
    })
    if isinstance(rule, tuple):
        meta["white_xyz_cd_m2"] = list(rule)
    if f_number is not None:
        meta["f_number"] = float(f_number)
    return SpectralImage(data, np.asarray(wl, dtype=np.float64), meta)
