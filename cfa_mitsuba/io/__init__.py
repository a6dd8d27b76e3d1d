"""io/: spectral OpenEXR (JCGT layout) and sidecar JSON, plain images, raw
mosaics; every write is atomic."""

from .atomic import atomic_output, check_writable_dir  # noqa: F401
from .images import ImageFile, read_image, write_image  # noqa: F401
from .raw_npz import RAW_FORMAT, load_raw_npz, save_raw_npz  # noqa: F401
from .sidecar import read_sidecar, sidecar_path, write_sidecar  # noqa: F401
from .exr import read_spectral_exr, write_spectral_exr  # noqa: F401
from .cache import RenderCache, default_cache_dir  # noqa: F401
