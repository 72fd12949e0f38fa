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
import os
import shutil
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import ensemble_welch as ew  # noqa: E402

ENGINES = ("md", "lammps")
LABELS = {"md": "granagg md", "lammps": "granagg-lammps"}


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
    md, lmp = ew.runs_of(os.path.join(top, "md")), ew.runs_of(os.path.join(top, "lammps"))
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


def main():
    top, times, docs = ew.part_arguments(sys.argv[1:], "lammps_same_physics.py", __doc__)
    data, nruns = ew.load_ensembles(top, ENGINES, times, "lammps_same_physics.py")
    rows, (pmin, nsig, m, same) = ew.welch(data["lammps"], data["md"], ew.OBSERVABLES, times)
    init = initial_state_check(top)
    status = {e: ew.run_status(os.path.join(top, e)) for e in ENGINES}
    part = os.path.basename(os.path.normpath(top))
    notes = ""
    if init:
        worst = np.nanmax([r[2:] for r in init], axis=0)
        notes = (f"\nInitial states (frame 0, {len(init)} seeds run by both engines, N = "
                 f"{init[0][1]}): largest difference in x {worst[0]:.3g}, in v {worst[1]:.3g}, "
                 f"in q {worst[2]:.3g}"
                 f"{' (identical)' if np.all(np.nan_to_num(worst, nan=1.0) == 0) else ''}.\n")
    text = ew.write_comparison(
        top, f"scripts/lammps_same_physics.py: part {part}, granagg-lammps ensemble against "
        "granagg md's", ENGINES, LABELS, nruns, rows, (pmin, nsig, m, same), status, notes)
    csv, md = os.path.join(top, "comparison.csv"), os.path.join(top, "comparison.md")
    print(text)
    if docs:
        os.makedirs("docs/validation", exist_ok=True)
        shutil.copy(csv, f"docs/validation/lammps_same_physics_{docs}.csv")
        shutil.copy(md, f"docs/validation/lammps_same_physics_{docs}.md")
    return 0


if __name__ == "__main__":
    sys.exit(main())
