"""Writing under a full disk or the file-size limit (`ulimit -f`), and onto
a folder: one line naming the file the user or the cache named (never a
temporary ``.part``) and the cause, exit 2, nothing half written left
(issue 51, items 3 and 6)."""

from __future__ import annotations

import resource

import pytest

from cli_limits import assert_error_last, run_limited
from cfa_mitsuba.io.atomic import WriteError, atomic_output

#: `ulimit -f 20`: 20 blocks of 1024 bytes.
SMALL_FILES = [(resource.RLIMIT_FSIZE, 20 * 1024)]


def test_render_under_the_file_size_limit_names_the_cache_entry(tmp_path):
    cache = tmp_path / "cache"
    proc = run_limited("render", "macbeth", "--width", 120, "--height", 80, "--out", tmp_path / "out", cache=cache,
                       limits=SMALL_FILES)
    line = assert_error_last(proc, "cannot write", "File too large", "ulimit -f", str(cache / "renders"))
    assert ".part" not in line and line.split("'")[1].endswith(".exr")
    left = [p for p in tmp_path.rglob("*") if p.is_file() and p.parent.name != "locks"]
    assert not left, f"half-written files left: {left}"


@pytest.fixture(scope="module")
def exr(tmp_path_factory):
    out = tmp_path_factory.mktemp("exr")
    proc = run_limited("render", "macbeth", "--width", 240, "--height", 160, "--out", out, cache=out / "cache")
    assert proc.returncode == 0, proc.stderr
    return out / "macbeth.exr"


def test_capture_under_the_file_size_limit_names_its_output(exr, tmp_path):
    out = tmp_path / "raw.npz"
    proc = run_limited("capture", exr, "--cfa", "bayer", "--out", out, limits=SMALL_FILES)
    assert_error_last(proc, "cannot write", str(out), "File too large")
    assert not list(tmp_path.iterdir()), "nothing half written is left"


def test_capture_that_fits_under_the_limit_writes_a_whole_file(exr, tmp_path):
    """When capture exits 0 under a limit, what it wrote is the whole raw
    file: the same arrays as a capture without the limit."""
    import numpy as np

    from cfa_mitsuba.io import load_raw_npz

    limited, free = tmp_path / "limited.npz", tmp_path / "free.npz"
    proc = run_limited("capture", exr, "--cfa", "bayer", "--seed", 3, "--out", limited,
                       limits=[(resource.RLIMIT_FSIZE, 1 << 20)])
    assert proc.returncode == 0, proc.stderr
    assert run_limited("capture", exr, "--cfa", "bayer", "--seed", 3, "--out", free).returncode == 0
    np.testing.assert_array_equal(load_raw_npz(limited).raw, load_raw_npz(free).raw)


def test_atomic_output_onto_a_folder_names_the_folder(tmp_path):
    target = tmp_path / "x.json"
    target.mkdir()
    with pytest.raises(WriteError, match=r"cannot write '.*x\.json': it is a directory") as err:
        with atomic_output(target) as tmp:
            tmp.write_text("{}")
    assert err.value.path == target and ".part" not in str(err.value)
    assert [p.name for p in tmp_path.iterdir()] == ["x.json"]


def test_a_nested_writer_error_names_the_outer_target(tmp_path):
    """The cache writes an EXR inside its own atomic block (two temporary
    names): the error names the entry."""
    target = tmp_path / "entry.exr"
    with pytest.raises(WriteError) as err:
        with atomic_output(target) as outer:
            with atomic_output(outer) as inner:
                raise OSError(27, "File too large")
    assert err.value.path == target and "ulimit -f" in str(err.value)
    assert not list(tmp_path.iterdir())


def test_a_kernel_whose_cache_cannot_be_written_still_runs(tmp_path, monkeypatch):
    """numba writes a compiled kernel's cache on its first call; a full disk
    or the file-size limit there ended a capture in 'File too large' (the
    first capture of a fresh install under `ulimit -f`)."""
    import errno
    import importlib.util

    from numba.core import caching

    from cfa_mitsuba.io.jit_cache import tolerate_cache_write_errors

    def full(self, *args, **kwargs):
        raise OSError(errno.EFBIG, "File too large")

    monkeypatch.setattr(caching.IndexDataCacheFile, "save", full)
    tolerate_cache_write_errors()
    src = tmp_path / "kernel_under_test.py"
    src.write_text("import numba\n\n@numba.njit(cache=True)\ndef twice(x):\n    return 2 * x\n")
    spec = importlib.util.spec_from_file_location("kernel_under_test", src)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    assert mod.twice(21) == 42
    assert not list(tmp_path.rglob("*.nbi")) and not list(tmp_path.rglob("*.tmp.*"))


def test_every_module_with_cached_kernels_tolerates_a_failed_cache_write():
    """The patch above is made by each module that compiles with
    ``cache=True`` (the first of them to load makes it): one without the call
    would fail a capture that reaches it first on a full disk."""
    import re
    from pathlib import Path

    import cfa_mitsuba

    package = Path(cfa_mitsuba.__file__).parent
    cached = [p for p in package.rglob("*.py") if re.search(r"jit\([^)]*cache=True", p.read_text())]
    assert len(cached) >= 10, cached
    missing = [str(p.relative_to(package)) for p in cached if "\ntolerate_cache_write_errors()" not in p.read_text()]
    assert not missing, missing
