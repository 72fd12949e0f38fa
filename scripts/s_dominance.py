#!/usr/bin/python3
"""What S(t) measures (issue 30; docs/validation.md, "What S measures"): from one or more
`granagg analyze` folders (an ensemble each), the mean cluster size S_grid beside S without the
largest cluster, the largest cluster's share, the occupied fraction p(t) against the 3-D
site-percolation threshold, and the density length l(t) of the structure factor; with the local
slopes of S_grid, S without the largest and l, per run, and their mean and standard error over
the runs. A check and a figure, not a test; the numbers come from granagg analyze.

usage: /usr/bin/python3 scripts/s_dominance.py OUT NAME=SOURCE [NAME=SOURCE ...]
    [--ratio 2] [--t-min 50] [--length-only]
SOURCE is a `granagg analyze` folder (its per_run/S_t.csv) or such a per-run table itself, e.g.
a committed docs/validation/S_*_runs.csv (one row per run and frame, with the run column).
Writes OUT/<NAME>.csv (one row per frame time present in every run of that ensemble) and
OUT/s_dominance.png; with --length-only the figure shows l(t) and its local slope alone (for
ensembles that differ only in how l is measured, e.g. analyze's --structure-kcut).

Each run's onset t_c is analyze's (docs/analysis.md, "onset"): the time at which S_grid first
reaches ONSET_FACTOR = 2 times its early plateau, the median of S_grid over 0 < t <= 10,
interpolated in (ln t, ln S). The figure's last row shows the local slopes in tau = t - t_c,
ln[y(tau)/y(tau/ratio)]/ln ratio (the exponent of a law y ~ (t - t_c)^z), each run from its own
onset, interpolated onto a common log grid for the mean and standard error; OUT/<NAME>_onset.csv
lists the onsets and those curves.
"""
import argparse
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import granagg_tables as gt  # noqa: E402

P_C = 0.3116  # simple-cubic site percolation (Deng & Bloete, PRE 72, 016126 (2005): 0.311608)
ONSET_FACTOR = 2.0  # analyze's --onset-factor default (analysis/pipeline/RunAnalyzer.h)
ONSET_T_BASE = 10.0  # analyze's --onset-baseline default
REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def repo_relative(path):
    """path relative to the repository when it lies inside it (provenance lines name no machine)."""
    full = os.path.abspath(path)
    return os.path.relpath(full, REPO) if full.startswith(REPO + os.sep) else path


def onset_time(t, s):
    """analyze's onset (analysis/stats/GrowthMarkers.cpp, onsetTime): over the usable samples
    (t > 0, S finite and > 0), the first time S reaches ONSET_FACTOR x their median over
    t <= ONSET_T_BASE, interpolated linearly in (ln t, ln S) from the usable sample before it (the
    sample's own time when it is the first); NaN when S never reaches it."""
    t = np.asarray(t, float)
    s = np.asarray(s, float)
    ok = (t > 0) & np.isfinite(s) & (s > 0)
    t, s = t[ok], s[ok]
    base = s[t <= ONSET_T_BASE]
    if len(base) == 0:
        return math.nan
    target = ONSET_FACTOR * float(np.median(base))
    for i in range(len(t)):
        if s[i] >= target:
            if i == 0:
                return float(t[0])
            f = math.log(target / s[i - 1]) / math.log(s[i] / s[i - 1])
            return math.exp(math.log(t[i - 1]) + f * math.log(t[i] / t[i - 1]))
    return math.nan


def local_slope(t, y, ratio):
    """ln[y(t)/y(t/ratio)] / ln ratio, y(t/ratio) interpolated in (ln t, ln y); NaN where t/ratio
    is before the first time or a value is not positive."""
    t = np.asarray(t, float)
    y = np.asarray(y, float)
    out = np.full(len(t), np.nan)
    ok = (t > 0) & (y > 0) & np.isfinite(y)
    if ok.sum() < 2:
        return out
    lt, ly = np.log(t[ok]), np.log(y[ok])
    for i, (ti, yi) in enumerate(zip(t, y)):
        tb = ti / ratio
        if not (ok[i] and tb >= t[ok][0]):
            continue
        out[i] = (math.log(yi) - np.interp(math.log(tb), lt, ly)) / math.log(ratio)
    return out


def ensemble(source, ratio, t_min):
    path = source if os.path.isfile(source) else os.path.join(source, "per_run", "S_t.csv")
    per = gt.read(path)
    if per is None:
        sys.exit(f"s_dominance.py: no per-run table at {path} (run granagg analyze first)")
    runs = sorted(set(int(r) for r in per["run"]))
    series = {}
    for r in runs:
        rows = per[per["run"] == r]
        t = rows["t"]
        s = {"t": t}
        for c in ("S_grid", "S_grid_without_largest", "largest_share_grid", "occupied_fraction",
                  "S_particle", "S_particle_without_largest", "l_density"):
            s[c] = rows[c]
        for c in ("S_grid", "S_grid_without_largest", "l_density"):
            s["z_" + c] = local_slope(t, rows[c], ratio)
        s["t_c"] = onset_time(t, rows["S_grid"])
        series[r] = s
    # the frame times every run has (times rounded to 9 digits, as analyze matches them)
    key = lambda x: float("%.9g" % x)  # noqa: E731
    common = set(key(x) for x in series[runs[0]]["t"])
    for r in runs[1:]:
        common &= set(key(x) for x in series[r]["t"])
    times = sorted(x for x in common if x >= t_min)
    cols = ["S_grid", "S_grid_without_largest", "largest_share_grid", "occupied_fraction",
            "S_particle", "S_particle_without_largest", "l_density", "z_S_grid",
            "z_S_grid_without_largest", "z_l_density"]
    table = []
    for tt in times:
        row = [tt]
        for c in cols:
            v = []
            for r in runs:
                idx = [i for i, x in enumerate(series[r]["t"]) if key(x) == tt][0]
                v.append(series[r][c][idx])
            v = np.array(v, float)
            v = v[np.isfinite(v)]
            m = v.mean() if len(v) else np.nan
            se = v.std(ddof=1) / math.sqrt(len(v)) if len(v) >= 2 else np.nan
            row += [m, se]
        row.append(len(runs))
        table.append(row)
    names = ["t"] + [f"{c}_{s}" for c in cols for s in ("mean", "se")] + ["n_runs"]
    return names, np.array(table), series, runs


SLOPES = ("z_S_grid", "z_S_grid_without_largest", "z_l_density")


def since_onset(series, runs, ratio, points=40):
    """The local slopes in tau = t - t_c, ln[y(tau)/y(tau/ratio)] / ln ratio (the exponent of a
    law y ~ (t - t_c)^z), per run from its own onset, interpolated in ln tau onto a log grid over
    the tau range every run with an onset covers; returns (tau, {z: (mean, se, n)}) with NaN where
    fewer than two runs have a finite value, or None without onsets."""
    have = []
    for r in runs:
        if not np.isfinite(series[r]["t_c"]):
            continue
        tau = np.asarray(series[r]["t"], float) - series[r]["t_c"]
        if (tau > 0).sum() >= 2:
            have.append(r)
    if not have:
        return None
    spans = []
    slopes = {}
    for r in have:
        tau = np.asarray(series[r]["t"], float) - series[r]["t_c"]
        pos = tau > 0
        spans.append((tau[pos].min(), tau[pos].max()))
        slopes[r] = {z: local_slope(tau[pos], np.asarray(series[r][z[2:]], float)[pos], ratio)
                     for z in SLOPES}
        slopes[r]["tau"] = tau[pos]
    lo, hi = max(a for a, _ in spans), min(b for _, b in spans)
    if not lo < hi:
        return None
    grid = np.exp(np.linspace(math.log(lo), math.log(hi), points))
    out = {}
    for z in SLOPES:
        vals = []
        for r in have:
            tau = slopes[r]["tau"]
            y = slopes[r][z]
            ok = np.isfinite(y)
            vals.append(np.interp(np.log(grid), np.log(tau[ok]), y[ok], left=np.nan,
                                  right=np.nan) if ok.sum() >= 2 else np.full(points, np.nan))
        v = np.array(vals)
        n = np.isfinite(v).sum(axis=0)
        with np.errstate(invalid="ignore", divide="ignore"):
            m = np.nanmean(np.where(n >= 2, v, np.nan), axis=0)
            se = np.nanstd(np.where(n >= 2, v, np.nan), axis=0, ddof=1) / np.sqrt(n)
        out[z] = (m, se, n)
    return grid, out


def write_onset(path, series, runs, curves, argv, ratio):
    """OUT/<NAME>_onset.csv: the runs' onsets, then the slopes against t - t_c."""
    with open(path, "w") as f:
        f.write(f"# command = /usr/bin/python3 scripts/s_dominance.py {' '.join(argv)}\n")
        f.write(f"# onset t_c per run (S_grid reaches {ONSET_FACTOR:g} x its median over "
                f"0 < t <= {ONSET_T_BASE:g}): " + "; ".join(
                    f"run {r}: {series[r]['t_c']:.4g}" for r in runs) + "\n")
        if curves is None:
            f.write("# no run reached its onset\n")
            return
        grid, out = curves
        f.write(f"# local slopes in t - t_c, z = ln[y(tau)/y(tau/{ratio:g})]/ln {ratio:g} with "
                "tau = t - t_c, per run from its own onset, interpolated in ln tau; mean and "
                "standard error over the runs (n_*: runs with a value)\n")
        names = ["t_minus_t_c"] + [f"{z}_{k}" for z in SLOPES for k in ("mean", "se", "n")]
        f.write(",".join(names) + "\n")
        for i, tau in enumerate(grid):
            row = [tau] + [x for z in SLOPES for x in (out[z][0][i], out[z][1][i], out[z][2][i])]
            f.write(",".join("%.6g" % x for x in row) + "\n")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out")
    ap.add_argument("ensembles", nargs="+",
                    help="NAME=SOURCE: an analyze folder or a per-run table (per_run/S_t.csv)")
    ap.add_argument("--ratio", type=float, default=2.0, help="p of the local slope (default 2)")
    ap.add_argument("--t-min", type=float, default=50.0, help="first time tabulated (default 50)")
    ap.add_argument("--length-only", action="store_true",
                    help="figure: l(t) and its local slope only")
    ap.add_argument("--png", default=None,
                    help="where the figure goes (default OUT/s_dominance.png)")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    results = {}
    for spec in a.ensembles:
        if "=" not in spec:
            sys.exit(f"s_dominance.py: '{spec}' is not NAME=SOURCE")
        name, folder = spec.split("=", 1)
        names, tab, series, runs = ensemble(folder, a.ratio, a.t_min)
        argv = [repo_relative(x) if os.path.exists(x) else
                (x.split("=", 1)[0] + "=" + repo_relative(x.split("=", 1)[1]) if "=" in x else x)
                for x in sys.argv[1:]]
        path = os.path.join(a.out, name + ".csv")
        with open(path, "w") as f:
            f.write(f"# command = /usr/bin/python3 scripts/s_dominance.py {' '.join(argv)}\n")
            f.write(f"# source = {repo_relative(folder)} (granagg analyze; runs {len(runs)})\n")
            f.write(f"# local slopes z_* = ln[y(t)/y(t/{a.ratio:g})]/ln {a.ratio:g} per run, then "
                    "mean and standard error over the runs\n")
            f.write(",".join(names) + "\n")
            for row in tab:
                f.write(",".join("%.6g" % x for x in row) + "\n")
        curves = since_onset(series, runs, a.ratio)
        onset_path = os.path.join(a.out, name + "_onset.csv")
        write_onset(onset_path, series, runs, curves, argv, a.ratio)
        results[name] = (names, tab, curves)
        print(f"wrote {path} and {onset_path}")

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    if a.length_only:
        plot_length(results, a, plt)
        return
    fig, ax = plt.subplots(3, 2, figsize=(11, 12))
    for k, (name, (names, tab, curves)) in enumerate(results.items()):
        c = {n: i for i, n in enumerate(names)}
        t = tab[:, 0]
        col = f"C{k}"
        ax[0, 0].errorbar(t, tab[:, c["S_grid_mean"]], tab[:, c["S_grid_se"]], color=col,
                          label=f"{name}: S_grid")
        ax[0, 0].errorbar(t, tab[:, c["S_grid_without_largest_mean"]],
                          tab[:, c["S_grid_without_largest_se"]], color=col, ls="--",
                          label=f"{name}: S_grid without the largest")
        ax[0, 1].plot(t, tab[:, c["occupied_fraction_mean"]], color=col, label=f"{name}: p(t)")
        ax[0, 1].plot(t, tab[:, c["largest_share_grid_mean"]], color=col, ls=":",
                      label=f"{name}: largest cluster's share of the occupied sites")
        ax[1, 0].errorbar(t, tab[:, c["l_density_mean"]], tab[:, c["l_density_se"]], color=col,
                          label=f"{name}: l")
        for z, ls, lab in (("z_S_grid", "-", "S_grid"),
                           ("z_S_grid_without_largest", "--", "S_grid without the largest"),
                           ("z_l_density", ":", "l")):
            m, se = tab[:, c[z + "_mean"]], tab[:, c[z + "_se"]]
            ax[1, 1].plot(t, m, color=col, ls=ls, label=f"{name}: {lab}")
            ax[1, 1].fill_between(t, m - se, m + se, color=col, alpha=0.15)
        if curves is not None:
            grid, out = curves
            for z, ls, lab, panel in (("z_S_grid", "-", "S_grid", 0),
                                      ("z_S_grid_without_largest", "--",
                                       "S_grid without the largest", 0),
                                      ("z_l_density", ":", "l", 1)):
                m, se, _ = out[z]
                ax[2, panel].plot(grid, m, color=col, ls=ls, label=f"{name}: {lab}")
                ax[2, panel].fill_between(grid, m - se, m + se, color=col, alpha=0.15)
    ax[0, 1].axhline(P_C, color="k", lw=0.8)
    ax[0, 1].text(60, P_C * 1.1, "site percolation p_c = 0.3116", fontsize=8)
    for a_ in ax.flat:
        a_.set_xscale("log")
        a_.set_xlabel("t")
        a_.legend(fontsize=7, loc="lower right" if a_ is ax[0, 1] else "best")
    ax[0, 0].set_yscale("log")
    ax[0, 0].set_ylabel("mean cluster size (grid sites)")
    ax[0, 1].set_yscale("log")
    ax[0, 1].set_ylabel("fraction")
    ax[1, 0].set_yscale("log")
    ax[1, 0].set_ylabel("density length l [d]")
    ax[1, 1].set_ylabel(f"local slope (ratio {a.ratio:g}), mean +- se over runs")
    ax[1, 1].axhline(0.5, color="k", lw=0.5)
    for a_ in ax[2]:
        a_.set_xlabel("tau = t - t_c (each run's own onset)")
        a_.set_ylabel(f"local slope in tau (ratio {a.ratio:g}), mean +- se over runs")
    ax[2, 1].axhline(0.5, color="k", lw=0.5)
    fig.tight_layout()
    png = a.png or os.path.join(a.out, "s_dominance.png")
    fig.savefig(png, dpi=110)
    print(f"wrote {png}")


def plot_length(results, a, plt):
    """l(t) and its local slope, mean +- standard error over the runs, one colour per ensemble."""
    fig, ax = plt.subplots(1, 2, figsize=(11, 4.2))
    for k, (name, (names, tab, _)) in enumerate(results.items()):
        c = {n: i for i, n in enumerate(names)}
        t = tab[:, 0]
        ax[0].errorbar(t, tab[:, c["l_density_mean"]], tab[:, c["l_density_se"]], color=f"C{k}",
                       label=name)
        m, se = tab[:, c["z_l_density_mean"]], tab[:, c["z_l_density_se"]]
        ax[1].plot(t, m, color=f"C{k}", label=name)
        ax[1].fill_between(t, m - se, m + se, color=f"C{k}", alpha=0.2)
    for a_ in ax:
        a_.set_xscale("log")
        a_.set_xlabel("t")
        a_.legend(fontsize=8)
    ax[0].set_yscale("log")
    ax[0].set_ylabel("density length l [d]")
    ax[1].set_ylabel(f"local slope of l (ratio {a.ratio:g}), mean +- se over runs")
    ax[1].axhline(0.5, color="k", lw=0.5)
    fig.tight_layout()
    png = a.png or os.path.join(a.out, "s_dominance.png")
    fig.savefig(png, dpi=110)
    print(f"wrote {png}")


if __name__ == "__main__":
    main()
