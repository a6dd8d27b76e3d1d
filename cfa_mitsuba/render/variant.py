"""Choosing and loading the Mitsuba 3 variant.

Order of preference (DESIGN.md): ``cuda_ad_spectral`` where a CUDA GPU is
present, else ``llvm_ad_spectral``, else ``scalar_spectral``.  Only spectral
variants are accepted: the RGB and mono ones cannot produce band radiance.

drjit 1.5 needs LLVM >= 16 for its LLVM backend (LLVM 15 fails with "Cannot
select fmaximum", research/mitsuba-spectral.md), and it reads the library's
location from ``DRJIT_LIBLLVM_PATH`` once, when drjit is first imported.  So
:func:`ensure_libllvm` looks for the newest libLLVM >= 16 in the usual Debian
and upstream-LLVM locations and sets that variable *before* importing drjit,
unless the user set it already.

Dr.Jit ignores ``OMP_NUM_THREADS``; a caller that must cap the render's
threads (a Dask worker sharing a node) sets ``CFA_MITSUBA_THREADS``, which
:func:`load` passes to ``drjit.set_thread_count``.
"""

from __future__ import annotations

__all__ = [
    "SPECTRAL_VARIANTS",
    "MIN_LLVM",
    "find_libllvm",
    "ensure_libllvm",
    "available_variants",
    "choose_variant",
    "load",
    "THREADS_ENV",
]

import glob
import os
import re
import sys

from ..errors import CfaMitsubaError

#: The variants this project renders with, in order of preference.
SPECTRAL_VARIANTS = ("cuda_ad_spectral", "llvm_ad_spectral", "scalar_spectral")
#: Oldest LLVM whose libLLVM drjit 1.5 can use.
MIN_LLVM = 16
#: Environment variable with a thread budget for Dr.Jit (an integer >= 1).
THREADS_ENV = "CFA_MITSUBA_THREADS"

_LLVM_GLOBS = (
    "/usr/lib/x86_64-linux-gnu/libLLVM-*.so*",
    "/usr/lib/x86_64-linux-gnu/libLLVM.so.*",
    "/usr/lib/aarch64-linux-gnu/libLLVM-*.so*",
    "/usr/lib/aarch64-linux-gnu/libLLVM.so.*",
    "/usr/lib/llvm-*/lib/libLLVM*.so*",
    "/usr/lib64/libLLVM*.so*",
    "/usr/local/lib/libLLVM*.so*",
)
_INSTALL_HINT = "install LLVM >= 16 (Debian/Ubuntu: apt-get install libllvm19) or set DRJIT_LIBLLVM_PATH"


def _llvm_major(path: str) -> int | None:
    """Major LLVM version of a libLLVM shared library, from its file name
    (``libLLVM-19.so``, ``libLLVM.so.19.1``) or its ``llvm-N`` directory."""
    name = os.path.basename(path)
    if not re.fullmatch(r"libLLVM(-[\d.]+(rc\d*)?)?\.so(\.[\d.]+)*", name):
        return None  # component libraries (libLLVMCore...) and static archives
    m = re.match(r"libLLVM-(\d+)", name) or re.match(r"libLLVM\.so\.(\d+)", name)
    if m is None:
        m = re.search(r"llvm-(\d+)", path)
    return int(m.group(1)) if m else None


def find_libllvm(globs=_LLVM_GLOBS) -> tuple[str, int] | None:
    """The newest libLLVM with major version >= :data:`MIN_LLVM`, as
    ``(path, major)``, or None."""
    best = None
    for pattern in globs:
        for path in glob.glob(pattern):
            major = _llvm_major(path)
            if major is None or major < MIN_LLVM or not os.path.isfile(path):
                continue
            # Prefer the newest version; among equals the shortest (canonical) name.
            key = (major, -len(path))
            if best is None or key > best[0]:
                best = (key, path)
    return (best[1], best[0][0]) if best else None


def ensure_libllvm() -> str | None:
    """Point ``DRJIT_LIBLLVM_PATH`` at a usable libLLVM unless it is set.

    Returns the path in effect (None if none was found).  Has no effect once
    drjit is imported, since drjit reads the variable only then.
    """
    current = os.environ.get("DRJIT_LIBLLVM_PATH")
    if current:
        return current
    if "drjit" in sys.modules:
        return None
    found = find_libllvm()
    if found is None:
        return None
    os.environ["DRJIT_LIBLLVM_PATH"] = found[0]
    return found[0]


def _import_drjit():
    ensure_libllvm()
    import drjit

    return drjit


def available_variants() -> tuple[str, ...]:
    """The spectral variants that can run here, best first."""
    dr = _import_drjit()
    import mitsuba

    have = set(mitsuba.variants())
    out = []
    for v in SPECTRAL_VARIANTS:
        if v not in have:
            continue
        if v.startswith("cuda") and not dr.has_backend(dr.JitBackend.CUDA):
            continue
        if v.startswith("llvm") and not dr.has_backend(dr.JitBackend.LLVM):
            continue
        out.append(v)
    return tuple(out)


def choose_variant(requested: str | None = None) -> str:
    """Return the variant to render with.

    ``requested`` (the ``--variant`` option) must be one of
    :data:`SPECTRAL_VARIANTS` and usable here; None picks the best available.
    """
    if requested is not None:
        if requested not in SPECTRAL_VARIANTS:
            raise CfaMitsubaError(
                f"unknown or non-spectral Mitsuba variant {requested!r} (choose from {', '.join(SPECTRAL_VARIANTS)})"
            )
        if requested not in available_variants():
            if requested.startswith("llvm"):
                raise CfaMitsubaError(f"Mitsuba variant {requested!r} needs libLLVM >= {MIN_LLVM}: {_INSTALL_HINT}")
            raise CfaMitsubaError(f"Mitsuba variant {requested!r} is not usable here (no CUDA GPU or driver found)")
        return requested
    avail = available_variants()
    if not avail:  # pragma: no cover - scalar_spectral ships with every Mitsuba wheel
        raise CfaMitsubaError("no spectral Mitsuba variant is available (pip install mitsuba==3.9.1)")
    return avail[0]


def llvm_notice() -> str | None:
    """A one-line hint when the LLVM variant is unavailable, else None."""
    dr = _import_drjit()
    if dr.has_backend(dr.JitBackend.LLVM):
        return None
    return f"no usable libLLVM >= {MIN_LLVM} found, so rendering falls back to the slow scalar_spectral variant: {_INSTALL_HINT}"


def thread_budget() -> int | None:
    """The thread count from :data:`THREADS_ENV`, or None when unset."""
    raw = os.environ.get(THREADS_ENV, "").strip()
    if not raw:
        return None
    try:
        n = int(raw)
    except ValueError:
        n = 0
    if n < 1:
        raise CfaMitsubaError(f"{THREADS_ENV}={raw!r} must be a positive integer")
    return n


def load(variant: str, threads: int | None = None):
    """Import Mitsuba, select ``variant``, register our integrator, apply the
    thread budget (``threads``, else :data:`THREADS_ENV`), return the module."""
    dr = _import_drjit()
    import mitsuba as mi

    if mi.variant() != variant:
        mi.set_variant(variant)
    n = threads if threads is not None else thread_budget()
    if n is not None:
        dr.set_thread_count(int(n))
    from . import integrator

    integrator.register(mi)
    return mi
