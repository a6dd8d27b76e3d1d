"""What a metric may read: the two images of one comparison, their white,
the scene geometry and the pixel pitch, converted on first use and shared
by every metric computed on them."""

from __future__ import annotations

__all__ = ["MetricInputs"]

import numpy as np

from . import colourspace as mcolour


class MetricInputs:
    """What a metric may read, built once per camera output and shared by
    every metric computed on it (conversions are made on first use).

    Parameters
    ----------
    reference_xyz, test_xyz : (H, W, 3) absolute CIE XYZ of the ideal sensor
        and of the camera (same scale as ``white_xyz``); None where a caller
        has only display images.
    white_xyz : (3,) XYZ of the scene white.
    geometry : the scene geometry (:func:`~cfa_mitsuba.metrics.scene_geometry`):
        patches, roi, row, steps, samples_per_degree, frequency_cy_per_deg.
    pixel_pitch_um : the sensor's pixel pitch (um), for MTF in cy/mm.
    reference_srgb8, test_srgb8 : 8-bit sRGB code values (0..255 floats),
        given directly or derived from XYZ (white -> 255).
    reference_linear, test_linear : linear sRGB with the white at 1, given
        directly or derived from XYZ.
    shared : a dict kept with the reference image (the caller's: one per
        ideal image), where what depends on the reference alone (its sRGB
        codes, S-CIELAB's filtered reference) is computed once for every
        camera output compared with it.

    The sRGB codes and linear RGB derived here are read-only (the metrics
    read them and check each once); the arrays given are used as they are.
    """

    def __init__(self, reference_xyz=None, test_xyz=None, white_xyz=None, *, geometry: dict | None = None,
                 pixel_pitch_um: float | None = None, reference_srgb8=None, test_srgb8=None,
                 reference_linear=None, test_linear=None, shared: dict | None = None):
        self.reference_xyz = reference_xyz
        self.test_xyz = test_xyz
        self.white_xyz = None if white_xyz is None else np.asarray(white_xyz, dtype=np.float64)
        self.geometry = dict(geometry or {})
        self.pixel_pitch_um = pixel_pitch_um
        self.shared = shared if shared is not None else {}
        self._srgb8 = {"reference": reference_srgb8 if reference_srgb8 is not None
                       else self.shared.get("srgb8_reference"), "test": test_srgb8}
        self._linear = {"reference": reference_linear if reference_linear is not None
                        else self.shared.get("linear_reference"), "test": test_linear}

    def _xyz(self, which: str):
        return self.reference_xyz if which == "reference" else self.test_xyz

    def srgb8(self, which: str):
        """8-bit sRGB code values of ``which`` ('reference' or 'test'), quantised."""
        if self._srgb8[which] is None and self._xyz(which) is not None:
            self._srgb8[which] = mcolour.xyz_to_srgb8(self._xyz(which), self.white_xyz)
            # made here, read by every metric of this pair and written by none: read-only, so
            # the metrics check it once (_common.check_values); the reference's is kept for every camera output
            self._srgb8[which].flags.writeable = False
            if which == "reference":
                self.shared["srgb8_reference"] = self._srgb8[which]
        return self._srgb8[which]

    def linear(self, which: str):
        """Linear sRGB of ``which`` with the scene white at 1 (None if absent)."""
        if self._linear[which] is None and self._xyz(which) is not None:
            self._linear[which] = mcolour.xyz_to_linear(self._xyz(which), scale=float(self.white_xyz[1]))
            self._linear[which].flags.writeable = False  # as srgb8's
            if which == "reference":
                self.shared["linear_reference"] = self._linear[which]
        return self._linear[which]
