"""Comparing two ensembles of granagg runs observable by observable (Welch's t, Bonferroni).

Shared by scripts/coulomb_accuracy.py (Coulomb settings against a tight reference) and
scripts/lammps_same_physics.py (granagg-lammps against granagg md). Both read the per-run tables
of `granagg analyze` (docs/analysis.md: per_run/thermo.csv, S_t.csv, N_s_particle.csv) and
compare the ensembles at a few times.

Each observable at each time is compared by Welch's t test (unequal variances; the runs of one
ensemble are independent, and two ensembles are treated as unpaired). Two ensembles are called
indistinguishable when no p value falls below 0.05 / m (Bonferroni over the m tests). With few
runs the test only sees large differences, so each row also gives the smallest difference it
would detect (80 % power at the 5 % level, about 2.8 standard errors of the difference),
relative to the reference mean.
Needs Debian's python3-numpy and python3-scipy (/usr/bin/python3).
"""
import glob
import os
import re
import sys

import numpy as np
from scipy import stats

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import granagg_tables as gt  # noqa: E402

OBSERVABLES = ("T_g", "mean_abs_q", "S_grid", "S_particle", "clusters_particle", "N_1")
# smallest difference a two-sided test at the 5 % level detects with 80 % power, in standard
# errors of the difference: z_0.975 + z_0.80 = 1.96 + 0.84 (normal approximation)
DETECTABLE_SE = 2.8


def per_run_values(analysis, times, missing="error", who="ensemble_welch.py"):
    """{observable: array (runs, len(times))} and the run count, from ANALYSIS/per_run (a
    `granagg analyze` output folder); (None, 0) when its tables are absent. A run without a frame
    at a time (within 1e-3 t) is an error, or NaN with missing="nan" (a run that stopped early)."""
    pr = os.path.join(analysis, "per_run")
    thermo = gt.read(os.path.join(pr, "thermo.csv"))
    st = gt.read(os.path.join(pr, "S_t.csv"))
    ns = gt.read(os.path.join(pr, "N_s_particle.csv"))
    if thermo is None or st is None or ns is None:
        return None, 0
    runs = sorted(set(int(r) for r in thermo["run"]))
    out = {o: np.full((len(runs), len(times)), np.nan) for o in OBSERVABLES}
    for a, run in enumerate(runs):
        for b, t in enumerate(times):
            def row(tab):
                sel = (tab["run"] == run) & (np.abs(tab["t"] - t) < 1e-3 * t)
                return tab[sel]
            th, s = row(thermo), row(st)
            if len(th) != 1 or len(s) != 1:
                if missing == "nan":
                    continue
                raise SystemExit(f"{who}: {analysis} run {run} has no frame at t = {t}")
            out["T_g"][a, b] = th["T_g"][0]
            out["mean_abs_q"][a, b] = th["mean_abs_q"][0]
            for o in ("S_grid", "S_particle", "clusters_particle"):
                out[o][a, b] = s[o][0]
            n1 = ns[(ns["run"] == run) & (np.abs(ns["t"] - t) < 1e-3 * t) & (ns["s"] == 1)]
            out["N_1"][a, b] = n1["N_s"][0] if len(n1) else 0.0
    return out, len(runs)


def ensemble_stats(values, n):
    """{observable: (means, sds, counts)} over runs, per time, from per_run_values(). Runs without
    a value at a time (NaN) are left out of that time's statistics; counts is then per time."""
    out = {}
    for o, v in values.items():
        counts = np.sum(np.isfinite(v), axis=0)
        with np.errstate(invalid="ignore", divide="ignore"):
            means = np.array([np.nanmean(c) if k else np.nan for c, k in zip(v.T, counts)])
            sds = np.array([np.nanstd(c, ddof=1) if k > 1 else np.nan
                            for c, k in zip(v.T, counts)])
        out[o] = (means, sds, counts if np.any(counts != n) else n)
    return out


def welch(x, ref, observables, times):
    """Ensemble x against ensemble ref ({observable: (means, sds, counts)}, counts a number or one
    per time): one row per observable and time, (observable, t, mean, ref_mean, sd, ref_sd,
    rel_diff, rel_detectable, t_stat, p, n, ref_n), and the verdict (smallest p, number of p < 0.05,
    m tests, indistinguishable after Bonferroni). Times where either side has fewer than 2 runs
    are left out of the tests."""
    rows = []
    pmin, nsig, m = 1.0, 0, 0
    for o in observables:
        for b, t in enumerate(times):
            xm, xs, xn = x[o][0][b], x[o][1][b], np.broadcast_to(x[o][2], len(times))[b]
            ym, ys, yn = ref[o][0][b], ref[o][1][b], np.broadcast_to(ref[o][2], len(times))[b]
            if xn < 2 or yn < 2 or not (np.isfinite(xm) and np.isfinite(ym)):
                continue
            se = np.sqrt(xs ** 2 / xn + ys ** 2 / yn)
            if se > 0:
                tstat, p = stats.ttest_ind_from_stats(xm, xs, xn, ym, ys, yn, equal_var=False)
            else:  # identical constant values
                tstat, p = 0.0, 1.0
            m += 1
            pmin = min(pmin, p)
            nsig += p < 0.05
            rows.append((o, t, xm, ym, xs, ys, (xm - ym) / ym if ym != 0 else np.nan,
                         DETECTABLE_SE * se / abs(ym) if ym != 0 else np.nan, tstat, p,
                         int(xn), int(yn)))
    return rows, (pmin, nsig, m, m > 0 and pmin >= 0.05 / m)


def runs_of(folder):
    """{seed: run folder} of the run<seed> folders in FOLDER."""
    out = {}
    for d in glob.glob(os.path.join(folder, "run*")):
        m = re.fullmatch(r"run(\d+)", os.path.basename(d))
        if m and os.path.isdir(d):
            out[int(m.group(1))] = d
    return out


def run_status(folder):
    """(finished runs, unfinished runs, mean wall seconds of the finished ones) of the run<seed>
    folders in FOLDER (a finished run has a file `done` holding its wall seconds)."""
    done, wall = 0, []
    runs = runs_of(folder)
    for d in runs.values():
        f = os.path.join(d, "done")
        if os.path.exists(f):
            done += 1
            wall.append(float(open(f).read()))
    return done, len(runs) - done, (np.mean(wall) if wall else np.nan)


def write_comparison(top, title, names, labels, nruns, rows, verdict, status, notes=""):
    """TOP/comparison.csv and TOP/comparison.md of welch()'s rows for ensemble names[1] against
    names[0] (the reference), with each ensemble's run status (run_status) and NOTES (markdown)
    after the run table. Returns the markdown text."""
    pmin, nsig, m, same = verdict
    ref, x = names
    with open(os.path.join(top, "comparison.csv"), "w") as f:
        f.write(f"# {title}; Welch's t test per observable and time\n")
        f.write("# runs analysed: " + ", ".join(f"{e} {nruns[e]}" for e in names) + "\n")
        f.write(f"# tests {m}, p < 0.05: {nsig}, smallest p {pmin:.4g}, Bonferroni 0.05/m: "
                f"{'indistinguishable' if same else 'DIFFERS'}\n")
        f.write(f"observable,t,{x}_mean,{ref}_mean,{x}_sd,{ref}_sd,rel_diff,rel_detectable,"
                f"t_stat,p,{x}_runs,{ref}_runs\n")
        for r in rows:
            f.write("%s,%g,%.6g,%.6g,%.4g,%.4g,%.4g,%.4g,%.3f,%.4g,%d,%d\n" % r)
    md = os.path.join(top, "comparison.md")
    with open(md, "w") as f:
        f.write("| ensemble | runs finished | runs unfinished | wall per finished run (s) |\n"
                "|---|---|---|---|\n")
        for e in names:
            d, u, w = status[e]
            f.write(f"| {labels[e]} | {d} | {u} | {'-' if np.isnan(w) else f'{w:.0f}'} |\n")
        f.write(notes)
        f.write(f"\n**Verdict ({m} tests, Bonferroni 0.05/{m} = {0.05 / max(m, 1):.2g}): "
                f"{'indistinguishable' if same else 'DIFFERS'}**; {nsig} p values below 0.05, "
                f"the smallest {pmin:.3g}.\n")
        f.write(f"\n| observable | t | {labels[x]} | {labels[ref]} | rel. difference "
                f"| detectable (80 % power) | p | runs ({x}, {ref}) |\n"
                "|---|---|---|---|---|---|---|---|\n")
        for r in rows:
            f.write(f"| {r[0]} | {r[1]:g} | {r[2]:.4g} | {r[3]:.4g} | {100 * r[6]:+.2f} % "
                    f"| {100 * r[7]:.2f} % | {r[9]:.2g} | {r[10]}, {r[11]} |\n")
    return open(md).read()


def part_arguments(args, who, doc):
    """(PARTDIR, times, docs name or None) of a two-ensemble comparison's command line
    `PARTDIR --times "A B C" [--docs NAME]`; prints DOC for -h and exits (2 for bad input)."""
    if not args or args[0] in ("-h", "--help"):
        print(doc)
        sys.exit(0 if args else 2)
    if "--times" not in args or args.index("--times") + 1 >= len(args):
        print(f"{who}: --times needs the comparison times, e.g. --times '50 100 150'")
        sys.exit(2)
    try:
        times = tuple(float(t) for t in args[args.index("--times") + 1].replace(",", " ").split())
    except ValueError:
        print(f"{who}: --times takes numbers, e.g. --times '50 100 150'")
        sys.exit(2)
    docs = None
    if "--docs" in args:
        k = args.index("--docs")
        if k + 1 >= len(args) or not re.fullmatch(r"[a-z0-9_]+", args[k + 1]):
            print(f"{who}: --docs needs a name of [a-z0-9_]")
            sys.exit(2)
        docs = args[k + 1]
    return args[0], times, docs


def load_ensembles(top, names, times, who):
    """({name: ensemble_stats}, {name: runs}) of TOP/NAME/analysis for each name, runs that
    stopped early left out per time; exits 1 unless every ensemble is analysed."""
    data, nruns = {}, {}
    for e in names:
        v, n = per_run_values(os.path.join(top, e, "analysis"), times, missing="nan", who=who)
        if v is not None:
            data[e], nruns[e] = ensemble_stats(v, n), n
    if len(data) < len(names):
        print(f"{who}: {top} has no analysed ensemble of each of {', '.join(names)} yet "
              f"(analysed: {', '.join(data) or 'none'})")
        sys.exit(1)
    return data, nruns
