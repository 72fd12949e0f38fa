#!/usr/bin/env bash
# Is the adaptive time step accurate enough for the science? (docs/benchmarks.md, "Adaptive time
# step"). Runs ensembles of the paper's gas at N = 2000 on the fixed "auto" step (the reference)
# and on integrator.dt = "adaptive", from the same seeds, analyses each ensemble and compares
# them observable by observable at 3 times (scripts/adaptive_accuracy.py: Welch's t for T_g,
# mean |q|, S_grid, S_particle, the particle-cluster count and N_1, Bonferroni over the tests;
# scripts/ensemble_welch.py). A study, not a test.
#
#   usage: bash scripts/adaptive_accuracy.sh [--out DIR] [--runs R] [--n N] [--jobs J] [PART ...]
#     DIR   default results/adaptive_accuracy (reused: finished runs are not redone)
#     R     runs per step rule and part, seeds 1..R (default 10)
#     N     particles (default 2000; phi = 0.076 as in the paper)
#     J     runs at once, one thread each (default 2)
#     PART  neutral (the paper preset, K = 0, to t = 1000; compared at 100, 300, 1000) and/or
#           charged (K = 5, Q = 0.05, to t = 1000; compared at 100, 300, 1000) (default: both)
#
# Environment: GRANAGG_BIN (default build/bin/granagg; copy it elsewhere first if you will
# rebuild while the study runs). A run killed half-way starts again from t = 0. The whole script
# is one brace group ending in exit, so editing it while a study runs cannot change the study.
{
set -euo pipefail
cd "$(dirname "$0")/.."
G=${GRANAGG_BIN:-build/bin/granagg}
PY=/usr/bin/python3
OUT=results/adaptive_accuracy
RUNS=10
N=2000
JOBS=2
PARTS=()
die() { echo "adaptive_accuracy.sh: $*" >&2; exit 2; }
while [ $# -gt 0 ]; do
  case "$1" in
    --out) OUT=${2:?}; shift 2 ;;
    --runs) [[ ${2:-} =~ ^[1-9][0-9]*$ ]] || die "--runs needs a positive integer"
            RUNS=$2; shift 2 ;;
    --n) [[ ${2:-} =~ ^[1-9][0-9]*$ ]] || die "--n needs a positive integer"; N=$2; shift 2 ;;
    --jobs) [[ ${2:-} =~ ^[1-9][0-9]*$ ]] || die "--jobs needs a positive integer"
            JOBS=$2; shift 2 ;;
    -h|--help) sed -n '2,/^{/p' "$0" | grep '^#' | sed -E 's/^# ?//'; exit 0 ;;
    neutral|charged) PARTS+=("$1"); shift ;;
    *) die "unknown part or option '$1' (see --help)" ;;
  esac
done
[ ${#PARTS[@]} -gt 0 ] || PARTS=(neutral charged)
[ -x "$G" ] || die "no granagg at $G (run bash scripts/setup.sh)"

# the part's settings, and its comparison times
part_settings() {
  case "$1" in
    neutral) echo "--set run.t_end=1000" ;;
    charged) echo "--set coulomb.K=5 --set charging.Q=0.05 --set run.t_end=1000" ;;
  esac
}
TIMES="100 300 1000"
rule_settings() {
  case "$1" in
    fixed) echo "--set integrator.dt=auto" ;;
    adaptive) echo "--set integrator.dt=adaptive" ;;
  esac
}

mkdir -p "$OUT"
LOG="$OUT/study.log"
say() { echo "[$(date -u +%FT%TZ)] $*" | tee -a "$LOG" >&2; }
say "granagg: $("$G" --version 2>&1 | head -1); N = $N, $RUNS runs per rule and part, $JOBS at once"

todo=()
for p in "${PARTS[@]}"; do
  for seed in $(seq 1 "$RUNS"); do
    for rule in fixed adaptive; do  # (alternating: a study cut short stays balanced)
      [ -f "$OUT/$p/$rule/run$seed/done" ] || todo+=("$p $rule $seed")
    done
  done
done
run_one() {
  local p=$1 rule=$2 seed=$3 dir="$OUT/$1/$2/run$3" t0
  mkdir -p "$OUT/$p/$rule"
  t0=$(date +%s)
  # shellcheck disable=SC2046
  if "$G" md --preset paper --set system.N="$N" --set output.frame_interval=100 \
      $(part_settings "$p") $(rule_settings "$rule") --seed "$seed" --threads 1 \
      --out "$dir" --force -q > "$OUT/$p/$rule/run$seed.log" 2>&1; then
    echo "$(( $(date +%s) - t0 ))" > "$dir/done"
    say "$p $rule run $seed done in $(cat "$dir/done") s"
  else
    say "$p $rule run $seed FAILED (log: $OUT/$p/$rule/run$seed.log)"
  fi
}
export -f run_one part_settings rule_settings say
export G OUT N LOG
if [ ${#todo[@]} -gt 0 ]; then
  printf '%s\n' "${todo[@]}" | xargs -P "$JOBS" -L 1 bash -c 'run_one $0 $1 $2'
fi

for p in "${PARTS[@]}"; do
  for rule in fixed adaptive; do
    runs=()
    for seed in $(seq 1 "$RUNS"); do
      [ -f "$OUT/$p/$rule/run$seed/done" ] && runs+=("$OUT/$p/$rule/run$seed")
    done
    [ ${#runs[@]} -ge 2 ] || { say "$p $rule: fewer than 2 finished runs, not analysed"; continue; }
    "$G" analyze "${runs[@]}" --out "$OUT/$p/$rule/analysis" --force --threads "$JOBS" -q \
      && say "$p $rule: analysed ${#runs[@]} runs"
  done
  "$PY" scripts/adaptive_accuracy.py "$OUT/$p" --times "$TIMES" || true
done
exit 0
}
