"""XYZ images made from CIELAB ones (colour-science's Lab -> XYZ), for the
metrics' known-answer tests."""

from __future__ import annotations

import numpy as np

WHITE = np.array([95.05, 100.0, 108.9])


def lab_image_to_xyz(lab):
    """(H, W, 3) XYZ (white ``WHITE``) of a CIELAB image."""
    import colour

    xy = colour.XYZ_to_xy(WHITE / 100.0)
    return 100.0 * np.asarray(colour.Lab_to_XYZ(lab, illuminant=xy))
