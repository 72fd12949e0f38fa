#!/usr/bin/python3
"""Energy drift of the cold elastic runs that scripts/cold_drift.sh writes, one line per cap.

E = kinetic + elastic + Coulomb energy (the run's observables, every 10 steps) is conserved by
the elastic dynamics with fixed charges; its change is the integrator's. From step 200 after the
restart on (switching the damping off changes E once): the least-squares slope of
(E - E_200) / E_kin(0) per 1000 steps (the drift: what accumulates) and the largest
|E - E_200| / E_kin(0) (the excursion: with multiple time stepping E swings within each slow
interval, as the slow impulse is given at once, and the samples catch it at every phase).

  usage: /usr/bin/python3 scripts/cold_drift.py DIR START_STEP [--suffix S] CAP [CAP ...]
    START_STEP  the step of the cold state the restarts began from
    --suffix S  the folders are DIR/cap<CAP>S (cold_drift.sh --adaptive: -adaptive)
Writes DIR/drift<S>.csv and prints it as a table. The slope is also given per 10 time units,
which compares runs of different time steps.
"""
import os
import sys

import h5py
import numpy as np

SETTLE_STEPS = 200


def drift(folder, start):
    with h5py.File(os.path.join(folder, "traj.h5"), "r") as f:
        o = f["granagg/observables"]
        step = o["collisions/step"][:]
        time = o["collisions/time"][:]
        ek = o["kinetic_energy/value"][:]
        e = ek + o["elastic_energy/value"][:] + o["coulomb_energy/value"][:]
    after = step > start  # the restart's samples
    step, time, ek, e = step[after], time[after], ek[after], e[after]
    if len(step) < 10:
        raise SystemExit(f"cold_drift.py: {folder} has fewer than 10 samples after step {start}")
    keep = step - start >= SETTLE_STEPS
    s, x = step[keep], (e[keep] - e[keep][0]) / ek[0]
    kilo = (s - s[0]) / 1000.0
    slope = np.polyfit(kilo, x, 1)[0]
    slope_t = np.polyfit((time[keep] - time[keep][0]) / 10.0, x, 1)[0]
    return {"steps": int(s[-1] - s[0]), "ekin0": ek[0], "slope_per_1000": slope,
            "slope_per_10t": slope_t, "dt": (time[keep][-1] - time[keep][0]) / (s[-1] - s[0]),
            "max_excursion": np.abs(x).max(), "end": x[-1]}


def main():
    if len(sys.argv) < 4 or sys.argv[1] in ("-h", "--help"):
        print(__doc__)
        return 0 if len(sys.argv) >= 2 and sys.argv[1] in ("-h", "--help") else 2
    top, start, caps = sys.argv[1], int(sys.argv[2]), sys.argv[3:]
    suffix = ""
    if caps and caps[0] == "--suffix":
        if len(caps) < 3:
            print("cold_drift.py: --suffix needs a value and at least one cap")
            return 2
        suffix, caps = caps[1], caps[2:]
    rows = [(cap, drift(os.path.join(top, "cap" + cap + suffix), start)) for cap in caps]
    with open(os.path.join(top, f"drift{suffix}.csv"), "w") as f:
        f.write("# scripts/cold_drift.py: E = kinetic + elastic + Coulomb of the cold elastic gas "
                "with fixed charges, relative to E_kin(0), from %d steps after step %d on\n"
                % (SETTLE_STEPS, start))
        f.write("every_max,steps,mean_dt,ekin0,slope_per_1000_steps,slope_per_10_time_units,"
                "max_excursion,end\n")
        for cap, r in rows:
            f.write("%s,%d,%.6g,%.6g,%.4g,%.4g,%.4g,%.4g\n" % (
                cap, r["steps"], r["dt"], r["ekin0"], r["slope_per_1000"], r["slope_per_10t"],
                r["max_excursion"], r["end"]))
    print("| every_max | steps | mean dt | drift per 1000 steps | drift per 10 time units "
          "| largest excursion | at the end |")
    print("|---|---|---|---|---|---|---|")
    for cap, r in rows:
        print(f"| {cap}{suffix} | {r['steps']} | {r['dt']:.4g} | {r['slope_per_1000']:.2g} "
              f"| {r['slope_per_10t']:.2g} | {r['max_excursion']:.2g} | {r['end']:.2g} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
