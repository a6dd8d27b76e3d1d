"""cfa-mitsuba: a physically based camera simulator and image-quality metric
system for colour filter arrays (a re-creation of Bae 2020, PLoS ONE 15(5):
e0232583, on Mitsuba 3 and numpy).

The stages, in the order data flows through them (DESIGN.md)::

    render -> io -> optics -> sensor -> isp -> metrics -> study -> report

``import cfa_mitsuba as cm`` makes every stage reachable (imported on first use), so ``cm.sensor.get_cfa``,
``cm.io.read_spectral_exr``, ``cm.isp.demosaic`` and ``cm.metrics.ssim`` work
without further imports.  Mitsuba itself is imported only when something is
rendered.
"""

from ._version import __version__  # noqa: F401
from .errors import CfaMitsubaError  # noqa: F401

#: The stage subpackages and shared modules, imported on first use
#: (``cm.sensor`` works without an import, and ``from cfa_mitsuba import
#: __version__`` does not pull in the whole chain).
_SUBMODULES = ("errors", "spectra", "values", "colorimetry", "render", "io", "optics", "sensor", "isp", "metrics",
               "study", "report")
_VALUES = ("OpticalImage", "RawImage", "RenderedImage", "SpectralImage")


def __getattr__(name):
    import importlib

    if name in _SUBMODULES:
        module = importlib.import_module(f".{name}", __name__)
        if name == "study":  # the report registers its builder with cm.study.run (study/api.py)
            importlib.import_module(".report", __name__)
        return module
    if name in _VALUES:
        from . import values

        return getattr(values, name)
    raise AttributeError(f"module 'cfa_mitsuba' has no attribute {name!r}")


def __dir__():
    return sorted({*globals(), *_SUBMODULES, *_VALUES})
