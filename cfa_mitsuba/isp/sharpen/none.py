"""``none``: no sharpening (the default)."""

from __future__ import annotations

from . import SharpenMethod

#: This module's method (registered by :func:`.collect_sharpeners`).
SHARPENERS = (SharpenMethod(name="none", function=None, order=0, licence="this project (MIT)",
                            description="no sharpening (default)"),)
