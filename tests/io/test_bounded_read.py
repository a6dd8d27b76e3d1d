"""The one bounded, regular-file reader (cfa_mitsuba/io/guard.py) under an
address-space limit, on files that grow and on documents nested too deeply
for their parser (issue 51, items 1 and 5)."""

from __future__ import annotations

import json
import resource

import numpy as np
import pytest

from cli_limits import run_limited
from cfa_mitsuba.errors import CfaMitsubaError
from cfa_mitsuba.io import guard

#: `ulimit -v 4000000` (KiB), as clusters set it.
ADDRESS_LIMIT = 4_000_000 * 1024


def _png(path, size=16):
    from PIL import Image

    rng = np.random.default_rng(3)
    Image.fromarray(rng.integers(0, 256, (size, size, 3), dtype=np.uint8)).save(path)
    return path


@pytest.mark.parametrize("size", [1, 16])
def test_a_png_is_read_under_an_address_space_limit(tmp_path, size):
    """Any PNG, even 1 x 1, was a MemoryError under `ulimit -v`: the reader
    asked for its whole 16 GiB bound up front."""
    png = _png(tmp_path / "a.png", size)
    if size == 1:  # too small for a metric: read it directly in a limited process
        proc = run_limited("metric", "ssim", png, png, limits=[(resource.RLIMIT_AS, ADDRESS_LIMIT)])
        assert "MemoryError" not in proc.stderr and "Traceback" not in proc.stderr, proc.stderr
        assert proc.returncode == 2 and "at least 11 x 11" in proc.stderr, proc.stderr
        return
    proc = run_limited("metric", "ssim", png, png, "--json", limits=[(resource.RLIMIT_AS, ADDRESS_LIMIT)])
    assert proc.returncode == 0, proc.stderr
    assert json.loads(proc.stdout)["value"] == pytest.approx(1.0, abs=1e-12)


def test_read_bytes_reads_a_file_that_reports_no_size_whole(tmp_path):
    """It asks for the size fstat gives plus one byte, then reads on while
    there is more (a file that grew, or /proc's files of size 0), up to the
    bound."""
    status = guard.read_text("/proc/self/status", "process status")
    assert status.startswith("Name:") and "VmRSS" in status
    big = tmp_path / "big.txt"
    big.write_text("x" * 5000)
    assert len(guard.read_bytes(big, limit=5000)) == 5000
    with pytest.raises(CfaMitsubaError, match="larger than 4999 bytes"):
        guard.read_bytes(big, limit=4999)


def test_a_toml_nested_deeper_than_its_parser_is_one_line(tmp_path):
    deep = tmp_path / "deep.toml"
    deep.write_text("a = " + "[" * 5000 + "]" * 5000 + "\n")  # 10 kB
    with pytest.raises(CfaMitsubaError, match="nest too deeply"):
        guard.read_toml(deep, "config file")
    ok = tmp_path / "ok.toml"
    ok.write_text("a = [[1], [2]]\n")
    assert guard.read_toml(ok, "config file") == {"a": [[1], [2]]}


def test_json_nested_deeper_than_any_result_is_refused_unparsed(tmp_path):
    deep = tmp_path / "ranges.json"
    deep.write_text("[" * 100_000)
    with pytest.raises(CfaMitsubaError, match="nested more than"):
        guard.read_json(deep, allow_nan=True)
    nan = tmp_path / "timing.json"
    nan.write_text('{"a": NaN}')
    assert np.isnan(guard.read_json(nan, allow_nan=True)["a"])
    with pytest.raises(CfaMitsubaError, match="NaN"):
        guard.read_json(nan)


def test_read_csv_goes_through_the_reader(tmp_path):
    import os

    fifo = tmp_path / "metrics.csv"
    os.mkfifo(fifo)
    with pytest.raises(CfaMitsubaError, match="FIFO"):
        guard.read_csv(fifo)
    table = tmp_path / "t.csv"
    table.write_text("a,b\n1,x\n")
    assert guard.read_csv(table).to_dict("records") == [{"a": 1, "b": "x"}]


def test_a_deep_toml_as_config_cfa_sensor_or_case_is_one_line(tmp_path):
    from cli_limits import assert_error_last

    from cfa_mitsuba.sensor import load_cfa_toml
    from cfa_mitsuba.sensor.sensor_file import read_sensor_file

    deep = tmp_path / "deep.toml"
    deep.write_text("a = " + "[" * 5000 + "]" * 5000 + "\n")
    assert_error_last(run_limited("study", deep, "--out", tmp_path / "s"), "config file", "nest too deeply")
    assert_error_last(run_limited("parity", deep), "parity case", "nest too deeply")
    for read, what in ((load_cfa_toml, "CFA file"), (read_sensor_file, "sensor file")):
        with pytest.raises(CfaMitsubaError, match=f"{what} .*nest too deeply"):
            read(deep)
