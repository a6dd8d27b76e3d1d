"""The render cache's files when something else stands in their place: a
FIFO, a link to /dev/zero or a folder where the cache keeps an entry, its
checksum or its lock (issue 51, items 2 and 3).  Each is one line naming
the real path and what is there, never a hang, a MemoryError or the name
of an internal ``.part`` file."""

from __future__ import annotations

import os
import re
import shutil

import pytest

from cli_limits import assert_error_last, run_limited

RENDER = ("render", "macbeth", "--width", 30, "--height", 20)


@pytest.fixture(scope="module")
def one_render(tmp_path_factory):
    """A cache holding one render, made once: (cache, key)."""
    base = tmp_path_factory.mktemp("cache")
    proc = run_limited(*RENDER, "--out", base / "first", cache=base / "cache")
    assert proc.returncode == 0, proc.stderr
    return base / "cache", re.search(r"cached as ([0-9a-f]{32})", proc.stderr).group(1)


@pytest.fixture
def cached(one_render, tmp_path):
    """A private copy of that cache: (cache, key, out)."""
    shutil.copytree(one_render[0], tmp_path / "cache")
    return tmp_path / "cache", one_render[1], tmp_path / "again"


def _entry(cache, key, suffix):
    return cache / "renders" / key[:2] / f"{key}{suffix}" if suffix != ".lock" else cache / "locks" / f"{key}.lock"


def _replace(path, kind):
    if path.exists() or path.is_symlink():
        path.unlink()
    if kind == "fifo":
        os.mkfifo(path)
    elif kind == "dev-zero":
        path.symlink_to("/dev/zero")
    else:
        path.mkdir()
        (path / "inside").write_text("not the cache's")


@pytest.mark.parametrize("suffix,kind,words", [
    (".sha256", "fifo", ["render cache checksum", "FIFO"]),
    (".sha256", "dev-zero", ["render cache checksum", "character device"]),
    (".sha256", "folder", ["render cache checksum", "directory"]),
    (".exr", "folder", ["render cache entry", "directory"]),
    (".exr", "fifo", ["render cache entry", "FIFO"]),
    (".lock", "folder", ["render cache lock", "directory"]),
    (".lock", "fifo", ["render cache lock", "FIFO"]),
])
def test_a_special_file_in_the_cache_is_one_line_naming_it(cached, suffix, kind, words):
    cache, key, out = cached
    path = _entry(cache, key, suffix)
    if suffix == ".lock":  # the lock is taken only when the entry must be made
        _entry(cache, key, ".sha256").unlink()
    _replace(path, kind)
    proc = run_limited(*RENDER, "--out", out, cache=cache)  # a hang raises TimeoutExpired
    line = assert_error_last(proc, *words, str(path))
    assert ".part" not in line
    assert not list(cache.rglob("*.part")), "a temporary file was left behind"
    if kind == "folder":
        assert (path / "inside").read_text() == "not the cache's"  # the user's folder is not touched


def test_a_study_stops_on_a_fifo_checksum_instead_of_hanging(cached, tmp_path):
    cache, key, _ = cached
    _replace(_entry(cache, key, ".sha256"), "fifo")
    config = tmp_path / "tiny.toml"
    config.write_text('name = "tiny"\nseeds = 2\nscenes = ["macbeth"]\ncfas = ["bayer"]\ndemosaics = ["bilinear"]\n'
                      "luminances = [100]\n[render.macbeth]\nwidth = 30\nheight = 20\n[output]\nreport = false\n")
    proc = run_limited("study", config, "--out", tmp_path / "s", "--quiet", "--workers", 1, cache=cache)
    assert_error_last(proc, "render cache checksum", "FIFO")


def test_a_damaged_regular_checksum_is_rendered_again(cached):
    """A checksum that is a regular file but not a checksum (too long, not
    text) is the ordinary corrupt state: one notice, rendered again."""
    cache, key, out = cached
    _entry(cache, key, ".sha256").write_bytes(b"\xff" * 5000)
    proc = run_limited(*RENDER, "--out", out, cache=cache)
    assert proc.returncode == 0, proc.stderr
    assert "has no checksum" in proc.stderr and "rendering it again" in proc.stderr
    assert len(_entry(cache, key, ".sha256").read_text().strip()) == 64
