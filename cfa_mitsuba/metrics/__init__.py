"""metrics/: the eight image-quality metrics, pure functions on arrays."""
