#!/usr/bin/env bash
# What running granagg's model on LAMMPS costs (issue 28, "Cost"; docs/lammps.md): particle-steps
# per second of `granagg md`, `granagg-lammps` on 1 and 2 MPI ranks, and Debian's plain `lmp` on
# the same LAMMPS input without the charging fix, side by side on this machine, from the same
# state, at the same time step. Performance is measured here, never in tests.
#
#   usage: bash scripts/bench_lammps_engine.sh [--out DIR]   (default results/bench_lammps_engine,
#                                                              overwritten)
#   writes DIR/cost.csv (one row per case, code and core count) and DIR/cost.md (the table, the
#   settings, the machine and the load), and prints cost.md.
#
#   environment: N=10000  K=5  Q=0.05  T_PREP=5 (length of the run that charges the state)
#                CHARGED_STEPS="100 400"  NEUTRAL_STEPS="200 2000" (timed window n1..n2)
#                REPEATS=3  THREADS="1 2" (granagg md)  RANKS="1 2" (granagg-lammps, lmp)
#                EVERY1_THREADS="1" (also granagg md with coulomb.every = 1 on these thread
#                counts: every force at every step, as LAMMPS integrates; "" skips it)
#                RESPA_EVERY=4 (charged: also granagg-lammps with coulomb.every = RESPA_EVERY,
#                run_style respa with the PPPM mesh every RESPA_EVERY steps; "" skips it)
#                G=build/bin/granagg  GL=build/bin/granagg-lammps
#                WAIT_LOAD=0.5  WAIT_MAX=300 (wait until the 1-minute load is below WAIT_LOAD,
#                at most WAIT_MAX seconds, then run anyway and say the load)
#
# The state. LAMMPS's PPPM does nothing while every charge is zero, so the charged case starts
# from charges that collisional charging made: `granagg md --preset paper` with N, coulomb.K = K
# and charging.Q = Q from the random start to t = T_PREP (2 threads, not timed); its last frame
# (DIR/state/traj.h5) is the initial state of every timed run (charging.initial = "file"). The
# neutral case starts from the same positions and velocities with zero charges, coulomb.K = 0,
# and the paper's neutral charging (Q = 1, the charges exert no force). Both are the paper preset
# otherwise: Hertz contacts E = 278.6, D = 27.7 clamped, phi = 0.076, the auto time step
# (contact time of a 7.43 impact / 50), coulomb.accuracy = 1e-4.
#
# The codes, each at its own design for the same configuration:
# - granagg md: the default multiple time stepping (coulomb.every = "auto"), and with
#   EVERY1_THREADS coulomb.every = 1.
# - granagg-lammps: the translated input (OUT/lammps.in: gran/hertz/history + coul/long + pppm with
#   granagg's PPPM design, fix nve/sphere) with fix granagg/charging, every force every step;
#   charged also with RESPA_EVERY (its rate counts steps of granagg's dt: RESPA_EVERY per
#   LAMMPS step, so that every row advances the same time per particle-step).
# - plain LAMMPS: that same lammps.in and initial.data, run by Debian's `lmp`, without the line
#   `fix granagg ...` (nothing else changes: the same PPPM grid, G, cutoff, skin, dt, thermo).
#   The ratio granagg-lammps / plain LAMMPS on one rank is the overhead of the fix.
#
# Timing: the steps n1..n2 of a run from the state (the first n1 steps warm up and cancel).
# - granagg md: loop_s of `--profile` (the MD loop, output included) of a run of n2 steps minus
#   that of a run of n1 steps (as scripts/bench_md_lammps.sh does).
# - granagg-lammps: it runs in chunks of output.observable_interval = n1 steps (`run n1 pre no
#   post no`); the time is the sum of LAMMPS's "Loop time" over the chunks after the first
#   (log.lammps), so the run library's work between chunks (observables, frames) is outside.
# - plain LAMMPS: `run n1` then `run n2-n1`; the second run's "Loop time".
# Each rate is from the fastest of REPEATS runs (load only ever slows a run down); the range over
# the repeats is given as the noise. The overhead of the fix is also given per repeat (its two runs
# lie a minute apart at most), as the median and range of the per-repeat ratios.
{
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/bench_common.sh
OUT=results/bench_lammps_engine
while [ $# -gt 0 ]; do
  case "$1" in
    --out) OUT=$2; shift 2 ;;
    -h|--help) sed -n '2,/^{/p' "$0" | grep '^#' | sed -E 's/^# ?//'; exit 0 ;;
    *) echo "bench_lammps_engine.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
N=${N:-10000}
K=${K:-5}
Q=${Q:-0.05}
T_PREP=${T_PREP:-5}
CHARGED_STEPS=${CHARGED_STEPS:-"100 400"}
NEUTRAL_STEPS=${NEUTRAL_STEPS:-"200 2000"}
REPEATS=${REPEATS:-3}
THREADS=${THREADS:-"1 2"}
RANKS=${RANKS:-"1 2"}
EVERY1_THREADS=${EVERY1_THREADS-1}
RESPA_EVERY=${RESPA_EVERY-4}
G=$(realpath "${G:-build/bin/granagg}")
GL=$(realpath "${GL:-build/bin/granagg-lammps}")
WAIT_LOAD=${WAIT_LOAD:-0.5}
WAIT_MAX=${WAIT_MAX:-300}
for b in "$G" "$GL"; do
  [ -x "$b" ] || { echo "bench_lammps_engine.sh: no binary at $b (build it first)" >&2; exit 1; }
done
bench_need_lmp bench_lammps_engine.sh
command -v mpirun >/dev/null 2>&1 || RANKS=1
rm -rf "$OUT"
mkdir -p "$OUT/bin"
OUT=$(realpath "$OUT")
# private copies: a rebuild of the shared tree during the benchmark must not replace them
cp "$G" "$OUT/bin/granagg"
cp "$GL" "$OUT/bin/granagg-lammps"
G=$OUT/bin/granagg
GL=$OUT/bin/granagg-lammps
say() { echo "[$(date -u +%FT%TZ)] $*" >&2; }
START=$(now)

waited=0
while awk "BEGIN {exit !($(load1) >= $WAIT_LOAD)}" && [ "$waited" -lt "$WAIT_MAX" ]; do
  [ "$waited" -gt 0 ] || say "waiting for the 1-minute load ($(load1)) to drop below $WAIT_LOAD"
  sleep 15
  waited=$((waited + 15))
done
LOAD_START="$(cut -d' ' -f1-3 /proc/loadavg)"
say "load $LOAD_START (waited ${waited} s)"

# ---------------------------------------------------------------------------------------------
# The charged state
say "state: granagg md --preset paper, N = $N, K = $K, Q = $Q, to t = $T_PREP"
OMP_NUM_THREADS=2 "$G" md --preset paper --set system.N="$N" --set coulomb.K="$K" \
  --set charging.Q="$Q" --set run.t_end="$T_PREP" --set output.frames_per_decade=0 \
  --set output.frame_interval=0 --set output.checkpoint_wall_seconds=0 --threads 2 \
  --out "$OUT/state" > "$OUT/state.log" 2>&1 || { cat "$OUT/state.log" >&2; exit 1; }
STATE=$OUT/state/traj.h5
read -r DT STATE_T STATE_TG STATE_Q STATE_QMAX < <(/usr/bin/python3 - "$STATE" <<'PY'
import sys
import h5py
import numpy as np
f = h5py.File(sys.argv[1], "r")
a = f["particles/all"]
q = a["charge/value"][-1]
v = a["velocity/value"][-1]
print(repr(float(f["parameters"].attrs["dt"])), repr(float(a["position/time"][-1])),
      f"{np.mean(v * v):.4g}", f"{np.mean(np.abs(q)):.4g}", f"{np.max(np.abs(q)):.4g}")
PY
)
say "state at t = $STATE_T: T_g = $STATE_TG, <|q|> = $STATE_Q, max |q| = $STATE_QMAX; dt = $DT"

# ---------------------------------------------------------------------------------------------
# One run of each kind -> seconds of the window n1..n2
case_sets() {  # case -> the --set words of that case (besides N, the state and the run length)
  if [ "$1" = charged ]; then
    echo "--set coulomb.K=$K --set charging.Q=$Q --set charging.initial=file"
  else
    echo "--set coulomb.K=0 --set charging.initial=neutral"
  fi
}
common_sets() {  # n1 n2 -> --set words: the state, n2 steps, observables every n1 steps
  echo "--set system.N=$N --set system.initial=$STATE --set run.t_end=$(calc "$2 * $DT")" \
    "--set output.observable_interval=$1 --set output.frames_per_decade=0" \
    "--set output.frame_interval=0 --set output.checkpoint_wall_seconds=0"
}

granagg_time() {  # case n1 n2 threads every -> seconds of steps n1..n2
  local c=$1 n1=$2 n2=$3 th=$4 every=$5 n ta tb
  for n in "$n1" "$n2"; do
    # shellcheck disable=SC2046
    OMP_NUM_THREADS=$th "$G" md --preset paper $(case_sets "$c") $(common_sets "$n" "$n") \
      --set coulomb.every="$every" --threads "$th" --profile --out "$OUT/run/g" --force \
      > "$OUT/run/g.log" 2>&1 || { cat "$OUT/run/g.log" >&2; exit 1; }
    if [ "$n" = "$n1" ]; then ta=$(granagg_loop_seconds "$OUT/run/g/profile.csv" "$n")
    else tb=$(granagg_loop_seconds "$OUT/run/g/profile.csv" "$n"); fi
  done
  calc "$tb - $ta"
}

gl_time() {  # case n1 n2 ranks -> seconds of steps n1..n2 (LAMMPS's loop times)
  local c=$1 n1=$2 n2=$3 np=$4 launch
  mapfile -t launch < <(lmp_launch "$np")
  # shellcheck disable=SC2046
  OMP_NUM_THREADS=1 "${launch[@]}" "$GL" --preset paper $(case_sets "$c") \
    $(common_sets "$n1" "$n2") --out "$OUT/run/gl_${c}_$np" --force \
    > "$OUT/run/gl.log" 2>&1 || { cat "$OUT/run/gl.log" >&2; exit 1; }
  local steps
  steps=$(awk '/^Loop time of/ {s += $9} END {print s}' "$OUT/run/gl_${c}_$np/log.lammps")
  [ "$steps" = "$n2" ] || { echo "granagg-lammps ran $steps steps, not $n2" >&2; exit 1; }
  lammps_loop_seconds "$OUT/run/gl_${c}_$np/log.lammps" 2
}

gl_respa_time() {  # n1 n2 ranks k -> seconds of steps n1..n2 of dt (charged, coulomb.every = k:
  # LAMMPS's steps are k dt, chunks of n1 / k of them)
  local n1=$1 n2=$2 np=$3 k=$4 launch dir=$OUT/run/glr_$3
  [ $((n1 % k)) -eq 0 ] || { echo "RESPA_EVERY = $k must divide $n1" >&2; exit 2; }
  mapfile -t launch < <(lmp_launch "$np")
  # shellcheck disable=SC2046
  OMP_NUM_THREADS=1 "${launch[@]}" "$GL" --preset paper $(case_sets charged) \
    $(common_sets $((n1 / k)) "$n2") --set coulomb.every="$k" --out "$dir" --force \
    > "$OUT/run/glr.log" 2>&1 || { cat "$OUT/run/glr.log" >&2; exit 1; }
  local steps
  steps=$(awk '/^Loop time of/ {s += $9} END {print s}' "$dir/log.lammps")
  [ "$steps" = "$((n2 / k))" ] || { echo "granagg-lammps ran $steps steps, not $((n2 / k))" >&2
                                     exit 1; }
  lammps_loop_seconds "$dir/log.lammps" 2
}

plain_input() {  # case n1 n2 ranks -> $OUT/run/lmp_<case>/in.lammps: the input of granagg-lammps's
  # run on that many ranks (the same for any count) without the fix
  local c=$1 n1=$2 n2=$3 src=$OUT/run/gl_${1}_$4 dst=$OUT/run/lmp_$1
  mkdir -p "$dst"
  cp "$src/initial.data" "$dst/"
  grep -q '^fix granagg .*granagg/charging' "$src/lammps.in" \
    || { echo "no fix granagg line in $src/lammps.in" >&2; exit 1; }
  sed -e '/^fix granagg /d' -e "s|^read_data .*|read_data $dst/initial.data|" -e '/^run /d' \
    "$src/lammps.in" > "$dst/in.lammps"
  printf 'run %s\nrun %s\n' "$n1" "$((n2 - n1))" >> "$dst/in.lammps"
}

lmp_time() {  # case n1 n2 ranks -> the "Loop time" of `run n2-n1`
  local c=$1 np=$4 dir=$OUT/run/lmp_$1
  lmp_run "$dir" "$np" "lmp_$np.log" in.lammps
  lammps_loop_seconds "$dir/lmp_$np.log" 2
}

# ---------------------------------------------------------------------------------------------
mkdir -p "$OUT/run"
echo "case,N,code,cores,n1,n2,particle_steps_per_s,per_core,min_over_repeats,max_over_repeats" \
  > "$OUT/cost.csv"
declare -A CODE=(
  [lammps]="LAMMPS (plain lmp): the same input without fix granagg/charging; MPI ranks"
  [granagg-lammps]="granagg-lammps: LAMMPS + fix granagg/charging; MPI ranks"
  [granagg-lammps-respa]="granagg-lammps, coulomb.every = ${RESPA_EVERY:-0} (run_style respa:\
 PPPM every ${RESPA_EVERY:-0} steps); MPI ranks"
  [granagg-md]="granagg md, coulomb.every = auto (the default); OpenMP threads"
  [granagg-md-every1]="granagg md, coulomb.every = 1; OpenMP threads")
ROWS=()
NOTES=()
row() {  # case code cores key n1 n2: a row from the times T[key] (fastest) and rates R[key]
  local rate per lo hi
  # shellcheck disable=SC2086
  rate=$(calc "$N * ($6 - $5) / $(mins ${T[$4]})")
  per=$(calc "$rate / $3")
  # shellcheck disable=SC2086
  read -r lo hi <<< "$(printf '%s\n' ${R[$4]} | sort -g | awk 'NR == 1 {a = $1} {b = $1}
                                                               END {printf "%.3g %.3g", a, b}')"
  echo "$1,$N,$2,$3,$5,$6,$(printf '%.4g' "$rate"),$(printf '%.4g' "$per"),$lo,$hi" \
    >> "$OUT/cost.csv"
  RATE[$4]=$rate
  local vs=""
  if [ -n "${RATE[lmp$3]:-}" ] && [ "${4#lmp}" = "$4" ]; then
    vs=$(calc "$rate / ${RATE[lmp$3]}" | xargs printf '%.2f')
  fi
  local line
  line="| $1 | ${CODE[$2]} | $3 | $(printf '%.3g' "$rate") | $(printf '%.3g' "$per")"
  ROWS+=("$line | $lo-$hi | $vs |")
}

for c in charged neutral; do
  if [ $c = charged ]; then read -r n1 n2 <<< "$CHARGED_STEPS"
  else read -r n1 n2 <<< "$NEUTRAL_STEPS"; fi
  [ $((n2 % n1)) -eq 0 ] && [ "$n2" -gt "$n1" ] \
    || { echo "bench_lammps_engine.sh: the $c window '$n1 $n2' needs n2 a multiple of n1 > 0" >&2
         exit 2; }
  declare -A T=() R=() RATE=()
  add() {  # key seconds
    T[$1]+="$2 "; R[$1]+="$(calc "$N * ($n2 - $n1) / $2") "
  }
  say "$c: steps $n1..$n2, $REPEATS repeats (load $(load1))"
  for rep in $(seq "$REPEATS"); do
    for np in $RANKS; do
      add "gl$np" "$(gl_time $c "$n1" "$n2" "$np")"
      [ -f "$OUT/run/lmp_$c/in.lammps" ] || plain_input $c "$n1" "$n2" "$np"
      add "lmp$np" "$(lmp_time $c "$n1" "$n2" "$np")"
    done
    for th in $THREADS; do add "g$th" "$(granagg_time $c "$n1" "$n2" "$th" auto)"; done
    if [ $c = charged ]; then
      for th in $EVERY1_THREADS; do add "g1_$th" "$(granagg_time $c "$n1" "$n2" "$th" 1)"; done
      if [ -n "$RESPA_EVERY" ]; then
        for np in $RANKS; do add "glr$np" "$(gl_respa_time "$n1" "$n2" "$np" "$RESPA_EVERY")"; done
      fi
    fi
    say "  repeat $rep (load $(load1)):" \
      "$(for k in "${!R[@]}"; do printf '%s %s; ' "$k" "${R[$k]}"; done)"
  done
  for np in $RANKS; do row $c lammps "$np" "lmp$np" "$n1" "$n2"; done
  for np in $RANKS; do row $c granagg-lammps "$np" "gl$np" "$n1" "$n2"; done
  if [ $c = charged ] && [ -n "$RESPA_EVERY" ]; then
    for np in $RANKS; do row $c granagg-lammps-respa "$np" "glr$np" "$n1" "$n2"; done
  fi
  for th in $THREADS; do row $c granagg-md "$th" "g$th" "$n1" "$n2"; done
  if [ $c = charged ]; then
    for th in $EVERY1_THREADS; do row $c granagg-md-every1 "$th" "g1_$th" "$n1" "$n2"; done
  fi
  # the overhead of the fix: granagg-lammps against plain LAMMPS on as many ranks, from the
  # fastest runs and per repeat
  for np in $RANKS; do
    # shellcheck disable=SC2086
    best=$(calc "100 * ($(mins ${T[gl$np]}) / $(mins ${T[lmp$np]}) - 1)")
    per=$(paste -d' ' <(printf '%s\n' ${T[gl$np]}) <(printf '%s\n' ${T[lmp$np]}) \
      | awk '{r[NR] = 100 * ($1 / $2 - 1)}
             END {n = NR; for (i = 1; i <= n; ++i) for (j = i + 1; j <= n; ++j)
                    if (r[j] < r[i]) {t = r[i]; r[i] = r[j]; r[j] = t}
                  med = (n % 2) ? r[(n + 1) / 2] : 0.5 * (r[n / 2] + r[n / 2 + 1])
                  printf "%+.0f %% (%+.0f to %+.0f %%)", med, r[1], r[n]}')
    note="- $c, $np rank(s): fix granagg/charging costs $(printf '%+.0f' "$best") % time per"
    NOTES+=("$note step (fastest runs); per repeat $per")
  done
  for np in $RANKS; do
    note="- $c, plain LAMMPS on $np rank(s), where the time of its last run went:"
    NOTES+=("$note $(lammps_time_split "$OUT/run/lmp_$c/lmp_$np.log")")
  done
  in=$OUT/run/lmp_$c/in.lammps
  ks=$(grep '^kspace' "$in" | paste -sd';' - || true)
  NOTES+=("- $c, LAMMPS input: \`$(grep '^pair_style' "$in")\`${ks:+; \`${ks//;/\`; \`}\`}")
  log=$OUT/run/gl.log
  note="- $c, the last granagg-lammps run ($(grep -m1 'backend:' "$log" | sed 's/.* on //')):"
  note+=" $(grep -m1 '^md: done' "$log" | sed 's/^md: //');"
  note+=" $(grep -m1 'migrations' "$log" | sed 's/^granagg-lammps: \([0-9]*\) migrations.*/\1/')"
  NOTES+=("$note migrations between ranks")
done

ELAPSED=$(calc "$(now) - $START" | xargs printf '%.0f')
{
  echo "# Cost of granagg's model on LAMMPS (scripts/bench_lammps_engine.sh)"
  echo
  echo "- machine: $(bench_machine); load (1, 5, 15 min) at start $LOAD_START, at end" \
    "$(cut -d' ' -f1-3 /proc/loadavg); $(date -u +'%F %H:%M UTC'), ${ELAPSED} s in all"
  echo "- granagg: $("$G" --version | head -n 1); LAMMPS: $(bench_lmp_version);" \
    "$(mpirun --version 2>/dev/null | head -n 1)"
  echo "- state: \`granagg md --preset paper\`, N = $N, K = $K, Q = $Q, from the random start" \
    "to t = $STATE_T: T_g = $STATE_TG, <|q|> = $STATE_Q, max |q| = $STATE_QMAX; dt = $DT (auto)." \
    "Neutral: the same positions and velocities, charges 0, K = 0"
  echo "- rates over the steps n1..n2 (charged: $CHARGED_STEPS, neutral: $NEUTRAL_STEPS)," \
    "fastest of $REPEATS; per core = rate / cores; the last column is the rate over plain" \
    "LAMMPS's on as many cores"
  echo
  echo "| case | code | cores | particle-steps/s | per core | range over repeats | / plain LAMMPS |"
  echo "|---|---|---|---|---|---|---|"
  printf '%s\n' "${ROWS[@]}"
  echo
  printf '%s\n' "${NOTES[@]}"
} > "$OUT/cost.md"
cat "$OUT/cost.md"
exit 0
}
