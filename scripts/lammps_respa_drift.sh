#!/usr/bin/env bash
# Energy conservation of granagg-lammps under rRESPA (docs/lammps.md, "rRESPA: accuracy"): an
# elastic charged gas (contact.D = 0, charges fixed, so that E = kinetic + elastic + Coulomb is
# conserved by the dynamics) run with coulomb.every = 1 (run_style verlet) and k > 1 (run_style
# respa, the PPPM mesh every k steps), from the same random start. Prints, per k, the largest
# excursion of E and the slope of E per 1000 steps of dt (fit from step 200 on), both relative
# to the initial kinetic energy. A study, not a test.
#
#   usage: bash scripts/lammps_respa_drift.sh [--out DIR] [K_VALUES...]   (default: 1 4 8)
#   environment: N=2000  Q0=0.3 (bipolar charges)  COULOMB_K=5  T_END=10  RANKS=1
#                GL=build/bin/granagg-lammps  MPIRUN=mpirun
{
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=results/lammps_respa_drift
if [ "${1:-}" = --out ]; then OUT=$2; shift 2; fi
case "${1:-}" in -h|--help) sed -n '2,/^{/p' "$0" | grep '^#' | sed -E 's/^# ?//'; exit 0 ;; esac
EVERY=("$@")
[ ${#EVERY[@]} -gt 0 ] || EVERY=(1 4 8)
N=${N:-2000}; Q0=${Q0:-0.3}; COULOMB_K=${COULOMB_K:-5}; T_END=${T_END:-10}; RANKS=${RANKS:-1}
GL=${GL:-build/bin/granagg-lammps}
MPIRUN=${MPIRUN:-mpirun}
[ -x "$GL" ] || { echo "lammps_respa_drift.sh: no granagg-lammps at $GL" >&2; exit 2; }
ROOT_FLAG=()
[ "$(id -u)" -ne 0 ] || ROOT_FLAG=(--allow-run-as-root)
mkdir -p "$OUT"
for k in "${EVERY[@]}"; do
  [[ $k =~ ^[1-9][0-9]*$ ]] && [ $((40 % k)) -eq 0 ] \
    || { echo "lammps_respa_drift.sh: k = '$k' must divide 40" >&2; exit 2; }
  # observables every 40 steps of dt (40 / k LAMMPS steps)
  "$MPIRUN" "${ROOT_FLAG[@]}" --oversubscribe -np "$RANKS" "$GL" --preset paper \
    --set system.N="$N" --set coulomb.K="$COULOMB_K" --set charging.initial=bipolar \
    --set charging.q0="$Q0" --set charging.mode=fixed --set contact.D=0 \
    --set coulomb.every="$k" --set run.t_end="$T_END" \
    --set output.observable_interval=$((40 / k)) --set output.frames_per_decade=0 \
    --set output.checkpoint_wall_seconds=0 --out "$OUT/k$k" --force -q > "$OUT/k$k.log" 2>&1 \
    || { cat "$OUT/k$k.log" >&2; exit 1; }
done
/usr/bin/python3 - "$OUT" "${EVERY[@]}" <<'PY'
import sys
import h5py
import numpy as np
out, ks = sys.argv[1], sys.argv[2:]
print("| coulomb.every | integration | steps of dt | max abs(E - E0) / E_kin0 |"
      " slope per 1000 steps / E_kin0 |")
print("|---|---|---|---|---|")
for k in ks:
    with h5py.File(f"{out}/k{k}/traj.h5", "r") as f:
        g = f["granagg/observables"]
        t = g["kinetic_energy/time"][:]
        ek, ee, ec = (g[n + "/value"][:] for n in
                      ("kinetic_energy", "elastic_energy", "coulomb_energy"))
        dt = float(f["parameters"].attrs["dt"]) / int(k)  # LAMMPS's step is k dt
    e = (ek + ee + ec - (ek[0] + ee[0] + ec[0])) / ek[0]
    steps = np.rint(t / dt)
    late = steps >= 200
    slope = np.polyfit(steps[late], e[late], 1)[0] * 1000
    kind = "run_style verlet" if k == "1" else f"run_style respa, mesh every {k}"
    print(f"| {k} | {kind} | {int(steps[-1])} | {np.abs(e).max():.2e} | {slope:+.2e} |")
PY
exit 0
}
