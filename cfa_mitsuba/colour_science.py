"""colour-science, imported without loading its plotting package.

``import colour`` (0.4.7) imports ``colour.plotting`` unconditionally, and
with it matplotlib's pyplot, pandas' plotting and the Munsell tables: 0.7 s
of its 2.2 s on this project's 2-core machine, paid by every command and
every study worker that only needs spectral data or a colour formula.
:func:`colour_science` puts a stand-in for ``colour.plotting`` in
``sys.modules`` before the first import: the real package is imported the
first time anything reads from it (``colour.plotting.plot_single_sd``,
``from colour.plotting import ...``), so code that plots with colour-science
still works, later.

Written here because colour-science has no switch for it (its
``colour/__init__.py`` runs ``from colour import plotting``).
"""

from __future__ import annotations

__all__ = ["colour_science"]

import importlib
import sys
import types
import warnings

_PLOTTING = "colour.plotting"


class _ImportedOnUse(types.ModuleType):
    """A module's stand-in that imports the module on its first attribute read."""

    def __getattr__(self, name: str):
        if sys.modules.get(self.__name__) is self:
            del sys.modules[self.__name__]
        real = importlib.import_module(self.__name__)
        parent, _, child = self.__name__.rpartition(".")
        setattr(sys.modules[parent], child, real)
        return getattr(real, name)


def colour_science():
    """The ``colour`` package (its import-time warnings about optional
    packages this project does not use are silenced)."""
    if "colour" not in sys.modules:
        sys.modules.setdefault(_PLOTTING, _ImportedOnUse(_PLOTTING))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        import colour
    return colour
