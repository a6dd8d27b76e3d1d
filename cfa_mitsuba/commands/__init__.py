"""One module per ``cfa-mitsuba`` sub-command (see :mod:`cfa_mitsuba.cli`)."""
