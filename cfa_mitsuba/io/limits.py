"""Limits: how much memory a command will need, how much there is, and the
largest render Mitsuba can do, checked before any work starts.

Every command that allocates in proportion to its input estimates its peak
resident memory from the input's size alone (pixels, bands, channels) and
refuses with one line naming the need and the limit when the estimate does
not fit (:func:`require_memory`), instead of starting and being killed by
the kernel, or crashing inside Dr.Jit.

The estimates are linear models measured on this project's code (peak
``ru_maxrss`` of a fresh process; ``benchmarks/bench_memory.py`` re-measures
them at the paper's sizes and prints measured against estimated):

============  ==============================================  ==============
stage         per pixel (bytes; B bands, C CFA channels)       fixed (MiB)
============  ==============================================  ==============
render        80 + 36 B   per EXR pixel, any spp                 270
capture       6 + 26 B    per EXR pixel, any K                   200
process       250 + 9 C   per sensor pixel                       200
study task    6 + 26 B    per EXR pixel (the capture dominates)  290
============  ==============================================  ==============

The render's memory does not grow with spp: the integrator's path loop is
one symbolic Dr.Jit kernel, so only the film (B + 4 float32 channels) and
its numpy copies are per pixel.  Nothing is tiled: the optics' diffraction
works on whole band planes (FFT), so capture needs the whole cube.

Limits of the renderer (JIT variants; :func:`check_render`):

* **samples**: width x height x spp <= 2^32 - 1.  Mitsuba renders all of a
  film's samples as one wavefront indexed by a 32-bit integer; above that it
  splits the render into passes (``SamplingIntegrator::render``,
  ``wavefront_size_limit = 0xffffffff``), which this project's Python
  integrator does not survive (a segmentation fault).
* **film**: width x height x (B + 4) <= 2^32 - 1 values.  The film is one
  Dr.Jit array of B AOV channels plus the hdrfilm's own 4, and Dr.Jit sizes
  arrays with 32-bit integers.

Memory available is the smaller of the cgroup limit
(``/sys/fs/cgroup/memory.max``, or cgroup v1's ``memory.limit_in_bytes``)
and the physical memory, further capped by the environment variable
``CFA_MITSUBA_MEMORY_LIMIT`` (bytes, or with a suffix K, M, G, T: ``2G``),
which is how a user reserves memory for other work and how the tests make a
small machine.
"""

from __future__ import annotations

__all__ = [
    "MAX_SIDE",
    "MAX_SPP",
    "MAX_SAMPLES",
    "MAX_FILM_VALUES",
    "FILM_EXTRA_CHANNELS",
    "MEMORY_ENV",
    "available_memory_bytes",
    "format_bytes",
    "parse_size",
    "require_memory",
    "estimate_render_bytes",
    "estimate_capture_bytes",
    "estimate_process_bytes",
    "estimate_task_bytes",
    "check_render",
]

import math
import os
import re
from pathlib import Path

from ..errors import CfaMitsubaError

#: Largest render width or height (pixels) and spp the settings accept.
MAX_SIDE = 32768
MAX_SPP = 1 << 20
#: Mitsuba's wavefront limit: samples of one render pass (width x height x spp).
MAX_SAMPLES = 2**32 - 1
#: Dr.Jit's array limit: values in the film (width x height x channels).
MAX_FILM_VALUES = 2**32 - 1
#: Channels of the ``hdrfilm`` (luminance) besides the band AOVs, as
#: ``film.prepare(aovs)`` counts them (measured: 35 for 31 bands).
FILM_EXTRA_CHANNELS = 4
#: Environment variable that caps the memory the estimator sees.
MEMORY_ENV = "CFA_MITSUBA_MEMORY_LIMIT"

_MIB = 1 << 20
# (fixed bytes, bytes per pixel, bytes per pixel and band/channel), measured
# (module docstring; benchmarks/bench_memory.py).
_RENDER = (270 * _MIB, 80, 36)
_CAPTURE = (200 * _MIB, 6, 26)
_PROCESS = (200 * _MIB, 250, 9)
_TASK = (290 * _MIB, 6, 26)
#: Bytes the main process holds per result row of a study at its peak: the
#: row (a dict of about 22 values, 0.8-1.1 kB) and the tables made from all
#: of them (tracemalloc over the paper study's 18,720 realisation rows put
#: through ``order_rows`` and ``mean_table``: 3.9 kB a row at the peak).
_RESULT_ROW = 4096

_SUFFIX = {"": 1, "k": 1 << 10, "m": 1 << 20, "g": 1 << 30, "t": 1 << 40}


def parse_size(text, what: str = MEMORY_ENV) -> int:
    """Bytes of a size written ``2G``, ``512M``, ``1.5GB`` or ``1000000``
    (powers of 1024; ``what`` names the setting in the error)."""
    m = re.fullmatch(r"\s*(\d+(?:\.\d*)?)\s*([kKmMgGtT]?)i?[bB]?\s*", str(text))
    if not m:
        raise CfaMitsubaError(f"{what}={text!r}: expected a size in bytes such as 2G, 512M or 1000000")
    value = int(float(m[1]) * _SUFFIX[m[2].lower()])
    if value <= 0:
        raise CfaMitsubaError(f"{what}={text!r}: must be positive")
    return value


def _cgroup_limit() -> int | None:
    for path in ("/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory/memory.limit_in_bytes"):
        try:
            text = Path(path).read_text().strip()
        except OSError:
            continue
        if text.isdigit() and int(text) < 1 << 60:  # v1 writes a huge number for "none"
            return int(text)
    return None


def _physical() -> int | None:
    try:
        import psutil

        return int(psutil.virtual_memory().total)
    except ImportError:
        pass
    try:
        return int(os.sysconf("SC_PAGE_SIZE")) * int(os.sysconf("SC_PHYS_PAGES"))
    except (ValueError, OSError, AttributeError):
        return None


def available_memory_bytes() -> tuple[int | None, str]:
    """Memory a command may use, bytes, and where the number comes from:
    the smallest of ``$CFA_MITSUBA_MEMORY_LIMIT``, the cgroup limit and the
    physical memory (None when none can be read)."""
    found = []
    env = os.environ.get(MEMORY_ENV)
    if env:
        found.append((parse_size(env), f"${MEMORY_ENV}"))
    cg = _cgroup_limit()
    if cg is not None:
        found.append((cg, "the cgroup memory limit"))
    phys = _physical()
    if phys is not None:
        found.append((phys, "physical memory"))
    if not found:
        return None, "unknown"
    return min(found)


def format_bytes(n: float) -> str:
    """``1.5 GB``-style size (powers of 1000, as ``free -h`` users read it)."""
    for unit, scale in (("TB", 1e12), ("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if n >= scale:
            return f"{n / scale:.3g} {unit}"
    return f"{int(n)} B"


def require_memory(need: int, what: str, hint: str = "") -> None:
    """Refuse ``what`` (e.g. ``"render of 6000 x 6000 pixels x 31 bands"``)
    when its estimated peak ``need`` (bytes) exceeds the memory available."""
    have, source = available_memory_bytes()
    if have is not None and need > have:
        tail = f"; {hint}" if hint else ""
        raise CfaMitsubaError(f"{what} needs about {format_bytes(need)} of memory, more than the "
                              f"{format_bytes(have)} available ({source}){tail}")


def _linear(model, pixels: int, per: int) -> int:
    fixed, a, b = model
    return int(fixed + int(pixels) * (a + b * int(per)))


def estimate_render_bytes(width: int, height: int, n_bands: int) -> int:
    """Peak memory of rendering ``width`` x ``height`` EXR pixels of
    ``n_bands`` bands (JIT variants, any spp), bytes."""
    return _linear(_RENDER, int(width) * int(height), n_bands)


def estimate_capture_bytes(height: int, width: int, n_bands: int) -> int:
    """Peak memory of ``capture`` on an EXR of ``height`` x ``width`` pixels
    and ``n_bands`` bands (optics and sensor, any K), bytes."""
    return _linear(_CAPTURE, int(width) * int(height), n_bands)


def estimate_process_bytes(height: int, width: int, n_channels: int) -> int:
    """Peak memory of ``process`` on a raw mosaic of ``height`` x ``width``
    sensor pixels with ``n_channels`` CFA channels (any demosaic), bytes."""
    return _linear(_PROCESS, int(width) * int(height), n_channels)


def estimate_task_bytes(height: int, width: int, n_bands: int) -> int:
    """Peak memory of one study evaluation task (one scene, luminance and
    CFA, every demosaic and metric) on an EXR of ``height`` x ``width``
    pixels and ``n_bands`` bands, bytes."""
    return _linear(_TASK, int(width) * int(height), n_bands)


def estimate_result_rows_bytes(n_rows: int) -> int:
    """Peak memory the main process of a study needs for ``n_rows`` result
    rows (realisation rows: camera outputs x the values each metric gives)
    and the tables made from them, bytes."""
    return int(n_rows) * _RESULT_ROW


def check_render(width: int, height: int, spp: int, n_bands: int, *, name=None) -> None:
    """Refuse a render beyond the renderer's limits or the memory available.

    ``name`` maps a setting ('width', 'spp', ...) to how the user spelled it
    (default ``--width``); a study passes its config keys.
    """
    name = name or (lambda key: f"--{key}")
    w, h, n, b = int(width), int(height), int(spp), int(n_bands)
    values = w * h * (b + FILM_EXTRA_CHANNELS)
    if values > MAX_FILM_VALUES:
        raise CfaMitsubaError(
            f"a film of {name('width')} {w} x {name('height')} {h} with {b} bands holds {values:,} values, above "
            f"Dr.Jit's limit of 2^32 - 1 per array; at most {MAX_FILM_VALUES // (b + FILM_EXTRA_CHANNELS):,} "
            "pixels at this band count")
    samples = w * h * n
    if samples > MAX_SAMPLES:
        most = math.isqrt(MAX_SAMPLES // (w * h)) ** 2  # the stratified sampler takes squares
        raise CfaMitsubaError(
            f"{name('spp')} {n} at {w} x {h} pixels is {samples:,} samples, above Mitsuba's limit of "
            f"2^32 - 1 = {MAX_SAMPLES:,} per render (one 32-bit sample index); use at most "
            f"{most:,} spp at this size")
    require_memory(estimate_render_bytes(w, h, b), f"a render of {w} x {h} pixels x {b} bands",
                   f"lower {name('width')} / {name('height')}")

