"""sRGB previews of spectral renders (for people, not for metrics).

The radiance goes to linear sRGB with the scene's white diffuser at Y = 1
(:func:`cfa_mitsuba.io.exr.linear_srgb`, the EXR's own R, G, B channels),
is clipped to the gamut and encoded as display sRGB (IEC 61966-2-1) with
colour-science.
"""

from __future__ import annotations

__all__ = ["srgb_preview", "write_preview"]

from pathlib import Path

import numpy as np

from .. import colorimetry
from ..io.exr import linear_srgb
from ..values import SpectralImage


def srgb_preview(image: SpectralImage, exposure: float = 1.0) -> np.ndarray:
    """(H, W, 3) display sRGB in 0..1 of ``image``; ``exposure`` multiplies
    the linear values before encoding (1: white diffuser at 1.0)."""
    rgb = linear_srgb(image.data, image.wavelengths, image.meta) * exposure
    return np.clip(colorimetry.linear_to_srgb(np.clip(rgb, 0.0, 1.0)), 0.0, 1.0)


def write_preview(path, image: SpectralImage, exposure: float = 1.0) -> Path:
    """Write :func:`srgb_preview` of ``image`` as an 8-bit PNG, atomically."""
    from ..io.images import write_image

    return write_image(Path(path), srgb_preview(image, exposure))


def main(argv=None) -> int:
    """``python -m cfa_mitsuba.render.preview EXR PNG [--width W]``: an sRGB
    preview of a spectral EXR (its sidecar gives the white), optionally
    downsized to W pixels across by box averaging."""
    import argparse

    from ..io.exr import read_spectral_exr

    parser = argparse.ArgumentParser(prog="python -m cfa_mitsuba.render.preview", description=main.__doc__)
    parser.add_argument("exr")
    parser.add_argument("png")
    parser.add_argument("--width", type=int, default=None, help="downsize to this width (integer factor, box filter)")
    args = parser.parse_args(argv)
    image = read_spectral_exr(args.exr)
    rgb = srgb_preview(image)
    if args.width and args.width < rgb.shape[1]:
        # Box-average in linear light, then re-encode: downsizing sRGB codes
        # directly would darken fine detail such as the chirp.
        f = max(1, rgb.shape[1] // args.width)
        h, w = (rgb.shape[0] // f) * f, (rgb.shape[1] // f) * f
        lin = colorimetry.srgb_to_linear(rgb[:h, :w]).reshape(h // f, f, w // f, f, 3).mean(axis=(1, 3))
        rgb = np.clip(colorimetry.linear_to_srgb(lin), 0, 1)
    from ..io.images import write_image

    write_image(args.png, rgb)
    return 0


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
