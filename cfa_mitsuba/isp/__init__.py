"""isp/: white balance, demosaicing, colour correction -> XYZ and sRGB.

``cm.isp.demosaic(raw, cfa, method)`` demosaics a white-balanced mosaic of
any periodic CFA with one of the registered methods (``list_demosaics()``;
add one with ``register_demosaic``); ``cm.isp.process(raw_image, method)``
runs the whole processor, RawImage -> RenderedImage.  docs/isp.md has the
definitions, the generalisations and the measured numbers.
"""

from .demosaic import collect_demosaics, demosaic, get_demosaic, list_demosaics, register_demosaic  # noqa: F401
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
from .pipeline import (PREPARE_KEYWORDS, WHITE_BALANCE_MODES, PreparedRaw, prepare, process,  # noqa: F401
                       process_prepared)
from .synthetic import channels_from_rgb, mosaic_image  # noqa: F401

collect_demosaics(__name__)  # each method module declares DEMOSAICS
