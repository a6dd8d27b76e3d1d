"""study/: configs, the runner, executors, caches, normalisation, ranks.

From Python: ``cm.study.run(config_or_path, out=None) -> Results`` and
``cm.study.load(out_dir)`` (:mod:`.api`), the tables as pandas DataFrames.
"""

from .api import Results, load, run  # noqa: F401

__all__ = ["Results", "run", "load"]
