"""io/: spectral OpenEXR (JCGT layout) and sidecar JSON, plain images, raw
mosaics; every write is atomic."""

from .atomic import atomic_output, check_writable_dir  # noqa: F401
from .images import ImageFile, read_image, write_image  # noqa: F401
from .raw_npz import RAW_FORMAT, load_raw_npz, save_raw_npz  # noqa: F401
