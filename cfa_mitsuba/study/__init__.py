"""study/: configs, the runner, executors, caches, normalisation, ranks."""
