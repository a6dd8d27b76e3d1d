"""How far one study's values moved from another's, per metric.

    python benchmarks/compare_values.py NEW/metrics.csv OLD/metrics.csv [--expected] [--json PATH]

Joins the two tables on (scene, cfa, demosaic, luminance, metric) and, for
``realisation`` tables, the realisation; prints per metric the rows
compared, the largest absolute and relative difference and where it is.
With ``--expected`` OLD is tests/data/quick_expected.csv (its ``value`` and
``tolerance``): NEW must be a quick study's metrics_realisations.csv (its
first realisation is compared, as tests/test_study_run.py does) and the
table adds the largest difference as a fraction of the stored tolerance.
``--json PATH`` also writes the numbers (per metric: rows, rows with the
same value, largest absolute and relative difference), for the docs to
quote.
"""

from __future__ import annotations

import argparse
import json
import sys

import pandas as pd

KEYS = ["scene", "cfa", "demosaic", "luminance", "metric"]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("new")
    ap.add_argument("old")
    ap.add_argument("--expected", action="store_true", help="OLD is quick_expected.csv (value, tolerance)")
    ap.add_argument("--json", help="also write the per-metric numbers to this file")
    args = ap.parse_args(argv)
    new = pd.read_csv(args.new, comment="#")
    old = pd.read_csv(args.old, comment="#")
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
    print(cols + "   where (largest abs)")
    for metric, g in both.groupby("metric"):
        worst = g.loc[g["abs"].idxmax()]
        line = f"{metric:<18}{len(g):>6}{g['abs'].max():>13.3g}{g['rel'].max():>13.3g}"
        if args.expected:
            line += f"{g['frac'].max():>13.3g}"
        print(line + f"   {worst['scene']} {worst['cfa']} {worst['demosaic']} L{worst['luminance']:g}")
    if args.json:
        def numbers(g):
            return {"rows": int(len(g)), "identical": int((g["value_new"] == g["value_old"]).sum()),
                    "max_abs": float(g["abs"].max()), "max_rel": float(g["rel"].fillna(0.0).max())}

        with open(args.json, "w") as f:
            json.dump({"new": args.new, "old": args.old, "all": numbers(both),
                       "per_metric": {m: numbers(g) for m, g in both.groupby("metric")},
                       "command": "python3 benchmarks/compare_values.py " + " ".join(sys.argv[1:] if argv is None else argv)},
                      f, indent=1)
    print(f"{'all':<18}{len(both):>6}{both['abs'].max():>13.3g}{both['rel'].max():>13.3g}"
          + (f"{both['frac'].max():>13.3g}" if args.expected else ""))
    if args.expected:
        outside = int((both["abs"] > both["tolerance"]).sum())
        print(f"outside the stored tolerance: {outside}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
