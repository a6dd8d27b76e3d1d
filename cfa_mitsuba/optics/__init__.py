"""optics/: scene radiance to sensor-plane irradiance (f-number, lens
transmittance, relative illumination, diffraction OTF, pixel-area
integration), computed once per scene and reused by every CFA."""

from .compute import DEFAULT_PIXEL_PITCH_UM, check_oversample, compute_optics, integrate_pixels  # noqa: F401
from .diffraction import apply_diffraction, diffraction_mtf  # noqa: F401
from .lens import (DEFAULT_F_NUMBER, DEFAULT_FOV_DEG, DEFAULT_SCENE_DISTANCE_M, LensGeometry,  # noqa: F401
                   OpticsParams, lens_geometry, on_axis_factor, relative_illumination)
from .presets import OpticsPreset, get_optics_preset, list_optics_presets  # noqa: F401
