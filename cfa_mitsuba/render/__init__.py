"""render/: Mitsuba 3 spectral rendering of the built-in scenes and users'
scene files into a :class:`~cfa_mitsuba.values.SpectralImage` (W/(m^2 sr nm)).

Mitsuba is imported lazily (only when something is rendered)."""
