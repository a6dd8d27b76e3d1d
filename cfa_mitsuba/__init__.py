"""cfa-mitsuba: a physically based camera simulator and image-quality metric
system for colour filter arrays (a re-creation of Bae 2020, PLoS ONE 15(5):
e0232583, on Mitsuba 3 and numpy).

The stages, in the order data flows through them (DESIGN.md)::

    render -> io -> optics -> sensor -> isp -> metrics -> study -> report

``import cfa_mitsuba as cm`` imports every stage, so ``cm.sensor.get_cfa``,
``cm.io.read_spectral_exr``, ``cm.isp.demosaic`` and ``cm.metrics.ssim`` work
without further imports.  Mitsuba itself is imported only when something is
rendered.
"""

__version__ = "0.1.0"

from . import errors, spectra, values  # noqa: E402,F401
from . import render, io, optics, sensor, isp, metrics, study, report  # noqa: E402,F401
from .errors import CfaMitsubaError  # noqa: E402,F401
from .values import OpticalImage, RawImage, RenderedImage, SpectralImage  # noqa: E402,F401
