#!/usr/bin/env bash
# Same physics on both engines (issue 28, "Evidence"; docs/lammps.md, "Same physics"): ensembles of
# `granagg md` and `granagg-lammps` runs from the same initial states (the same configuration and
# seeds: both build the random initial state with md::prepareInitialState), analysed with
# `granagg analyze` per engine, and compared at 3 times (T_g, <|q|>, S_grid, S_particle, the
# particle-cluster count, N_1) by Welch's t with Bonferroni (scripts/lammps_same_physics.py, which
# shares scripts/ensemble_welch.py with scripts/coulomb_accuracy.py). A study, not a test.
#
#   usage: bash scripts/lammps_same_physics.sh [options] OUT
#     --runs N           runs per engine and part, seeds 1..N (default 5)
#     --part P           neutral or charged (repeatable; default: neutral, then charged)
#       neutral: the paper preset (N = 50016, phi = 0.076, K = 0, charging Q = 1) to t = 1000,
#                frames also every 100; compared at t = 300, 600, 1000
#       charged: the paper preset with N = 1e4, coulomb.K = 5, charging.Q = 0.05,
#                coulomb.every = 1 (granagg md evaluates every force at every step, as
#                granagg-lammps does) to t = 60, frames also every 5; compared at 15, 30, 60
#                (the issue allows t <= 150; t = 60 keeps 5 + 5 runs within about 2 hours on
#                2 cores: a granagg-lammps run is about 1.8e8 particle-steps at 2e5 per second)
#     --set KEY=VALUE    appended to both engines' configuration (repeatable; e.g. a small test:
#                        --set system.N=2000 --set run.t_end=20 --set output.frame_interval=5)
#     --lammps-set KEY=VALUE  appended to granagg-lammps's configuration only (repeatable; e.g.
#                        --lammps-set coulomb.every=4: rRESPA against granagg md at every step)
#     --times "A B C"    the comparison times instead of the part's (frames must exist there)
#     --threads T        granagg md threads (default 2)    --ranks P  granagg-lammps ranks (2)
#     --include-unfinished  also analyse runs that stopped before run.t_end (each time is then
#                        compared over the runs that reached it; the table gives the counts)
#     --analyze-only     run nothing; analyse and compare what is there
#   environment: G=build/bin/granagg  GL=build/bin/granagg-lammps  MPIRUN=mpirun
#
# Resumable: runs go one at a time, md and lammps alternating by seed, so that a study cut short
# has balanced ensembles. A run whose folder has `done` is kept. A run with a checkpoint continues
# with --restart (the folder's lock of a killed run is cleared with --force). Otherwise the run
# starts afresh. SIGTERM (or SIGINT) to this script stops the run in progress with its checkpoint
# and exits 143 without analysing; run the same command again to resume.
#
# Writes OUT/PART/{md,lammps}/run<seed>/ (the run folders), run<seed>.log, analysis/ (granagg
# analyze of the ensemble), OUT/PART/comparison.{csv,md}, and OUT/study.log.
{
set -euo pipefail
cd "$(dirname "$0")/.."
G=${G:-build/bin/granagg}
GL=${GL:-build/bin/granagg-lammps}
MPIRUN=${MPIRUN:-mpirun}
PY=/usr/bin/python3
RUNS=5
THREADS=2
RANKS=2
PARTS=()
SETS=()
LAMMPS_SETS=()
TIMES=""
UNFINISHED=0
ANALYZE_ONLY=0
OUT=""
die() { echo "lammps_same_physics.sh: $*" >&2; exit 2; }
while [ $# -gt 0 ]; do
  case "$1" in
    --runs) [[ ${2:-} =~ ^[1-9][0-9]*$ ]] || die "--runs needs a positive integer"
            RUNS=$2; shift 2 ;;
    --part) case ${2:-} in neutral|charged) PARTS+=("$2") ;;
              *) die "--part must be neutral or charged, not '${2:-}'" ;; esac; shift 2 ;;
    --set) [[ ${2:-} == *=* ]] || die "--set needs KEY=VALUE"; SETS+=(--set "$2"); shift 2 ;;
    --lammps-set) [[ ${2:-} == *=* ]] || die "--lammps-set needs KEY=VALUE"
                  LAMMPS_SETS+=(--set "$2"); shift 2 ;;
    --times) TIMES=${2:-}; [ -n "$TIMES" ] || die "--times needs times"; shift 2 ;;
    --threads) THREADS=${2:-}; shift 2 ;;
    --ranks) RANKS=${2:-}; shift 2 ;;
    --include-unfinished) UNFINISHED=1; shift ;;
    --analyze-only) ANALYZE_ONLY=1; shift ;;
    -h|--help) sed -n '2,/^{/p' "$0" | grep '^#' | sed -E 's/^# ?//'; exit 0 ;;
    -*) die "unknown option '$1' (see --help)" ;;
    *) [ -z "$OUT" ] || die "one output folder only ('$OUT', '$1')"; OUT=$1; shift ;;
  esac
done
[ -n "$OUT" ] || die "give the output folder (see --help)"
[ ${#PARTS[@]} -gt 0 ] || PARTS=(neutral charged)
[ -x "$G" ] || die "no granagg at $G (run bash scripts/setup.sh)"
[ -x "$GL" ] || die "no granagg-lammps at $GL (needs liblammps-dev; docs/lammps.md)"
ROOT_FLAG=()
[ "$(id -u)" -ne 0 ] || ROOT_FLAG=(--allow-run-as-root)

part_args() {
  case "$1" in
    neutral) echo "--preset paper --set output.frame_interval=100" ;;
    charged) echo "--preset paper --set system.N=10000 --set coulomb.K=5 --set charging.Q=0.05" \
                  "--set coulomb.every=1 --set run.t_end=60 --set output.frame_interval=5" ;;
  esac
}
part_times() { case "$1" in neutral) echo "300 600 1000" ;; charged) echo "15 30 60" ;; esac; }

mkdir -p "$OUT"
LOG="$OUT/study.log"
say() { echo "[$(date -u +%FT%TZ)] $*" | tee -a "$LOG" >&2; }

STOPPED=0
CHILD=""
# shellcheck disable=SC2317  # (invoked by the trap)
on_signal() {
  STOPPED=1
  # mpirun forwards SIGTERM to its ranks; both engines stop at a step boundary with a checkpoint
  [ -z "$CHILD" ] || kill -TERM "$CHILD" 2>/dev/null || true
}
trap on_signal TERM INT

# run_one PART ENGINE SEED: runs or continues one run; returns 1 when the study was stopped
run_one() {
  local part=$1 engine=$2 seed=$3 dir="$OUT/$1/$2/run$3" t0 rc cmd
  [ -f "$dir/done" ] && return 0
  mkdir -p "$OUT/$part/$engine"
  if [ "$engine" = md ]; then
    if [ -f "$dir/checkpoint.h5" ]; then
      cmd=("$G" md --restart "$dir" --threads "$THREADS" --force)
    else
      # shellcheck disable=SC2207
      cmd=("$G" md $(part_args "$part") "${SETS[@]}" --set system.seed="$seed"
           --threads "$THREADS" --out "$dir" --force)
    fi
  else
    if [ -f "$dir/checkpoint.toml" ]; then
      cmd=("$MPIRUN" "${ROOT_FLAG[@]}" --oversubscribe -np "$RANKS" "$GL" --restart "$dir" --force)
    else
      # shellcheck disable=SC2207
      cmd=("$MPIRUN" "${ROOT_FLAG[@]}" --oversubscribe -np "$RANKS" "$GL" $(part_args "$part")
           "${SETS[@]}" "${LAMMPS_SETS[@]}" --set system.seed="$seed" --out "$dir" --force)
    fi
  fi
  say "$part $engine run $seed: ${cmd[*]}"
  t0=$(date +%s)
  "${cmd[@]}" >> "$OUT/$part/$engine/run$seed.log" 2>&1 &
  CHILD=$!
  rc=0
  wait "$CHILD" || rc=$?
  # (a trapped signal interrupts wait: wait again for the run to write its checkpoint)
  while kill -0 "$CHILD" 2>/dev/null; do wait "$CHILD" || rc=$?; done
  CHILD=""
  echo "$(( $(date +%s) - t0 ))" >> "$dir/wall_seconds" 2>/dev/null || true
  if [ "$STOPPED" = 1 ]; then
    say "$part $engine run $seed stopped (exit $rc); it continues from its checkpoint when" \
        "this command runs again"
    return 1
  fi
  if [ "$rc" = 0 ]; then
    awk '{s += $1} END {print s}' "$dir/wall_seconds" > "$dir/done"
    say "$part $engine run $seed done in $(cat "$dir/done") s"
  else
    say "$part $engine run $seed FAILED (exit $rc; log: $OUT/$part/$engine/run$seed.log)"
  fi
}

say "granagg: $("$G" --version 2>&1 | head -1); parts: ${PARTS[*]}; $RUNS runs per engine;" \
    "granagg md on $THREADS threads, granagg-lammps on $RANKS ranks; extra: ${SETS[*]:-none};" \
    "granagg-lammps only: ${LAMMPS_SETS[*]:-none}"
if [ "$ANALYZE_ONLY" = 0 ]; then
  for part in "${PARTS[@]}"; do
    for seed in $(seq 1 "$RUNS"); do
      for engine in md lammps; do
        run_one "$part" "$engine" "$seed" || { say "stopped"; exit 143; }
      done
    done
  done
fi

for part in "${PARTS[@]}"; do
  for engine in md lammps; do
    runs=()
    for seed in $(seq 1 "$RUNS"); do
      d="$OUT/$part/$engine/run$seed"
      if [ -f "$d/done" ] || { [ "$UNFINISHED" = 1 ] && [ -f "$d/traj.h5" ]; }; then
        runs+=("$d")
      fi
    done
    if [ ${#runs[@]} -lt 2 ]; then
      say "$part $engine: ${#runs[@]} usable runs, fewer than 2: not analysed"
      rm -rf "$OUT/$part/$engine/analysis"
      continue
    fi
    "$G" analyze "${runs[@]}" --out "$OUT/$part/$engine/analysis" --force --threads "$THREADS" \
        -q 2>> "$LOG" && say "$part $engine: analysed ${#runs[@]} runs: ${runs[*]##*/}"
  done
  "$PY" scripts/lammps_same_physics.py "$OUT/$part" --times "${TIMES:-$(part_times "$part")}" \
      | tee -a "$LOG" || say "$part: no comparison (see above)"
done
exit 0
}
