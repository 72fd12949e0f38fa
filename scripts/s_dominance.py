#!/usr/bin/python3
"""What S(t) measures (issue 30; docs/validation.md, "What S measures"): from one or more
`granagg analyze` folders (an ensemble each), the mean cluster size S_grid beside S without the
largest cluster, the largest cluster's share, the occupied fraction p(t) against the 3-D
site-percolation threshold, and the density length l(t) of the structure factor; with the local
slopes of S_grid, S without the largest and l, per run, and their mean and standard error over
the runs. A check and a figure, not a test; the numbers come from granagg analyze.

usage: /usr/bin/python3 scripts/s_dominance.py OUT NAME=ANALYZE_DIR [NAME=ANALYZE_DIR ...]
    [--ratio 2] [--t-min 50] [--length-only]
writes OUT/<NAME>.csv (one row per frame time present in every run of that ensemble) and
OUT/s_dominance.png; with --length-only the figure shows l(t) and its local slope alone (for
ensembles that differ only in how l is measured, e.g. analyze's --structure-kcut).
"""
import argparse
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import granagg_tables as gt  # noqa: E402

P_C = 0.3116  # simple-cubic site percolation (Deng & Bloete, PRE 72, 016126 (2005): 0.311608)


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


def ensemble(folder, ratio, t_min):
    per = gt.read(os.path.join(folder, "per_run", "S_t.csv"))
    if per is None:
        sys.exit(f"s_dominance.py: no per_run/S_t.csv in {folder} (run granagg analyze first)")
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


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out")
    ap.add_argument("ensembles", nargs="+", help="NAME=ANALYZE_DIR")
    ap.add_argument("--ratio", type=float, default=2.0, help="p of the local slope (default 2)")
    ap.add_argument("--t-min", type=float, default=50.0, help="first time tabulated (default 50)")
    ap.add_argument("--length-only", action="store_true",
                    help="figure: l(t) and its local slope only")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    results = {}
    for spec in a.ensembles:
        if "=" not in spec:
            sys.exit(f"s_dominance.py: '{spec}' is not NAME=ANALYZE_DIR")
        name, folder = spec.split("=", 1)
        names, tab, series, runs = ensemble(folder, a.ratio, a.t_min)
        path = os.path.join(a.out, name + ".csv")
        with open(path, "w") as f:
            f.write(f"# command = /usr/bin/python3 scripts/s_dominance.py {' '.join(sys.argv[1:])}\n")
            f.write(f"# source = {folder} (granagg analyze; runs {len(runs)})\n")
            f.write(f"# local slopes z_* = ln[y(t)/y(t/{a.ratio:g})]/ln {a.ratio:g} per run, then "
                    "mean and standard error over the runs\n")
            f.write(",".join(names) + "\n")
            for row in tab:
                f.write(",".join("%.6g" % x for x in row) + "\n")
        results[name] = (names, tab)
        print(f"wrote {path}")

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    if a.length_only:
        plot_length(results, a, plt)
        return
    fig, ax = plt.subplots(2, 2, figsize=(11, 8))
    for k, (name, (names, tab)) in enumerate(results.items()):
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
    fig.tight_layout()
    png = os.path.join(a.out, "s_dominance.png")
    fig.savefig(png, dpi=110)
    print(f"wrote {png}")


def plot_length(results, a, plt):
    """l(t) and its local slope, mean +- standard error over the runs, one colour per ensemble."""
    fig, ax = plt.subplots(1, 2, figsize=(11, 4.2))
    for k, (name, (names, tab)) in enumerate(results.items()):
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
    png = os.path.join(a.out, "s_dominance.png")
    fig.savefig(png, dpi=110)
    print(f"wrote {png}")


if __name__ == "__main__":
    main()
