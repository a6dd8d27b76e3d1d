"""isp/: white balance, demosaicing, colour correction -> XYZ and sRGB.

``cm.isp.demosaic(raw, cfa, method)`` demosaics a white-balanced mosaic of
any periodic CFA with one of the registered methods (``list_demosaics()``;
add one with ``register_demosaic``); ``cm.isp.process(raw_image, method)``
runs the whole processor, RawImage -> RenderedImage, with optional noise
reduction (``denoise=``, ``list_denoisers()``) and sharpening
(``sharpen=``, ``list_sharpeners()``).  docs/isp.md has the
definitions, the generalisations and the measured numbers.
"""

from .demosaic import (AccuracyBar, DemosaicMethod, collect_demosaics, demosaic, get_demosaic,  # noqa: F401
                       get_demosaic_record, list_demosaics, register_demosaic)
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
from .denoise import (DenoiseMethod, denoise_channels, denoise_mosaic, denoise_setting,  # noqa: F401
                      denoise_setting_name, denoise_support_px, get_denoiser, list_denoisers, register_denoiser)
from .noise_profile import NoiseProfile, noise_profile  # noqa: F401
from .sharpen import (SharpenMethod, get_sharpener, list_sharpeners, register_sharpener, sharpen_image,  # noqa: F401
                      sharpen_setting, sharpen_setting_name, sharpen_support_px)

collect_demosaics(__name__)  # each method module declares DEMOSAICS
