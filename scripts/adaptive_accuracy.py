#!/usr/bin/python3
"""Compares the adaptive-step ensemble with the fixed-step ensemble of one part of
scripts/adaptive_accuracy.sh (docs/benchmarks.md, "Adaptive time step").

For each observable at each time -- T_g, mean |q|, S_grid, S_particle, the number of particle
clusters and of monomers N_1 -- the adaptive runs' values are compared with the fixed-step runs'
by Welch's t test and called indistinguishable when no p value falls below 0.05 / m (Bonferroni
over the m tests): scripts/ensemble_welch.py, shared with scripts/coulomb_accuracy.py and
scripts/lammps_same_physics.py. Run k of both rules starts from the same state (seed k); the two
trajectories decorrelate long before the first comparison time, so the ensembles are compared
unpaired. The table also gives each rule's steps to t_end and its dt at the end (from the
observables).

  usage: /usr/bin/python3 scripts/adaptive_accuracy.py PARTDIR --times "A B C" [--docs NAME]
    PARTDIR  OUT/neutral or OUT/charged of scripts/adaptive_accuracy.sh
    --docs NAME  also copy the table to docs/validation/adaptive_accuracy_NAME.{csv,md}
Writes PARTDIR/comparison.csv and PARTDIR/comparison.md and prints the latter.
"""
import os
import shutil
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import ensemble_welch as ew  # noqa: E402

RULES = ("fixed", "adaptive")
LABELS = {"fixed": "fixed dt (\"auto\")", "adaptive": "adaptive dt"}


def steps_and_dt(folder):
    """Mean steps to t_end and mean dt at t_end (the last sample of the observable dt) over the
    finished runs in FOLDER."""
    import h5py
    steps, dts = [], []
    for run in ew.runs_of(folder).values():
        if not os.path.exists(os.path.join(run, "done")):
            continue
        try:
            with h5py.File(os.path.join(run, "traj.h5"), "r") as f:
                dts.append(float(f["granagg/observables/dt/value"][-1]))
                steps.append(int(f["granagg/observables/dt/step"][-1]))
        except (OSError, KeyError):
            pass
    return (np.mean(steps) if steps else np.nan), (np.mean(dts) if dts else np.nan)


def main():
    top, times, docs = ew.part_arguments(sys.argv[1:], "adaptive_accuracy.py", __doc__)
    data, nruns = ew.load_ensembles(top, RULES, times, "adaptive_accuracy.py")
    rows, verdict = ew.welch(data["adaptive"], data["fixed"], ew.OBSERVABLES, times)
    status = {r: ew.run_status(os.path.join(top, r)) for r in RULES}
    cost = {r: steps_and_dt(os.path.join(top, r)) for r in RULES}
    notes = "\n| rule | steps to t_end (mean) | dt at t_end (mean) |\n|---|---|---|\n"
    for r in RULES:
        notes += f"| {LABELS[r]} | {cost[r][0]:.0f} | {cost[r][1]:.4g} |\n"
    part = os.path.basename(os.path.normpath(top))
    text = ew.write_comparison(
        top, f"scripts/adaptive_accuracy.py: part {part}, adaptive-step ensemble against the "
        "fixed step's", RULES, LABELS, nruns, rows, verdict, status, notes)
    print(text)
    if docs:
        os.makedirs("docs/validation", exist_ok=True)
        for ext in ("csv", "md"):
            shutil.copy(os.path.join(top, f"comparison.{ext}"),
                        f"docs/validation/adaptive_accuracy_{docs}.{ext}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
