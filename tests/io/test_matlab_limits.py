"""MATLAB files that lie about their size or their structure: a v5 deflate
bomb is refused from its headers before anything is inflated (issue 51,
item 4); an HDF5 ``.mat`` whose dataset is a soft link to itself is one
line (item 5)."""

from __future__ import annotations

import tracemalloc

import numpy as np
import pytest
import scipy.io

from cli_limits import assert_error_last, run_limited
from cfa_mitsuba.errors import CfaMitsubaError
from cfa_mitsuba.io.mat5_headers import declared_variables
from cfa_mitsuba.io.matlab import read_mat


@pytest.fixture(scope="module")
def bomb(tmp_path_factory):
    """A compressed v5 file of 62 MB of zeros (about 60 kB on disk)."""
    p = tmp_path_factory.mktemp("mat") / "bomb.mat"
    scipy.io.savemat(p, {"cube": np.zeros((500, 500, 31)), "wavelengths": np.arange(400, 701, 10.0)},
                     do_compression=True)
    assert p.stat().st_size < 200_000
    return p


@pytest.mark.parametrize("compress", [False, True])
def test_declared_variables_agree_with_scipy(tmp_path, compress):
    """Names, shapes and classes as scipy.io.whosmat lists them; bytes once
    loaded as numpy holds them (0 for a struct or cell)."""
    p = tmp_path / "t.mat"
    values = {"cube": np.zeros((3, 4, 5)), "long_variable_name": np.ones(2, np.int16), "text": "hello",
              "s": {"x": np.ones(3)}, "u8": np.zeros((7, 9), np.uint8), "cells": np.array([1, "a"], dtype=object),
              "cx": np.ones((2, 2, 2), complex), "flag": np.array([True]), "f4": np.ones((5, 1), np.float32)}
    scipy.io.savemat(p, values, do_compression=compress)
    with open(p, "rb") as fh:
        mine = declared_variables(fh)
    assert [(n, s, c) for n, s, c, _ in mine] == [(n, tuple(s), c) for n, s, c in scipy.io.whosmat(p)]
    loaded = scipy.io.loadmat(p)
    nbytes = {n: b for n, _, c, b in mine if c not in ("struct", "cell", "char")}
    assert nbytes == {n: loaded[n].nbytes for n in nbytes}
    assert {n: b for n, _, c, b in mine if c in ("struct", "cell")} == {"s": 0, "cells": 0}


def test_declared_variables_inflate_nothing(bomb):
    tracemalloc.start()
    try:
        with open(bomb, "rb") as fh:
            found = declared_variables(fh)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert found == [("cube", (500, 500, 31), "double", 62_000_000), ("wavelengths", (1, 31), "double", 248)]
    assert peak < 1_000_000, peak  # the 62 MB are never inflated


def test_a_deflate_bomb_is_refused_before_scipy_reads_it(bomb, monkeypatch):
    def never(*args, **kwargs):
        raise AssertionError("scipy was asked to read the file")

    monkeypatch.setenv("CFA_MITSUBA_MEMORY_LIMIT", "50M")
    monkeypatch.setattr(scipy.io, "whosmat", never)
    monkeypatch.setattr(scipy.io, "loadmat", never)
    with pytest.raises(CfaMitsubaError, match=r"loading its 7,750,031 values \(sizes from its headers, before any is "
                                              r"inflated\) needs about 124 MB of memory"):
        read_mat(bomb)


def test_a_deflate_bomb_on_the_command_line_is_one_line(bomb, tmp_path):
    proc = run_limited("render", bomb, "--out", tmp_path / "out", env={"CFA_MITSUBA_MEMORY_LIMIT": "50M"})
    assert_error_last(proc, "before any is inflated", "CFA_MITSUBA_MEMORY_LIMIT")


def test_an_hdf5_mat_whose_dataset_links_to_itself_is_one_line(tmp_path):
    import h5py

    p = tmp_path / "loop.mat"
    with h5py.File(p, "w", userblock_size=512) as f:
        f["wavelengths"] = np.arange(400, 701, 10.0)
        f["cube"] = h5py.SoftLink("/cube")
    with pytest.raises(CfaMitsubaError, match="corrupt or not what its header says: .*too many links"):
        read_mat(p)
    assert_error_last(run_limited("render", p, "--out", tmp_path / "out"), str(p), "too many links")
