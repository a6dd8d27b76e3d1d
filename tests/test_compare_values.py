"""benchmarks/compare_values.py: how far one study's values moved from
another's, printed and written as JSON for the docs."""

import importlib.util
import json
from pathlib import Path

import pandas as pd

_SPEC = importlib.util.spec_from_file_location(
    "compare_values", Path(__file__).resolve().parents[1] / "benchmarks" / "compare_values.py")
compare_values = importlib.util.module_from_spec(_SPEC)
_SPEC.loader.exec_module(compare_values)


def _table(values):
    rows = [{"scene": "puppy", "cfa": cfa, "demosaic": "pocs", "luminance": 100.0, "metric": metric,
             "realisation": r, "value": v} for (cfa, metric, r), v in values.items()]
    return pd.DataFrame(rows)


def test_per_metric_differences_are_written_as_json(tmp_path, capsys):
    old = {("bayer", "ssim", 0): 0.9, ("bayer", "ssim", 1): 0.8, ("rgbw1", "scielab", 0): 2.0,
           ("rgbw1", "scielab", 1): 0.0}
    new = dict(old)
    new[("bayer", "ssim", 1)] = 0.8 * (1 + 1e-9)
    new[("rgbw1", "scielab", 0)] = 2.5
    _table(new).to_csv(tmp_path / "new.csv", index=False)
    _table(old).to_csv(tmp_path / "old.csv", index=False)
    out = tmp_path / "cmp.json"
    assert compare_values.main([str(tmp_path / "new.csv"), str(tmp_path / "old.csv"), "--json", str(out)]) == 0
    d = json.loads(out.read_text())
    assert d["all"]["rows"] == 4 and d["all"]["identical"] == 2
    assert d["per_metric"]["scielab"] == {"rows": 2, "identical": 1, "max_abs": 0.5, "max_rel": 0.25}
    assert abs(d["per_metric"]["ssim"]["max_rel"] - 1e-9) < 1e-15 and d["per_metric"]["ssim"]["identical"] == 1
    assert "4 rows in common" in capsys.readouterr().out


def test_a_missing_or_foreign_table_is_one_line_and_exit_2(tmp_path, capsys):
    import pytest

    good = tmp_path / "good.csv"
    _table({("bayer", "ssim", 0): 0.9}).to_csv(good, index=False)
    other = tmp_path / "other.csv"
    other.write_text("a,b\n1,2\n")
    for args, needle in (([str(good), str(tmp_path / "none.csv")], "cannot read"),
                         ([str(good), str(other)], "not a metrics table")):
        with pytest.raises(SystemExit) as exc:
            compare_values.main(args)
        assert exc.value.code == 2
        err = capsys.readouterr().err
        assert needle in err and err.count("\n") == 1 and "Traceback" not in err


def test_tolerances_hold_each_metric_to_its_smallest_relative_tolerance(tmp_path, capsys):
    old = {("bayer", "ssim", 0): 0.9, ("bayer", "scielab", 0): 2.0}
    new = {("bayer", "ssim", 0): 0.9 * (1 + 2e-6), ("bayer", "scielab", 0): 2.0 * (1 + 2e-6)}
    _table(new).to_csv(tmp_path / "new.csv", index=False)
    _table(old).to_csv(tmp_path / "old.csv", index=False)
    tol = pd.DataFrame([{"metric": "ssim", "value": 0.5, "tolerance": 5e-4},    # 1e-3 relative
                        {"metric": "ssim", "value": 1.0, "tolerance": 1e-5},    # the smallest: 1e-5
                        {"metric": "scielab", "value": 5.0, "tolerance": 5e-6},  # 1e-6: 2e-6 is beyond
                        {"metric": "scielab", "value": 0.0, "tolerance": 1.0}])  # a zero value is skipped
    tol.to_csv(tmp_path / "tol.csv", index=False)
    out = tmp_path / "cmp.json"
    assert compare_values.main([str(tmp_path / "new.csv"), str(tmp_path / "old.csv"), "--tolerances",
                                str(tmp_path / "tol.csv"), "--json", str(out)]) == 0
    d = json.loads(out.read_text())
    assert d["per_metric"]["ssim"]["min_rel_tolerance"] == 1e-5 and d["per_metric"]["ssim"]["within_tolerance"]
    assert abs(d["per_metric"]["scielab"]["min_rel_tolerance"] - 1e-6) < 1e-18
    assert d["per_metric"]["scielab"]["min_abs_tolerance"] == 5e-6  # the move is 4e-6: within absolutely
    assert d["per_metric"]["scielab"]["within_abs"] and not d["per_metric"]["scielab"]["within_rel"]
    assert d["all"]["within_tolerance"]
    assert "every metric within its smallest stored relative or absolute tolerance" in capsys.readouterr().out
    tol.loc[2, "tolerance"] = 3e-6  # now beyond both ways
    tol.to_csv(tmp_path / "tol.csv", index=False)
    assert compare_values.main([str(tmp_path / "new.csv"), str(tmp_path / "old.csv"), "--tolerances",
                                str(tmp_path / "tol.csv"), "--json", str(out)]) == 0
    d = json.loads(out.read_text())
    assert not d["per_metric"]["scielab"]["within_tolerance"] and not d["all"]["within_tolerance"]
    assert "beyond (or without) a stored tolerance: scielab" in capsys.readouterr().out
