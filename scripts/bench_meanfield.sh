#!/usr/bin/env bash
# Mean-field benchmarks (issue 2): wall time of the Smoluchowski solvers against the targets,
# side by side in one run on this machine. Prints a Markdown table for docs/benchmarks.md.
#   usage: bash scripts/bench_meanfield.sh [BUILD_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
G=${1:-build}/bin/granagg
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT

run() {  # label, then granagg arguments; prints "| label | wall s | last line of the summary |"
  local label=$1; shift
  local t0=$(date +%s.%N)
  "$G" "$@" --out "$TMP/out.csv" --force > "$TMP/log" 2>&1
  local t1=$(date +%s.%N)
  local S=$(grep -v '^#' "$TMP/out.csv" | tail -n 1 | cut -d, -f2)
  local z=$(grep -o 'z_inf = [0-9.]*' "$TMP/log" | head -n 1 || true)
  local loss=$(grep -v '^#' "$TMP/out.csv" | tail -n +2 \
    | awk -F, '{a = $7 < 0 ? -$7 : $7; if (a > m) m = a} END {printf "%.1e", m}')
  printf '| %s | %.2f | %s | %s | %s |\n' "$label" "$(echo "$t1 - $t0" | bc)" "$S" "${z:-}" "$loss"
}

echo "Machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs);" \
  "$("$G" --version)"
echo
echo "| run | wall [s] | final S | asymptotic z | largest abs. mass change |"
echo "|---|---|---|---|---|"
for beta in 2 2.5 3 4; do
  run "sectional beta=$beta, r=1.05, to S=1e8" smol --beta $beta --method sectional --s-end 1e8 \
    --t-end 1e12
done
for beta in 2 3; do
  run "discrete beta=$beta (adams) to S=1e4" smol --beta $beta --method discrete --s-end 1e4 \
    --t-end 1e8
done
run "discrete beta=2 (bdf, matrix-free GMRES) to S=1e4" smol --beta 2 --method discrete \
  --integrator bdf --s-end 1e4 --t-end 1e8
OMP_NUM_THREADS=1 run "discrete beta=2 (adams), 1 thread, to S=1e4" smol --beta 2 \
  --method discrete --s-end 1e4 --t-end 1e8
