"""How far one study's values moved from another's, per metric.

    python benchmarks/compare_values.py NEW/metrics.csv OLD/metrics.csv [--expected] [--json PATH]

Joins the two tables on (scene, cfa, demosaic, luminance, metric) and, for
``realisation`` tables, the realisation; prints per metric the rows
compared, the largest absolute and relative difference and where it is.
With ``--expected`` OLD is tests/data/quick_expected.csv (its ``value`` and
``tolerance``): NEW must be a quick study's metrics_realisations.csv (its
first realisation is compared, as tests/study/test_runner.py does) and the
table adds the largest difference as a fraction of the stored tolerance.
``--json PATH`` also writes the numbers (per metric: rows, rows with the
same value, largest absolute and relative difference), for the docs to
quote.  ``--tolerances FILE`` (tests/data/quick_expected.csv) holds two
studies of different size to the same rule: per metric, the largest
relative difference against the smallest relative tolerance FILE stores
for that metric (tolerance / |value|; the rule is in the file's first
line), and the largest absolute difference against the smallest absolute
tolerance, printed and written to the JSON (``min_rel_tolerance``,
``min_abs_tolerance``, ``within_rel``, ``within_abs``,
``within_tolerance``: either holds; ``all.within_tolerance`` when every
metric's does).  The two smallest tolerances may come from different rows,
so this is a bound, not the per-row test of ``--expected``.
"""

from __future__ import annotations

import argparse
import json
import sys

import pandas as pd
from pathlib import Path

from cfa_mitsuba.io.portable import relative_command, relative_path

KEYS = ["scene", "cfa", "demosaic", "luminance", "metric"]


def _read(ap, path: str, columns: set, what: str) -> pd.DataFrame:
    """The CSV at ``path`` ('#' lines skipped), or one line and exit 2 when
    it is missing, unreadable, not a CSV or lacks ``columns`` (then not ``what``)."""
    try:
        table = pd.read_csv(path, comment="#")
    except (OSError, ValueError) as exc:
        ap.exit(2, f"compare_values: cannot read {path}: {getattr(exc, 'strerror', None) or exc}\n")
    if not columns <= set(table.columns):
        ap.exit(2, f"compare_values: {path} has no {', '.join(map(repr, sorted(columns)))} columns: "
                   f"not {what}\n")
    return table


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("new")
    ap.add_argument("old")
    ap.add_argument("--expected", action="store_true", help="OLD is quick_expected.csv (value, tolerance)")
    ap.add_argument("--json", help="also write the per-metric numbers to this file")
    ap.add_argument("--tolerances", metavar="FILE",
                    help="a table of value and tolerance per row (tests/data/quick_expected.csv): compare each "
                         "metric's largest relative difference with the smallest relative tolerance stored for it")
    args = ap.parse_args(argv)
    new, old = (_read(ap, path, {"metric", "value"}, "a metrics table") for path in (args.new, args.old))
    rel_tol, abs_tol = {}, {}
    if args.tolerances:
        tol = _read(ap, args.tolerances, {"metric", "value", "tolerance"}, "a tolerance table")
        abs_tol = tol.groupby("metric")["tolerance"].min().to_dict()
        tol = tol[tol["value"] != 0]
        rel_tol = (tol["tolerance"] / tol["value"].abs()).groupby(tol["metric"]).min().to_dict()
    keys = list(KEYS)
    if args.expected:
        new = new[new["realisation"] == 0] if "realisation" in new.columns else new
    elif "realisation" in new.columns and "realisation" in old.columns:
        keys.append("realisation")
    for extra in ("f_number", "pixel_pitch_um", "exposure", "read_noise_e", "seed", "readout", "spectra"):
        if extra in new.columns and extra in old.columns and not args.expected:
            keys.append(extra)
    both = new.merge(old, on=keys, suffixes=("_new", "_old"))
    if both.empty:
        print("no rows in common", file=sys.stderr)
        return 2
    both["abs"] = (both["value_new"] - both["value_old"]).abs()
    both["rel"] = both["abs"] / both["value_old"].abs().where(both["value_old"] != 0)
    print(f"{len(both)} rows in common ({len(new)} new, {len(old)} old)")
    cols = f"{'metric':<18}{'rows':>6}{'max abs':>13}{'max rel':>13}"
    if args.expected:
        both["frac"] = both["abs"] / both["tolerance"]
        cols += f"{'/ tolerance':>13}"
    if args.tolerances:
        cols += f"{'min rel tol':>13}{'min abs tol':>13}"
    print(cols + "   where (largest abs)")
    for metric, g in both.groupby("metric"):
        worst = g.loc[g["abs"].idxmax()]
        line = f"{metric:<18}{len(g):>6}{g['abs'].max():>13.3g}{g['rel'].max():>13.3g}"
        if args.expected:
            line += f"{g['frac'].max():>13.3g}"
        if args.tolerances:
            line += f"{rel_tol.get(metric, float('nan')):>13.3g}{abs_tol.get(metric, float('nan')):>13.3g}"
        print(line + f"   {worst['scene']} {worst['cfa']} {worst['demosaic']} L{worst['luminance']:g}")
    def numbers(g, metric=None):
        out = {"rows": int(len(g)), "identical": int((g["value_new"] == g["value_old"]).sum()),
               "max_abs": float(g["abs"].max()), "max_rel": float(g["rel"].fillna(0.0).max())}
        if args.tolerances and metric is not None:
            t, a = rel_tol.get(metric), abs_tol.get(metric)
            out["min_rel_tolerance"] = None if t is None else float(t)
            out["min_abs_tolerance"] = None if a is None else float(a)
            out["within_rel"] = t is not None and out["max_rel"] <= t
            out["within_abs"] = a is not None and out["max_abs"] <= a
            out["within_tolerance"] = out["within_rel"] or out["within_abs"]
        return out

    per_metric = {m: numbers(g, m) for m, g in both.groupby("metric")}
    whole = numbers(both)
    if args.tolerances:
        whole["within_tolerance"] = all(v["within_tolerance"] for v in per_metric.values())
    if args.json:
        with open(args.json, "w") as f:
            base = Path(args.json).resolve().parent  # paths relative to the record's folder (io/portable.py)
            json.dump({"new": relative_path(args.new, base), "old": relative_path(args.old, base), "all": whole,
                       "per_metric": per_metric,
                       "command": "python3 benchmarks/compare_values.py "
                       + relative_command(sys.argv[1:] if argv is None else argv, base)},
                      f, indent=1)
    print(f"{'all':<18}{len(both):>6}{both['abs'].max():>13.3g}{both['rel'].max():>13.3g}"
          + (f"{both['frac'].max():>13.3g}" if args.expected else ""))
    if args.expected:
        outside = int((both["abs"] > both["tolerance"]).sum())
        print(f"outside the stored tolerance: {outside}")
    if args.tolerances:
        worse = [m for m, v in per_metric.items() if not v["within_tolerance"]]
        print("every metric within its smallest stored relative or absolute tolerance" if not worse
              else f"beyond (or without) a stored tolerance: {', '.join(worse)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
