#!/usr/bin/python3
"""A rerun ensemble against its committed table (docs/validation.md, "The charged ensembles at
N = 1e4, rerun"): S_grid and S_particle at a few times and the onset, committed mean +- standard
error beside the rerun's, with Welch's t for the difference. A check, not a test.

usage: /usr/bin/python3 scripts/rerun_compare.py OUT.csv NAME=COMMITTED:RERUN[:RUNS] [...]
    [--runs 5] [--times 50,100,150]
COMMITTED is a committed ensemble table (docs/validation/S_<part>.csv: t, S_grid_mean, S_grid_se,
S_particle_mean, S_particle_se), RERUN a `granagg analyze` folder of the rerun (S_t.csv,
fits.csv). The committed onset comes from docs/validation/ensembles.csv (row `part` = NAME).
Both ensembles have RUNS runs (default --runs). The committed tables keep only mean and standard
error, so the test works from those: t = (m1 - m2) / sqrt(se1^2 + se2^2), with the
Welch-Satterthwaite degrees of freedom, and the two-sided p value. With m tests in all, a
difference is significant below p = 0.05 / m (Bonferroni), which the provenance line states.
Needs Debian's python3-scipy.
"""
import argparse
import csv
import math
import os

from scipy import stats

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def rel(path):
    full = os.path.abspath(path)
    return os.path.relpath(full, REPO) if full.startswith(REPO + os.sep) else path


def read_rows(path):
    """A granagg CSV ('#' provenance lines, then a header row) as a list of dicts."""
    with open(path) as f:
        return list(csv.DictReader(line for line in f if not line.startswith("#")))


def at(table, t):
    """The row of `table` (list of dicts with 't') nearest to time t."""
    return min(table, key=lambda r: abs(float(r["t"]) - t))


def welch(m1, s1, m2, s2, n):
    """Welch's t of m2 - m1 and its two-sided p, for two means with standard errors s1, s2 of n
    runs each (scipy's test from summary statistics, as scripts/ensemble_welch.py uses it)."""
    if not s1 * s1 + s2 * s2 > 0:
        return math.nan, math.nan
    r = stats.ttest_ind_from_stats(m2, s2 * math.sqrt(n), n, m1, s1 * math.sqrt(n), n,
                                   equal_var=False)
    return float(r.statistic), float(r.pvalue)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out")
    ap.add_argument("pairs", nargs="+", help="NAME=COMMITTED:RERUN[:RUNS]")
    ap.add_argument("--runs", type=int, default=5, help="runs per ensemble (both)")
    ap.add_argument("--times", default="50,100,150", help="times compared (nearest frames)")
    a = ap.parse_args()
    times = [float(x) for x in a.times.split(",")]
    ens = {r["part"]: r for r in read_rows(os.path.join(REPO, "docs", "validation",
                                                          "ensembles.csv"))}
    rows = []
    for spec in a.pairs:
        name, paths = spec.split("=", 1)
        parts = paths.split(":")
        old_path, new_dir = parts[0], parts[1]
        runs = int(parts[2]) if len(parts) > 2 else a.runs
        old = read_rows(old_path)
        new = read_rows(os.path.join(new_dir, "S_t.csv"))
        for t in times:
            o, n = at(old, t), at(new, t)
            if abs(float(n["t"]) - t) > 0.01 * t:
                continue  # the rerun ends earlier
            for q in ("S_grid", "S_particle"):
                m1, s1 = float(o[q + "_mean"]), float(o[q + "_se"])
                m2, s2 = float(n[q + "_mean"]), float(n[q + "_se"])
                tt, p = welch(m1, s1, m2, s2, runs)
                rows.append([name, q, float(n["t"]), runs, m1, s1, m2, s2, tt, p])
        fit = read_rows(os.path.join(new_dir, "fits.csv"))[0]
        if name in ens:
            m1, s1 = float(ens[name]["onset"]), float(ens[name]["onset_se"])
            m2, s2 = float(fit["onset_time_grid"]), float(fit["onset_time_grid_err"])
            tt, p = welch(m1, s1, m2, s2, runs)
            rows.append([name, "onset_grid", math.nan, runs, m1, s1, m2, s2, tt, p])
    with open(a.out, "w") as f:
        f.write("# command = /usr/bin/python3 scripts/rerun_compare.py " +
                " ".join([rel(a.out)] + [s.split("=", 1)[0] + "=" +
                                         ":".join(rel(x) for x in s.split("=", 1)[1].split(":"))
                                         for s in a.pairs]) + "\n")
        m = sum(1 for r in rows if not math.isnan(r[-1]))
        f.write("# committed mean +- standard error (`committed`, `committed_se`) against the "
                "rerun's (`rerun`, `rerun_se`), `runs` runs each; welch_t = (rerun - "
                "committed) / sqrt(se1^2 + se2^2), p two-sided (Welch-Satterthwaite dof); "
                "onset_grid: analyze's onset of the mean S_grid (ensembles.csv / fits.csv); "
                f"{m} tests: significant below p = {0.05 / m:.2g} (Bonferroni)\n")
        f.write("part,quantity,t,runs,committed,committed_se,rerun,rerun_se,welch_t,p\n")
        for r in rows:
            f.write(",".join(r[:2] + [f"{r[2]:.6g}", str(r[3])] +
                             [f"{x:.6g}" for x in r[4:]]) + "\n")
    print(f"wrote {a.out} ({len(rows)} rows)")


if __name__ == "__main__":
    main()
