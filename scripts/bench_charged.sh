#!/usr/bin/env bash
# Where a charged run's time goes, early and late, for one or more granagg binaries side by side
# (issue 15; docs/benchmarks-coulomb.md, "The charged gas at the paper's scale"). Performance is
# measured here, never in tests.
#
#   usage: bash scripts/bench_charged.sh [--out DIR] BIN [BIN ...]
#     DIR  default results/bench_charged (overwritten)
#     BIN  granagg binaries to compare (e.g. a build of an older commit, then the current one)
#
# early  the paper preset with K = 5, Q = 0.05 (N = 50016, phi = 0.076), t = 0 .. EARLY_T from
#        the random start: the hot, homogeneous gas (PPPM-bound)
# late   a restart of a cold, clustered K = 5 gas (N = 1e4, t = 150, the validation study's
#        ensemble) for LATE_DT time units: the regime in which a run to t = 1000 spends more than
#        99 % of its steps (pair-bound). The state is LATE_STATE (a run folder with
#        checkpoint.h5); if absent, the first BIN makes one (N = 1e4 to t = 150, ~10 min on 2
#        cores) and keeps it in DIR/late-state.
# Each phase runs REPEATS times per binary with `--profile`; the table gives the fastest loop
# time and its split by phase (OUT/profile.csv of each run).
#
# Environment: THREADS (default 2), REPEATS (2), EARLY_T (2), LATE_DT (3),
# LATE_STATE (default results/validate/charged-K5/runs/K5/run2 when present).
{
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=results/bench_charged
BINS=()
while [ $# -gt 0 ]; do
  case "$1" in
    --out) OUT=$2; shift 2 ;;
    -h|--help) sed -n '2,/^{/p' "$0" | grep '^#' | sed -E 's/^# ?//'; exit 0 ;;
    *) [ -x "$1" ] || { echo "bench_charged.sh: '$1' is not an executable" >&2; exit 2; }
       BINS+=("$(realpath "$1")"); shift ;;
  esac
done
[ ${#BINS[@]} -gt 0 ] \
  || { echo "bench_charged.sh: give at least one granagg binary (see --help)" >&2; exit 2; }
THREADS=${THREADS:-2}
REPEATS=${REPEATS:-2}
EARLY_T=${EARLY_T:-2}
LATE_DT=${LATE_DT:-3}
LATE_STATE=${LATE_STATE:-results/validate/charged-K5/runs/K5/run2}
rm -rf "$OUT"
mkdir -p "$OUT"
say() { echo "[$(date -u +%FT%TZ)] $*" >&2; }
export OMP_NUM_THREADS=$THREADS

if [ ! -f "$LATE_STATE/checkpoint.h5" ]; then
  LATE_STATE=$OUT/late-state
  say "no late state: making one with ${BINS[0]} (N = 1e4, K = 5, Q = 0.05, t = 150)"
  "${BINS[0]}" md --preset paper --set system.N=10000 --set coulomb.K=5 --set charging.Q=0.05 \
    --set run.t_end=150 --set output.frames_per_decade=0 --set output.frame_interval=50 \
    --threads "$THREADS" --out "$LATE_STATE" -q
fi
T_STATE=$(/usr/bin/python3 -c "
import h5py, sys
f = h5py.File(sys.argv[1] + '/checkpoint.h5', 'r')
print(repr(float(f['state'].attrs['time'])))" "$LATE_STATE")
T_LATE=$(awk "BEGIN {print $T_STATE + $LATE_DT}")

say "load $(cut -d' ' -f1-3 /proc/loadavg); $THREADS threads, $REPEATS repeats;" \
  "late state $LATE_STATE (t = $T_STATE)"
for b in "${!BINS[@]}"; do
  G=${BINS[$b]}
  echo "$b $("$G" --version | head -n 1) $G" >> "$OUT/binaries.txt"
  mkdir -p "$OUT/bin$b"
  for rep in $(seq "$REPEATS"); do
    d=$OUT/bin$b/early$rep
    "$G" md --preset paper --set coulomb.K=5 --set charging.Q=0.05 --set run.t_end="$EARLY_T" \
      --set output.frames_per_decade=0 --set output.frame_interval=0 --profile \
      --threads "$THREADS" \
      --out "$d" > "$d.log" 2>&1
    d=$OUT/bin$b/late$rep
    mkdir -p "$d"
    cp "$LATE_STATE"/checkpoint.h5 "$LATE_STATE"/traj.h5 "$d"/
    [ -f "$LATE_STATE/run.json" ] && cp "$LATE_STATE/run.json" "$d"/
    "$G" md --restart "$d" --set run.t_end="$T_LATE" --profile --threads "$THREADS" > "$d.log" 2>&1
    rm -f "$d/traj.h5" "$d/checkpoint.h5"
    say "binary $b repeat $rep done (load $(cut -d' ' -f1 /proc/loadavg))"
  done
done
/usr/bin/python3 - "$OUT" "${#BINS[@]}" "$REPEATS" <<'EOF' | tee "$OUT/summary.md"
import os, sys
sys.path.insert(0, "scripts")
import granagg_tables as gt
out, nb, reps = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
names = [l.split(" ", 1)[1].strip() for l in open(os.path.join(out, "binaries.txt"))]
phases = ["contact_pass_s", "coulomb_real_slow_s", "pppm_sort_s", "pppm_assignment_s",
          "pppm_ffts_s", "pppm_k_space_s", "pppm_interpolation_s", "coulomb_list_s",
          "contact_list_s", "kick_drift_s", "other_s"]
for phase in ("early", "late"):
    best = []
    for b in range(nb):
        runs = [gt.read(os.path.join(out, f"bin{b}", f"{phase}{r}", "profile.csv"))
                for r in range(1, reps + 1)]
        runs = [r for r in runs if r is not None]
        best.append(min(runs, key=lambda r: r["loop_s"][0]))
    print(f"\n{phase}: N = {int(best[0]['N'][0])}, {int(best[0]['steps'][0])} steps; "
          f"fastest of {reps}; ms per step (share of the loop)\n")
    print("| phase | " + " | ".join(f"binary {b}" for b in range(nb)) + " |")
    print("|---|" + "---|" * nb)
    for p in phases:
        cells = []
        for r in best:
            s = r[p][0]
            cells.append(f"{1e3 * s / r['steps'][0]:.2f} ({100 * s / r['loop_s'][0]:.0f} %)")
        print(f"| {p[:-2].replace('_', ' ')} | " + " | ".join(cells) + " |")
    cells = [f"**{1e3 * r['loop_s'][0] / r['steps'][0]:.2f}** "
             f"({r['N'][0] * r['steps'][0] / r['loop_s'][0]:.3g} particle-steps/s)" for r in best]
    print("| **loop** | " + " | ".join(cells) + " |")
print("\nbinaries: " + "; ".join(f"{b}: {n}" for b, n in enumerate(names)))
EOF
exit 0
}
