"""sensor/: CFAs (layout + spectra), exposure, pixel integration, noise, ADC
-> :class:`~cfa_mitsuba.values.RawImage`."""

from .cfa import CFA, list_cfas, make_cfa, register_cfa, cfa_from_raw  # noqa: F401
from .catalogue import get_cfa, load_cfa_toml  # noqa: F401
from .spectra_sets import SpectraSet, get_spectra_set, list_spectra_sets  # noqa: F401
from .params import NOISE_MODES, SensorParams  # noqa: F401
from .presets import SensorPreset, get_sensor_preset, list_sensor_presets  # noqa: F401
from .noise import collect_electrons, fixed_pattern, read_out  # noqa: F401
from .capture import capture, capture_ideal, capture_many  # noqa: F401
from .metering import AUTO_EXPOSURE_LEVEL, DEFAULT_REFERENCE_LUMINANCE_CD_M2, auto_exposure  # noqa: F401
from .exposure_program import EXPOSURE_POLICIES, ExposureProgram  # noqa: F401
