"""``none``: no noise reduction (the default: today's results stand)."""

from __future__ import annotations

from . import DenoiseMethod

#: This module's method (registered by :func:`.collect_denoisers`).
DENOISERS = (DenoiseMethod(name="none", function=None, order=0, domains=("raw", "rgb"), strength=0.0,
                           tuning="none: nothing to tune", licence="this project (MIT)", support=lambda o: 0,
                           description="no noise reduction (default)"),)
