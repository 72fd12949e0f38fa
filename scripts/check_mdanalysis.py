#!/usr/bin/python3
"""MDAnalysis reads a granagg trajectory: the README's recipe, checked against h5py.

usage: /usr/bin/python3 scripts/check_mdanalysis.py RUN/traj.h5

Loads the file the way README says (Debian's python3-mdanalysis 2.4):

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        u = mda.Universe.empty(N, trajectory=False).load_new(path, format="H5MD",
                                                             convert_units=False)

and compares every frame's positions, velocities, box and time with the file's datasets read by
h5py (MDAnalysis stores coordinates in float32: agreement to float32 round-off). Prints one line
and exits 0, or names the first disagreement and exits 1.
"""
import sys
import warnings

import h5py
import numpy as np

with warnings.catch_warnings():  # MDAnalysis 2.4 warns about modules it does not use here
    warnings.simplefilter("ignore")
    import MDAnalysis as mda  # noqa: E402


def main():
    if len(sys.argv) != 2:
        print(__doc__)
        return 2
    path = sys.argv[1]
    with h5py.File(path, "r") as f:
        part = f["particles/all"]
        pos = part["position/value"][:]
        vel = part["velocity/value"][:] if "velocity" in part else None
        edges = part["box/edges/value"][:]
        times = part["position/time"][:]
    N = pos.shape[1]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        u = mda.Universe.empty(N, trajectory=False).load_new(path, format="H5MD",
                                                             convert_units=False)
    if len(u.trajectory) != len(pos):
        print(f"check_mdanalysis: {path}: MDAnalysis sees {len(u.trajectory)} frames, "
              f"the file holds {len(pos)}")
        return 1
    for k, ts in enumerate(u.trajectory):
        L = np.diag(edges[k])
        checks = [("positions", ts.positions, pos[k], np.abs(L).max()),
                  ("box", ts.dimensions[:3], L, np.abs(L).max()),
                  ("time", np.array([ts.time]), np.array([times[k]]), max(1.0, times[k]))]
        if vel is not None:
            checks.append(("velocities", ts.velocities, vel[k], max(1e-30, np.abs(vel[k]).max())))
        for name, got, want, scale in checks:
            err = np.abs(np.asarray(got, dtype=float) - want).max() / scale
            if not err < 1e-6:  # float32 round-off is 6e-8
                print(f"check_mdanalysis: {path}: frame {k}: {name} differ by {err:.3g} "
                      "(relative)")
                return 1
    print(f"check_mdanalysis: {path}: {len(pos)} frames of {N} particles read by MDAnalysis "
          f"{mda.__version__} agree with the file (positions, velocities, box, time)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
