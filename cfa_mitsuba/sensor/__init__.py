"""sensor/: CFAs (layout + spectra), exposure, pixel integration, noise, ADC
-> :class:`~cfa_mitsuba.values.RawImage`."""

from .cfa import CFA, get_cfa, list_cfas, load_cfa_toml, register_cfa  # noqa: F401
