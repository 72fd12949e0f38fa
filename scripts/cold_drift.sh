#!/usr/bin/env bash
# Energy drift of the cold charged gas under multiple time stepping, per cap of the slow interval
# (issue 15; docs/benchmarks-coulomb.md, "Session 14"). A cold, clustered state (a run folder with
# checkpoint.h5, e.g. the validation study's N = 1e4, K = 5, Q = 0.05 run at t = 150) is made
# elastic (contact.D = 0) with its charges fixed (charging.mode = "fixed"), so that its total
# energy E = kinetic + elastic + Coulomb is conserved by the dynamics; each copy then runs DT time
# units with coulomb.every_max = CAP, observables every 10 steps. What is left of E's change is
# the integrator's: scripts/cold_drift.py fits its slope per 1000 steps (from step 200 on, after
# the one-off change of switching the damping off) and its largest excursion, both relative to
# the initial kinetic energy, and compares them with what the dissipative gas loses.
#
#   usage: bash scripts/cold_drift.sh [--out DIR] [--dt DT] [--adaptive] STATE CAP [CAP ...]
#     DIR    default results/cold_drift (a folder per cap; existing ones are redone)
#     DT     time units to run (default 30: 8733 steps at the paper preset's dt)
#     --adaptive  the copies continue on integrator.dt = "adaptive" (docs/model.md section 6)
#            instead of the state's step; the folders are then cap<CAP>-adaptive
#     STATE  run folder with checkpoint.h5 and traj.h5 (the cold state)
#     CAP    values of coulomb.every_max (steps), e.g. 16 32 64
# Environment: GRANAGG_BIN (default build/bin/granagg), THREADS (default 1; the caps run 2 at
# once).
{
set -euo pipefail
cd "$(dirname "$0")/.."
G=${GRANAGG_BIN:-build/bin/granagg}
PY=/usr/bin/python3
OUT=results/cold_drift
DT=30
RULE=""
while [ $# -gt 0 ]; do
  case "$1" in
    --out) OUT=$2; shift 2 ;;
    --dt) DT=$2; shift 2 ;;
    --adaptive) RULE=adaptive; shift ;;
    -h|--help) sed -n '2,/^{/p' "$0" | grep '^#' | sed -E 's/^# ?//'; exit 0 ;;
    *) break ;;
  esac
done
[ $# -ge 2 ] || { echo "cold_drift.sh: give a state folder and at least one cap (see --help)" >&2
                  exit 2; }
STATE=$1; shift
[ -f "$STATE/checkpoint.h5" ] || { echo "cold_drift.sh: no $STATE/checkpoint.h5" >&2; exit 2; }
[ -x "$G" ] || { echo "cold_drift.sh: no granagg at $G (run bash scripts/setup.sh)" >&2; exit 2; }
for cap in "$@"; do
  [[ "$cap" =~ ^[0-9]+$ ]] || { echo "cold_drift.sh: cap '$cap' is not a step count" >&2; exit 2; }
done
mkdir -p "$OUT"
read -r T0 S0 < <("$PY" -c "
import h5py, sys
a = h5py.File(sys.argv[1] + '/checkpoint.h5', 'r')['state'].attrs
print(repr(float(a['time'])), int(a['step']))" "$STATE")
T1=$(awk "BEGIN {print $T0 + $DT}")
run_cap() {
  local cap=$1 dir="$OUT/cap$1${RULE:+-$RULE}"
  rm -rf "$dir"
  cp -r "$STATE" "$dir"
  rm -f "$dir/profile.csv"
  # the stored configuration is the one a restart runs with: edit it in the copy
  "$PY" - "$dir/checkpoint.h5" "$cap" "$RULE" <<'EOF'
import re, sys
import h5py
with h5py.File(sys.argv[1], "r+") as f:
    t = f["run/config_toml"][()]
    t = t.decode() if isinstance(t, bytes) else t
    keys = [("D", "0.0"), ("mode", '"fixed"'), ("every_max", sys.argv[2]),
            ("observable_interval", "10")]
    if sys.argv[3]:
        keys.append(("dt", '"%s"' % sys.argv[3]))
    for key, value in keys:
        t, n = re.subn(r"(?m)^%s = .*$" % key, "%s = %s" % (key, value), t)
        if n != 1:
            raise SystemExit("cold_drift.sh: the stored configuration has no single key " + key)
    del f["run/config_toml"]
    f["run/config_toml"] = t
EOF
  "$G" md --restart "$dir" --set run.t_end="$T1" --threads "${THREADS:-1}" > "$dir.log" 2>&1
  echo "cap $cap: $(tail -n 2 "$dir.log" | head -n 1)"
}
export -f run_cap
export G PY OUT STATE T1 RULE
printf '%s\n' "$@" | xargs -P 2 -I{} bash -c 'run_cap {}'
"$PY" scripts/cold_drift.py "$OUT" "$S0" ${RULE:+--suffix "-$RULE"} "$@"
exit 0
}
