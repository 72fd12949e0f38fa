#!/usr/bin/python3
"""Compares ensembles of the charged gas that differ only in their Coulomb settings with the
tight reference ensemble (scripts/coulomb_accuracy.sh writes them; issue 15).

For each setting and each observable at t = 50, 100, 150 -- T_g, mean |q|, S_grid, S_particle,
the number of particle clusters and of monomers N_1 -- the runs' values are compared with the
reference runs' by Welch's t test (unequal variances; the runs are independent: different seeds
within an ensemble, and each setting's run from seed k decorrelates from the reference's run from
seed k long before t = 50, so the ensembles are treated as unpaired). A setting is called
indistinguishable from the reference when no p value falls below 0.05 / m (Bonferroni over its
m tests). With few runs the test only sees large differences: the table also gives the smallest
difference it would detect (80 % power at the 5 % level, about 2.8 standard errors of the
difference), relative to the reference mean, so a pass says how close, not just "equal".

  usage: /usr/bin/python3 scripts/coulomb_accuracy.py DIR [--docs] [--ref-csv CSV]
    DIR     the study folder (results/coulomb_accuracy)
    --docs  also copy the table and figure to docs/validation/ and docs/img/validation/
    --ref-csv CSV  take the reference ensemble's means, standard deviations and run count from
            an earlier comparison.csv (e.g. docs/validation/coulomb_accuracy.csv) instead of
            DIR/ref: the reference costs 3 h of CPU and Welch's test needs only its statistics
Writes DIR/comparison.csv, DIR/comparison.md and DIR/comparison.png.
"""
import csv as _csv
import os
import shutil
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import ensemble_welch as ew  # noqa: E402
from ensemble_welch import OBSERVABLES, ensemble_stats  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TIMES = (50.0, 100.0, 150.0)
SETS = ("ref", "default", "fast", "follow", "fastfollow", "rfast25", "rfast20", "rfast20cap32",
        "rfast20cap64")
LABELS = {
    "ref": "reference (accuracy 1e-5, every 1)",
    "default": "old default (1e-4, every 4 fixed, r_fast 3.5)",
    "fast": "candidate (1e-3, every 8, r_fast 2.5)",
    "follow": "interval follows the gas (every_max 16), r_fast 3.5",
    "fastfollow": "1e-3, r_fast 2.5, interval follows the gas (every_max 16)",
    "rfast25": "interval follows (every_max 16), r_fast 2.5",
    "rfast20": "**default**: interval follows (every_max 16), r_fast 2.0",
    "rfast20cap32": "interval follows up to 32 steps, r_fast 2.0",
    "rfast20cap64": "interval follows up to 64 steps, r_fast 2.0",
}


def per_run_values(folder):
    """{observable: array (runs, len(TIMES))} and the run count, from OUT/SET/analysis/per_run."""
    return ew.per_run_values(os.path.join(folder, "analysis"), TIMES, who="coulomb_accuracy.py")


def stored_reference(csv):
    """The reference's {observable: (means, sds, n)} from an earlier comparison.csv: its ref_mean
    and ref_sd columns, and the run count from its '# runs: ref R, ...' line."""
    n = None
    with open(csv) as f:
        for line in f:
            if line.startswith("# runs:"):
                for item in line[len("# runs:"):].split(","):
                    name, count = item.split()
                    if name == "ref":
                        n = int(count)
    if n is None:
        raise SystemExit(f"coulomb_accuracy.py: {csv} does not give the reference's run count")
    with open(csv) as f:
        rows = list(_csv.DictReader(line for line in f if not line.startswith("#")))
    out = {}
    for o in OBSERVABLES:
        m, sd = np.full(len(TIMES), np.nan), np.full(len(TIMES), np.nan)
        for b, t in enumerate(TIMES):
            sel = [r for r in rows
                   if r["observable"] == o and abs(float(r["t"]) - t) < 1e-3 * t]
            if not sel:
                raise SystemExit(f"coulomb_accuracy.py: {csv} has no reference {o} at t = {t}")
            m[b], sd[b] = float(sel[0]["ref_mean"]), float(sel[0]["ref_sd"])
        out[o] = (m, sd, n)
    return out


def wall_seconds(folder):
    """Wall seconds of each finished run (the `done` files of coulomb_accuracy.sh)."""
    w = []
    for d in sorted(os.listdir(folder)):
        f = os.path.join(folder, d, "done")
        if d.startswith("run") and os.path.exists(f):
            w.append(float(open(f).read()))
    return np.array(w)


def main():
    if len(sys.argv) < 2 or sys.argv[1] in ("-h", "--help"):
        print(__doc__)
        return 0 if len(sys.argv) >= 2 else 2
    top = sys.argv[1]
    docs = "--docs" in sys.argv[2:]
    ref_csv = None
    if "--ref-csv" in sys.argv[2:]:
        k = sys.argv.index("--ref-csv")
        if k + 1 >= len(sys.argv):
            print("coulomb_accuracy.py: --ref-csv needs a file")
            return 2
        ref_csv = sys.argv[k + 1]
    data, nruns, wall = {}, {}, {}
    if ref_csv:
        data["ref"] = stored_reference(ref_csv)
        nruns["ref"] = data["ref"]["T_g"][2]
        wall["ref"] = np.array([])
    for s in SETS:
        if s == "ref" and ref_csv:
            continue
        if os.path.isdir(os.path.join(top, s)):
            v, n = per_run_values(os.path.join(top, s))
            if v is not None:
                data[s], nruns[s] = ensemble_stats(v, n), n
                wall[s] = wall_seconds(os.path.join(top, s))
    if "ref" not in data:
        print("coulomb_accuracy.py: no analysed reference ensemble yet in " + top)
        return 1
    ref = data["ref"]
    rows = []
    verdict = {}
    for s in data:
        if s == "ref":
            continue
        welch_rows, verdict[s] = ew.welch(data[s], ref, OBSERVABLES, TIMES)
        rows += [(s,) + r[:10] for r in welch_rows]
    os.makedirs(top, exist_ok=True)
    csv = os.path.join(top, "comparison.csv")
    with open(csv, "w") as f:
        f.write("# scripts/coulomb_accuracy.py: each setting's ensemble against the reference "
                "(accuracy 1e-5, every 1); Welch's t test per observable and time\n")
        f.write("# runs: " + ", ".join(f"{s} {nruns[s]}" for s in data) + "\n")
        if ref_csv:
            # relative to the repository: the line must not name the machine's folders
            src = os.path.abspath(ref_csv).replace(ROOT + os.sep, "")
            f.write(f"# reference statistics (means, sd, runs) from {src}\n")
        f.write("setting,observable,t,mean,ref_mean,sd,ref_sd,rel_diff,rel_detectable,t_stat,p\n")
        for r in rows:
            f.write("%s,%s,%g,%.6g,%.6g,%.4g,%.4g,%.4g,%.4g,%.3f,%.4g\n" % r)
    md = os.path.join(top, "comparison.md")
    with open(md, "w") as f:
        f.write("| setting | runs | wall per run (s, 1 thread) | tests | p < 0.05 | smallest p "
                "| Bonferroni (p >= 0.05 / m) |\n|---|---|---|---|---|---|---|\n")
        for s in data:
            w = wall[s]
            ws = f"{w.mean():.0f} ({w.min():.0f}-{w.max():.0f})" if len(w) else "-"
            if s == "ref":
                f.write(f"| {LABELS[s]} | {nruns[s]} | {ws} | | | | reference |\n")
            else:
                pmin, nsig, m, ok = verdict[s]
                f.write(f"| {LABELS[s]} | {nruns[s]} | {ws} | {m} | {nsig} | {pmin:.3g} | "
                        f"{'indistinguishable' if ok else 'DIFFERS'} |\n")
        f.write("\n| setting | observable | t | mean | reference | rel. difference "
                "| detectable (80 % power) | p |\n|---|---|---|---|---|---|---|---|\n")
        for r in rows:
            f.write(f"| {r[0]} | {r[1]} | {r[2]:g} | {r[3]:.4g} | {r[4]:.4g} | {100 * r[7]:+.1f} % "
                    f"| {100 * r[8]:.1f} % | {r[10]:.2g} |\n")
    print(open(md).read())
    png = os.path.join(top, "comparison.png")
    plot(top, data, png)
    if docs:
        os.makedirs("docs/validation", exist_ok=True)
        os.makedirs("docs/img/validation", exist_ok=True)
        shutil.copy(csv, "docs/validation/coulomb_accuracy.csv")
        shutil.copy(md, "docs/validation/coulomb_accuracy.md")
        shutil.copy(png, "docs/img/validation/coulomb_accuracy.png")
    return 0


def plot(top, data, png):
    """Relative difference of each setting's ensemble mean from the reference's, with the standard
    error of the difference, per observable at t = 50, 100, 150 (the numbers of the table)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    shown = ("T_g", "mean_abs_q", "clusters_particle", "N_1")
    fig, axes = plt.subplots(1, len(shown), figsize=(15, 4.2), sharey=True)
    ref = data["ref"]
    others = [s for s in data if s != "ref"]
    width = 0.8 / max(1, len(others))
    for ax, o in zip(axes, shown):
        rm, rsd, rn = ref[o]
        rse2 = rsd ** 2 / rn
        for k, s in enumerate(others):
            m, sd, n = data[s][o]
            se2 = sd ** 2 / n
            rel = 100.0 * (m / rm - 1.0)
            err = 100.0 * np.sqrt(se2 + rse2 * (m / rm) ** 2) / rm
            x = np.arange(len(TIMES)) + (k - (len(others) - 1) / 2) * width
            ax.errorbar(x, rel, yerr=err, fmt="o", ms=4, capsize=2,
                        label=LABELS[s].replace("**", ""))
        ax.axhline(0.0, color="k", lw=0.8)
        ax.set_xticks(np.arange(len(TIMES)))
        ax.set_xticklabels([f"t = {t:g}" for t in TIMES])
        ax.set_title(o)
    axes[0].set_ylabel("mean vs reference (%), +- 1 SE")
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=3, fontsize=8, frameon=False)
    fig.suptitle("K = 5, Q = 0.05, N = 2000: each Coulomb setting against the tight reference "
                 "(accuracy 1e-5, every step)")
    fig.tight_layout(rect=(0, 0.16, 1, 1))
    fig.savefig(png, dpi=110)


if __name__ == "__main__":
    sys.exit(main())
