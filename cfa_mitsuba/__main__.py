"""``python -m cfa_mitsuba`` = the ``cfa-mitsuba`` command."""

import sys

from .cli import main

sys.exit(main())
