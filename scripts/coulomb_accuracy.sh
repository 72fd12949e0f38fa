#!/usr/bin/env bash
# Is a Coulomb setting accurate enough for the science? (issue 15, docs/benchmarks-coulomb.md,
# "Accuracy behind the settings"). Runs ensembles of the charged gas (K = 5, exchange charging,
# Q = 0.05, the validation study's gas) that differ only in their Coulomb settings, from the same
# seeds, analyses each ensemble, and compares every setting with a tight reference (accuracy
# 1e-5, the total Coulomb force at every step) observable by observable
# (scripts/coulomb_accuracy.py: Welch's t for T_g, mean |q|, S and N_s at t = 50, 100, 150).
#
#   usage: bash scripts/coulomb_accuracy.sh [--out DIR] [--runs R] [--n N] [--jobs J] [SET ...]
#     DIR   default results/coulomb_accuracy (reused: finished runs are not redone)
#     R     runs per setting, seeds 1..R (default 6)
#     N     particles (default 2000; phi = 0.076 as in the paper)
#     J     runs at once, one thread each (default 2)
#     SET   any of: ref default fast follow fastfollow rfast25 rfast20 rfast20cap32
#           rfast20cap64
#           (default: all)
#       ref      coulomb.accuracy = 1e-5, coulomb.every = 1 (no multiple time stepping)
#       default  the defaults before issue 15 (accuracy 1e-4, every auto = 4 at the auto dt,
#                fixed, r_fast 3.5)
#       fast     accuracy 1e-3, every = 8, r_fast = 2.5 (a candidate for a cheaper default)
#       follow   every_max = 16 (the slow interval follows the gas), r_fast 3.5
#       fastfollow  accuracy 1e-3, r_fast = 2.5, every_max = 16
#       rfast25  every_max auto (16), r_fast = 2.5
#       rfast20  every_max auto (16), r_fast = 2.0: the defaults since issue 15
#       rfast20cap32  r_fast = 2.0 and every_max = 32
#       rfast20cap64  r_fast = 2.0 and every_max = 64 (the slow interval may grow to 64 steps)
#
# Cost on 2 cores (measured 2026-12-02, N = 2000, t = 150, 6 runs each): see the doc.
# Environment: GRANAGG_BIN (default build/bin/granagg; copy it elsewhere first if you will
# rebuild while the study runs). The whole script is one brace group ending in exit, so editing
# it while a study runs cannot change the running study.
{
set -euo pipefail
cd "$(dirname "$0")/.."
G=${GRANAGG_BIN:-build/bin/granagg}
PY=/usr/bin/python3
OUT=results/coulomb_accuracy
RUNS=6
N=2000
JOBS=2
SETS=()
while [ $# -gt 0 ]; do
  case "$1" in
    --out) OUT=$2; shift 2 ;;
    --runs) RUNS=$2; shift 2 ;;
    --n) N=$2; shift 2 ;;
    --jobs) JOBS=$2; shift 2 ;;
    -h|--help) sed -n '2,/^{/p' "$0" | grep '^#' | sed -E 's/^# ?//'; exit 0 ;;
    ref|default|fast|follow|fastfollow|rfast25|rfast20|rfast20cap32|rfast20cap64)
      SETS+=("$1"); shift ;;
    *) echo "coulomb_accuracy.sh: unknown setting or option '$1' (see --help)" >&2; exit 2 ;;
  esac
done
[ ${#SETS[@]} -gt 0 ] \
  || SETS=(ref default fast follow fastfollow rfast25 rfast20 rfast20cap32 rfast20cap64)
[ -x "$G" ] \
  || { echo "coulomb_accuracy.sh: no granagg at $G (run bash scripts/setup.sh)" >&2; exit 2; }

settings() {
  case "$1" in
    ref) echo "--set coulomb.accuracy=1e-5 --set coulomb.every=1" ;;
    default) echo "--set coulomb.every_max=1 --set coulomb.r_fast=3.5" ;;
    fast) echo "--set coulomb.accuracy=1e-3 --set coulomb.every=8 --set coulomb.r_fast=2.5" ;;
    follow) echo "--set coulomb.every_max=16 --set coulomb.r_fast=3.5" ;;
    fastfollow)
      echo "--set coulomb.accuracy=1e-3 --set coulomb.r_fast=2.5 --set coulomb.every_max=16" ;;
    rfast25) echo "--set coulomb.r_fast=2.5" ;;
    rfast20) echo "--set coulomb.r_fast=2.0" ;;
    rfast20cap32) echo "--set coulomb.r_fast=2.0 --set coulomb.every_max=32" ;;
    rfast20cap64) echo "--set coulomb.r_fast=2.0 --set coulomb.every_max=64" ;;
  esac
}

mkdir -p "$OUT"
LOG="$OUT/study.log"
say() { echo "[$(date -u +%FT%TZ)] $*" | tee -a "$LOG" >&2; }
say "granagg: $("$G" --version 2>&1 | head -1); N = $N, $RUNS runs per setting, $JOBS at once"

# one line per run still to do: SET SEED
todo=()
for s in "${SETS[@]}"; do
  for seed in $(seq 1 "$RUNS"); do
    [ -f "$OUT/$s/run$seed/done" ] || todo+=("$s $seed")
  done
done
run_one() {
  local s=$1 seed=$2 dir="$OUT/$1/run$2" t0
  mkdir -p "$OUT/$s"
  t0=$(date +%s)
  # shellcheck disable=SC2046
  if "$G" md --preset paper --set coulomb.K=5 --set charging.Q=0.05 --set system.N="$N" \
      --set run.t_end=150 --set output.frame_interval=10 $(settings "$s") --seed "$seed" \
      --threads 1 --out "$dir" --force -q > "$OUT/$s/run$seed.log" 2>&1; then
    echo "$(( $(date +%s) - t0 ))" > "$dir/done"
    say "$s run $seed done in $(cat "$dir/done") s"
  else
    say "$s run $seed FAILED (log: $OUT/$s/run$seed.log)"
  fi
}
export -f run_one settings say
export G OUT N LOG
if [ ${#todo[@]} -gt 0 ]; then
  printf '%s\n' "${todo[@]}" | xargs -P "$JOBS" -L 1 bash -c 'run_one $0 $1'
fi

for s in "${SETS[@]}"; do
  runs=()
  for seed in $(seq 1 "$RUNS"); do
    [ -f "$OUT/$s/run$seed/done" ] && runs+=("$OUT/$s/run$seed")
  done
  [ ${#runs[@]} -ge 2 ] || { say "$s: fewer than 2 finished runs, not analysed"; continue; }
  "$G" analyze "${runs[@]}" --out "$OUT/$s/analysis" --force --threads "$JOBS" -q \
    && say "$s: analysed ${#runs[@]} runs"
done
"$PY" scripts/coulomb_accuracy.py "$OUT"
exit 0
}
