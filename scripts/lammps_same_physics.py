#!/usr/bin/python3
"""Compares the granagg-lammps ensemble with the granagg md ensemble of one part of
scripts/lammps_same_physics.sh (issue 28, "Same physics"; docs/lammps.md).

For each observable at each time -- T_g, mean |q|, S_grid, S_particle, the number of particle
clusters and of monomers N_1 -- the LAMMPS runs' values are compared with granagg md's by Welch's
t test and called indistinguishable when no p value falls below 0.05 / m (Bonferroni over the m
tests): scripts/ensemble_welch.py, shared with scripts/coulomb_accuracy.py. The runs of one
engine differ in their seeds; run k of both engines starts from the same state (checked here:
frame 0 of both trajectories), but the two trajectories decorrelate long before the first
comparison time (rounding, amplified by the gas's chaos), so the ensembles are compared unpaired.
A run that stopped before a time (a study cut short, analysed with --include-unfinished) is left
out of that time's statistics; the table gives the run counts.

  usage: /usr/bin/python3 scripts/lammps_same_physics.py PARTDIR --times "A B C" [--docs NAME]
    PARTDIR  OUT/neutral or OUT/charged of scripts/lammps_same_physics.sh
    --docs NAME  also copy the table to docs/validation/lammps_same_physics_NAME.{csv,md}
Writes PARTDIR/comparison.csv and PARTDIR/comparison.md and prints the latter.
"""
import glob
import os
import re
import shutil
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import ensemble_welch as ew  # noqa: E402

ENGINES = ("md", "lammps")
LABELS = {"md": "granagg md", "lammps": "granagg-lammps"}


def runs_of(folder):
    """{seed: run folder} of an engine's folder."""
    out = {}
    for d in glob.glob(os.path.join(folder, "run*")):
        m = re.fullmatch(r"run(\d+)", os.path.basename(d))
        if m and os.path.isdir(d):
            out[int(m.group(1))] = d
    return out


def first_frame(run):
    """Positions, velocities and charges of frame 0 of RUN/traj.h5 (None if unreadable)."""
    import h5py
    try:
        with h5py.File(os.path.join(run, "traj.h5"), "r") as f:
            p = f["particles/all"]
            x = p["position/value"][0]
            v = p["velocity/value"][0] if "velocity" in p else None
            q = p["charge/value"][0] if "charge" in p and "value" in p["charge"] else None
            return x, v, q
    except (OSError, KeyError):
        return None


def initial_state_check(top):
    """Per seed run by both engines: the largest difference of frame 0's positions, velocities
    and charges (0 when granagg-lammps built the identical state)."""
    md, lmp = runs_of(os.path.join(top, "md")), runs_of(os.path.join(top, "lammps"))
    out = []
    for seed in sorted(set(md) & set(lmp)):
        a, b = first_frame(md[seed]), first_frame(lmp[seed])
        if a is None or b is None:
            continue
        diffs = []
        for u, w in zip(a, b):
            diffs.append(float(np.max(np.abs(u - w))) if u is not None and w is not None
                         and u.shape == w.shape else np.nan)
        out.append((seed, a[0].shape[0], *diffs))
    return out


def run_status(folder):
    """(finished runs, unfinished runs, mean wall seconds of the finished ones) of an engine."""
    done, wall = 0, []
    runs = runs_of(folder)
    for d in runs.values():
        f = os.path.join(d, "done")
        if os.path.exists(f):
            done += 1
            wall.append(float(open(f).read()))
    return done, len(runs) - done, (np.mean(wall) if wall else np.nan)


def main():
    args = sys.argv[1:]
    if not args or args[0] in ("-h", "--help"):
        print(__doc__)
        return 0 if args else 2
    top = args[0]
    if "--times" not in args or args.index("--times") + 1 >= len(args):
        print("lammps_same_physics.py: --times needs the comparison times, e.g. "
              "--times '50 100 150'")
        return 2
    try:
        times = tuple(float(t) for t in args[args.index("--times") + 1].replace(",", " ").split())
    except ValueError:
        print("lammps_same_physics.py: --times takes numbers, e.g. --times '50 100 150'")
        return 2
    docs = None
    if "--docs" in args:
        k = args.index("--docs")
        if k + 1 >= len(args) or not re.fullmatch(r"[a-z0-9_]+", args[k + 1]):
            print("lammps_same_physics.py: --docs needs a name of [a-z0-9_]")
            return 2
        docs = args[k + 1]
    data, nruns = {}, {}
    for e in ENGINES:
        v, n = ew.per_run_values(os.path.join(top, e, "analysis"), times, missing="nan",
                                 who="lammps_same_physics.py")
        if v is not None:
            data[e], nruns[e] = ew.ensemble_stats(v, n), n
    if len(data) < 2:
        print(f"lammps_same_physics.py: {top} has no analysed ensemble of both engines yet "
              f"(analysed: {', '.join(data) or 'none'})")
        return 1
    rows, (pmin, nsig, m, same) = ew.welch(data["lammps"], data["md"], ew.OBSERVABLES, times)
    init = initial_state_check(top)
    status = {e: run_status(os.path.join(top, e)) for e in ENGINES}
    part = os.path.basename(os.path.normpath(top))

    csv = os.path.join(top, "comparison.csv")
    with open(csv, "w") as f:
        f.write(f"# scripts/lammps_same_physics.py: part {part}, granagg-lammps ensemble against "
                "granagg md's; Welch's t test per observable and time\n")
        f.write("# runs analysed: " + ", ".join(f"{e} {nruns[e]}" for e in ENGINES) + "\n")
        f.write(f"# tests {m}, p < 0.05: {nsig}, smallest p {pmin:.4g}, Bonferroni 0.05/m: "
                f"{'indistinguishable' if same else 'DIFFERS'}\n")
        f.write("observable,t,lammps_mean,md_mean,lammps_sd,md_sd,rel_diff,rel_detectable,"
                "t_stat,p,lammps_runs,md_runs\n")
        for r in rows:
            f.write("%s,%g,%.6g,%.6g,%.4g,%.4g,%.4g,%.4g,%.3f,%.4g,%d,%d\n" % r)

    md = os.path.join(top, "comparison.md")
    with open(md, "w") as f:
        f.write("| engine | runs finished | runs unfinished | wall per finished run (s) |\n"
                "|---|---|---|---|\n")
        for e in ENGINES:
            d, u, w = status[e]
            f.write(f"| {LABELS[e]} | {d} | {u} | {'-' if np.isnan(w) else f'{w:.0f}'} |\n")
        if init:
            worst = np.nanmax([r[2:] for r in init], axis=0)
            f.write(f"\nInitial states (frame 0, {len(init)} seeds run by both engines, N = "
                    f"{init[0][1]}): largest difference in x {worst[0]:.3g}, in v {worst[1]:.3g}, "
                    f"in q {worst[2]:.3g}"
                    f"{' (identical)' if np.all(np.nan_to_num(worst, nan=1.0) == 0) else ''}.\n")
        f.write(f"\n**Verdict ({m} tests, Bonferroni 0.05/{m} = {0.05 / max(m, 1):.2g}): "
                f"{'indistinguishable' if same else 'DIFFERS'}**; {nsig} p values below 0.05, "
                f"the smallest {pmin:.3g}.\n")
        f.write("\n| observable | t | granagg-lammps | granagg md | rel. difference "
                "| detectable (80 % power) | p | runs (lammps, md) |\n"
                "|---|---|---|---|---|---|---|---|\n")
        for r in rows:
            f.write(f"| {r[0]} | {r[1]:g} | {r[2]:.4g} | {r[3]:.4g} | {100 * r[6]:+.2f} % "
                    f"| {100 * r[7]:.2f} % | {r[9]:.2g} | {r[10]}, {r[11]} |\n")
    print(open(md).read())
    if docs:
        os.makedirs("docs/validation", exist_ok=True)
        shutil.copy(csv, f"docs/validation/lammps_same_physics_{docs}.csv")
        shutil.copy(md, f"docs/validation/lammps_same_physics_{docs}.md")
    return 0


if __name__ == "__main__":
    sys.exit(main())
