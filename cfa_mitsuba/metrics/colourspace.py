"""The colour conversions the metrics use: :mod:`cfa_mitsuba.colorimetry`
(the project's one colour module), under the name the metrics have always
exported (``cm.metrics.colourspace``)."""

from ..colorimetry import *  # noqa: F401,F403
from ..colorimetry import __all__  # noqa: F401
