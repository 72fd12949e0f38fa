#!/usr/bin/env bash
# The cost of the analysis during the run, side by side on one machine (docs/benchmarks.md,
# "In-situ analysis"):
#   1. the paper's neutral run (N = 50016, t = 1000, adaptive step, 10 frames per decade) on
#      THREADS threads, REPEAT times each, alternating: plain; with --analyze; with --analyze
#      and no stored frames; and `granagg analyze` over the plain run's trajectory (the offline
#      path the in-situ one replaces);
#   2. `granagg analyze` of a box of N = 400128 (L = 140) on 1 and on 2 threads (its frames at
#      t <= 0.2);
#   3. the peak resident memory (GNU time's %M) of every command.
# Stop background campaigns first: timings share the cores.
#   usage: bash scripts/bench_insitu.sh [DIR]   (default results/bench-insitu; CSV in DIR/bench.csv)
#   environment: GRANAGG_BIN (build/bin/granagg), THREADS (2), SEED (11), REPEAT (2)
set -euo pipefail
cd "$(dirname "$0")/.."
DIR=${1:-results/bench-insitu}
BIN=${GRANAGG_BIN:-build/bin/granagg}
THREADS=${THREADS:-2}
SEED=${SEED:-11}
REPEAT=${REPEAT:-2}
mkdir -p "$DIR"
CSV="$DIR/bench.csv"
echo "case,threads,wall_s,max_rss_kb,granagg" > "$CSV"
version=$("$BIN" --version | head -n 1 | tr ',' ' ')

timed() {  # timed NAME THREADS CMD...: one row of bench.csv
  local name=$1 threads=$2
  shift 2
  /usr/bin/time -f "%e %M" -o "$DIR/time.txt" env OMP_NUM_THREADS="$threads" "$@" > /dev/null
  read -r wall rss < "$DIR/time.txt"
  echo "$name,$threads,$wall,$rss,$version" >> "$CSV"
  echo "$name ($threads threads): $wall s, $rss KB"
}

PAPER=(md --preset paper --set integrator.dt=adaptive --seed "$SEED" --threads "$THREADS" -q)
for rep in $(seq 1 "$REPEAT"); do
  rm -rf "$DIR/plain" "$DIR/insitu" "$DIR/insitu-bare" "$DIR/offline"
  timed paper_md "$THREADS" "$BIN" "${PAPER[@]}" --out "$DIR/plain"
  timed paper_md_analyze "$THREADS" "$BIN" "${PAPER[@]}" --analyze --out "$DIR/insitu"
  timed paper_md_analyze_no_frames "$THREADS" "$BIN" "${PAPER[@]}" --analyze \
    --set output.trajectory=false --out "$DIR/insitu-bare"
  timed paper_analyze_offline "$THREADS" "$BIN" analyze "$DIR/plain" --out "$DIR/offline" -q \
    --threads "$THREADS"
done

rm -rf "$DIR/big" "$DIR/big-a1" "$DIR/big-a2"
"$BIN" md --preset paper --set system.N=400128 --set run.t_end=0.2 \
  --set output.frames_per_decade=2 --seed "$SEED" --threads "$THREADS" -q --out "$DIR/big"
timed analyze_N400128 1 "$BIN" analyze "$DIR/big" --out "$DIR/big-a1" -q --threads 1
timed analyze_N400128 2 "$BIN" analyze "$DIR/big" --out "$DIR/big-a2" -q --threads 2
echo "wrote $CSV"
