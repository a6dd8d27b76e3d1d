"""isp/: white balance, demosaicing, colour correction -> XYZ and sRGB.

``cm.isp.demosaic(raw, cfa, method)`` demosaics a white-balanced mosaic of
any periodic CFA with one of the registered methods (``list_demosaics()``;
add one with ``register_demosaic``); ``cm.isp.process(raw_image, method)``
runs the whole processor, RawImage -> RenderedImage.  docs/isp.md has the
definitions, the generalisations and the measured numbers.
"""

from .demosaic import demosaic, get_demosaic, list_demosaics, register_demosaic  # noqa: F401
from .bilinear import bilinear as _bilinear
from .laplacian import adaptive_laplacian as _adaptive_laplacian, laplacian as _laplacian
from .pocs import pocs as _pocs
from .colour_matrix import (  # noqa: F401
    COLOUR_FITS,
    ColourFit,
    delta_e00,
    fit_colour_matrix,
    gray_world_gains,
    luminance_weights,
    white_balance_gains,
    xyz_to_srgb,
)
from .pipeline import WHITE_BALANCE_MODES, process  # noqa: F401
from .synthetic import channels_from_rgb, mosaic_image  # noqa: F401

register_demosaic("bilinear", _bilinear,
                  description="normalised convolution per channel, tent wide enough for each channel's gaps")
register_demosaic("laplacian", _laplacian,
                  description="gradient-corrected linear (Malvar-He-Cutler on Bayer), then colour differences")
register_demosaic("adaptive-laplacian", _adaptive_laplacian,
                  description="edge-directed (Hamilton-Adams classifiers on Bayer), directional colour differences")
register_demosaic("pocs", _pocs,
                  description="alternating projections onto observation and detail sets (Gunturk et al. 2002)")
