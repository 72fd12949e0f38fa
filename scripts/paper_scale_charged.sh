#!/usr/bin/env bash
# One charged run at the paper's scale (issue 15, goal 1): the paper preset (N = 50016,
# phi = 0.076) with K = 5 and the validation study's exchange charging (Q = 0.05), to t = 1000,
# timed end to end with --profile. Resumable: run it again and it continues from the run's
# checkpoint (written every 10 minutes of wall time), so the run may span sessions; the wall
# time of each leg is appended to OUT/legs.csv and the total is their sum.
#
#   usage: bash scripts/paper_scale_charged.sh [OUT]     (default results/paper-scale/K5-seed1)
#   environment: GRANAGG_BIN (default build/bin/granagg), THREADS (2), T_END (1000)
#
# Results: OUT/profile.csv of each leg (copied to OUT/profile-leg<k>.csv), OUT/legs.csv,
# the run's log OUT.log. docs/benchmarks-coulomb.md records the outcome.
{
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${1:-results/paper-scale/K5-seed1}
BIN=${GRANAGG_BIN:-build/bin/granagg}
THREADS=${THREADS:-2}
T_END=${T_END:-1000}
mkdir -p "$(dirname "$OUT")"
[ -f "$OUT.legs.csv" ] \
  || echo "leg,start_utc,end_utc,wall_s,t_start,t_end,status,granagg" > "$OUT.legs.csv"
leg=$(( $(wc -l < "$OUT.legs.csv") ))
t_start=0
if [ -f "$OUT/checkpoint.h5" ]; then
  t_start=$(/usr/bin/python3 -c \
    "import h5py,sys; print(float(h5py.File(sys.argv[1],'r')['state'].attrs['time']))" \
    "$OUT/checkpoint.h5")
  cmd=("$BIN" md --restart "$OUT" --set run.t_end="$T_END" --profile --threads "$THREADS")
else
  cmd=("$BIN" md --preset paper --set coulomb.K=5 --set charging.Q=0.05 --set run.t_end="$T_END"
       --seed 1 --profile --threads "$THREADS" --out "$OUT")
fi
start=$(date -u +%FT%TZ); s0=$(date +%s.%N)
echo "[$start] leg $leg: ${cmd[*]}" >> "$OUT.log"
set +e
OMP_NUM_THREADS=$THREADS "${cmd[@]}" >> "$OUT.log" 2>&1
rc=$?
set -e
s1=$(date +%s.%N)
t_end=$(/usr/bin/python3 -c \
  "import h5py,sys; print(float(h5py.File(sys.argv[1],'r')['state'].attrs['time']))" \
  "$OUT/checkpoint.h5" 2>/dev/null || echo nan)
echo "$leg,$start,$(date -u +%FT%TZ),$(echo "$s1 - $s0" | bc),$t_start,$t_end,$rc,$(
  "$BIN" --version | head -n 1 | tr ',' ' ')" >> "$OUT.legs.csv"
[ -f "$OUT/profile.csv" ] && cp "$OUT/profile.csv" "$OUT.profile-leg$leg.csv"
exit $rc
}
