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
