#!/bin/bash
# Benchmark of `granagg analyze` (issue 5): all observables, grid and particle clusters, on a
# synthetic H5MD trajectory of N particles x F frames (scripts/make_synthetic_h5md.py), on
# THREADS cores. Reports wall time and peak resident memory (/usr/bin/time -v). Memory should not
# depend on F: the frames are streamed (the all-origins MSD is off here: it stores every frame by
# design, --msd-origins t0; a last run on evenly spaced frames shows its cost).
#
#   scripts/bench_analysis.sh [N] [FRAMES] [THREADS] [BUILD_DIR]
#   defaults: N = 1e5, FRAMES = 200, THREADS = 2, BUILD_DIR = build-analysis next to the repo
set -euo pipefail
N=${1:-100000}
F=${2:-200}
THREADS=${3:-2}
HERE=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${4:-$HERE/../build-analysis}
BIN=$BUILD/bin/granagg
WORK=$(mktemp -d /tmp/granagg_bench_analysis.XXXXXX)
trap 'rm -rf "$WORK"' EXIT

echo "== synthetic trajectory: N = $N, $F frames"
/usr/bin/python3 "$HERE/scripts/make_synthetic_h5md.py" "$WORK/traj.h5" "$N" "$F"
ls -l "$WORK/traj.h5"

run() {
  local label=$1
  shift
  /usr/bin/time -v "$BIN" analyze "$WORK/traj.h5" --out "$WORK/out-$label" --threads "$THREADS" \
    -q "$@" 2> "$WORK/time-$label.txt"
  local wall mem
  wall=$(grep "Elapsed (wall clock)" "$WORK/time-$label.txt" | awk '{print $NF}')
  mem=$(grep "Maximum resident set size" "$WORK/time-$label.txt" | awk '{print $NF}')
  printf "%-28s N = %-8s frames = %-5s threads = %s  wall = %s  peak RSS = %.1f MiB\n" "$label" \
    "$N" "$F" "$THREADS" "$wall" "$(echo "$mem / 1024" | bc -l)"
}

echo "== granagg analyze ($("$BIN" --version))"
run "all observables (t0 MSD)" --msd-origins t0
run "no particle clusters" --msd-origins t0 --no-particle
run "no grid clusters" --msd-origins t0 --no-grid

# The all-origins MSD needs evenly spaced frames: a second file with linear times.
/usr/bin/python3 "$HERE/scripts/make_synthetic_h5md.py" "$WORK/traj.h5" "$N" "$F" linear > /dev/null
run "all + all-origins MSD" --msd-origins all --msd-max-memory 8192
