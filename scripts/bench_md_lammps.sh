#!/usr/bin/env bash
# MD throughput of granagg against LAMMPS (issue 3; docs/benchmarks.md): the same neutral
# viscoelastic-Hertz gas (phi = 0.076, E = 278.6, D = 27.7, clamped, d = m = 1, T = 1), the same
# initial state, the same fixed time step and the same Verlet skin, run in one go on this machine.
# Prints Markdown tables for docs/benchmarks.md: the two-body mapping check, then N, code, cores
# (granagg OpenMP threads, LAMMPS MPI ranks), particle-steps/s and the ratio granagg/LAMMPS on the
# same number of cores.
#
#   usage: bash scripts/bench_md_lammps.sh [GRANAGG_BINARY]      (default build/bin/granagg)
#   environment: SIZES="10000 100000"  STEPS_10000="200 2000"  STEPS_100000="100 500"
#                DT=0.002  SKIN=0.3  REPEATS=3  THREADS="1 2"  LMP_RANKS="1 2"
#                SKIP_TWO_BODY=1 (skip the mapping check)
#                LMP_FIXES="nve nve/sphere" (LAMMPS integrators timed; the ratio is against the
#                fastest)
#                PAPER_SCALE=1: also the paper-scale neutral run end to end (N = 50016 to t = 1000,
#                `--preset paper`, seed 1, 2 threads), on the fixed "auto" step and on
#                integrator.dt = "adaptive", interleaved, the fastest of REPEATS each (~5 min)
#                BANDWIDTH=1: also this machine's memory bandwidth, one thread, from the L2 to main
#                memory (scripts/bandwidth.py, ~20 s), the physical limit that docs/benchmarks.md,
#                "Memory traffic of the neutral step", compares the rates with
#
# Installs Debian's `lammps` (29 Sep 2021 stable, binary lmp) if it is missing; builds nothing.
#
# Timing: every run is done at two lengths n1 < n2 from the same initial state; the rate is
# N (n2 - n1) / (t(n2) - t(n1)). For granagg t is the time of the MD loop that `granagg md
# --profile` writes to profile.csv (loop_s: from the first step to the last, output included),
# so start-up,
# initial-state reading and file creation stay out and the first neighbour build cancels; for
# LAMMPS the input does `run n1` then `run n2-n1` and t(n2) - t(n1) is the second run's "Loop time"
# (same steps n1..n2 of the same cooling gas, so both codes do the same physical work). Each time
# is the smallest of REPEATS runs (the machine may be shared: load only slows a run down); the
# range of the per-repeat rates is printed as a measure of the noise. The ratio is given twice:
# from the fastest runs of each code, and as the median (and range) of the ratios within each
# repeat, whose runs lie minutes apart at most -- on a VM whose speed drifts over minutes the
# ratio of two fastest runs can pair one code's fast window with the other's slow one.
#
# LAMMPS mapping (src/GRANULAR/pair_gran_hertz_history.cpp): the normal force on each partner is
#     F = sqrt(delta R_i R_j/(R_i+R_j)) [kn delta + m_eff gamma_n xi'],
# so with R = 1/2 (factor 1/2) and m = 1 (m_eff = 1/2): kn = 2E = 557.2, gamma_n = 4D = 110.8;
# kt = gamma_t = xmu = 0, dampflag 0; `limit_damping` = granagg's contact.clamp = true. Density
# 6/pi gives mass 1 at diameter 1. scripts/lammps/two_body.in checks this mapping against
# `granagg kinetic restitution`.
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
G=$(realpath "${1:-build/bin/granagg}")
[ -x "$G" ] || { echo "bench_md_lammps: no granagg binary at $G (build it first)" >&2; exit 1; }
SIZES=${SIZES-"10000 100000"}   # SIZES="" runs only the two-body check
DT=${DT:-0.002}
REPEATS=${REPEATS:-3}
THREADS=${THREADS:-"1 2"}        # granagg OpenMP threads
LMP_RANKS=${LMP_RANKS:-"1 2"}    # LAMMPS MPI ranks (1 = serial, no mpirun)
E=278.6; D=27.7; PHI=0.076; SKIN=${SKIN:-0.3}   # SKIN: Verlet skin of both codes
# LAMMPS integrators: fix nve integrates the translation only, which is the whole model here (no
# tangential forces, hence no torques: the same trajectory as nve/sphere, checked by the
# temperatures printed below); nve/sphere, the usual choice for granular runs, also integrates
# the (zero) rotation. Both are timed; the ratio is taken against the faster.
LMP_FIXES=${LMP_FIXES:-"nve nve/sphere"}
. scripts/bench_common.sh
KN=$(calc "2 * $E"); GN=$(calc "4 * $D")

bench_need_lmp bench_md_lammps
# Debian's lammps pulls in Open MPI; without it, serial only
if ! command -v mpirun >/dev/null 2>&1; then
  LMP_RANKS=1
fi

TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT

steps_for() {  # N -> "n1 n2": STEPS_<N> if set, else 200 2000 up to N = 2e4 and 100 500 above
  local var="STEPS_$1"
  if [ -n "${!var:-}" ]; then echo "${!var}"
  elif [ "$1" -le 20000 ]; then echo "200 2000"
  else echo "100 500"; fi
}

# ---------------------------------------------------------------------------------------------
# Machine
echo "Machine: $(bench_machine)"
echo "granagg: $("$G" --version 2>&1 | head -n 1); $G"
echo "LAMMPS:  $(bench_lmp_version); $LMP"
echo "Load at start: $(cut -d' ' -f1-3 /proc/loadavg)"
echo

# ---------------------------------------------------------------------------------------------
# Two-body mapping check: restitution of a head-on collision in LAMMPS against granagg's
if [ -z "${SKIP_TWO_BODY:-}" ]; then
  VS="0.05 0.5 1 2"
  declare -A EG
  for c in clamped unclamped; do
    flag=""; [ $c = unclamped ] && flag=--unclamped
    while IFS=, read -r v e _; do EG[$c,$v]=$e; done \
      < <("$G" kinetic restitution --v "$(echo "$VS" | tr ' ' ,)" $flag 2>/dev/null \
          | grep -v '^#' | tail -n +2)
  done
  lmp_e() {  # v clamp dt -> e
    (cd "$TMP" && "$LMP" -in "$ROOT/scripts/lammps/two_body.in" -var v "$1" -var clamp "$2" \
      -var dt "$3" -log none -nocite -echo none) \
      | sed -n 's/^TWO_BODY .* e=\([-0-9.e]*\) .*/\1/p'
  }
  echo "Two-body head-on collision, restitution e(v): LAMMPS pair gran/hertz/history" \
    "(kn = 2E, gamma_n = 4D) against \`granagg kinetic restitution\`"
  echo
  echo "| v | granagg clamped | LAMMPS limit_damping, dt=1e-5 | LAMMPS limit_damping, dt=$DT |" \
    "granagg unclamped (\`--unclamped\`) | LAMMPS without limit_damping, dt=1e-5 |"
  echo "|---|---|---|---|---|---|"
  for v in $VS; do
    printf '| %s | %.6f | %s | %s | %.6f | %s |\n' "$v" "${EG[clamped,$v]:-nan}" \
      "$(lmp_e "$v" 1 1e-5)" "$(lmp_e "$v" 1 "$DT")" "${EG[unclamped,$v]:-nan}" \
      "$(lmp_e "$v" 0 1e-5)"
  done
  echo
fi

# ---------------------------------------------------------------------------------------------
# Throughput
gen_state() {  # N -> $TMP/state_N.csv (granagg) and $TMP/state_N.data (LAMMPS): random
  # non-overlapping positions (random sequential addition, cell list) and Gaussian velocities with
  # zero momentum rescaled to T_g = (1/3N) sum v^2 = 1 exactly, like granagg's own random state.
  /usr/bin/python3 "$ROOT/scripts/lammps/make_state.py" "$1" "$PHI" "$TMP"
}

granagg_time() {  # N steps threads -> seconds of the MD loop (profile.csv's loop_s)
  local N=$1 n=$2 th=$3
  # the neutral model, as in LAMMPS (charges fixed: no charge bookkeeping)
  { granagg_model_toml "$N" "$PHI" "$TMP/state_$N.csv" "$E" "$D" "$DT" "$SKIN"
    granagg_timing_toml "$(calc "$n * $DT")"; } > "$TMP/g.toml"
  OMP_NUM_THREADS=$th "$G" md --config "$TMP/g.toml" --out "$TMP/gout" --force --threads "$th" \
    --profile > "$TMP/g.log" 2>&1 || { cat "$TMP/g.log" >&2; exit 1; }
  # the loop time and step count from profile.csv (machine-readable; the log is for people)
  granagg_loop_seconds "$TMP/gout/profile.csv" "$n" || { cat "$TMP/g.log" >&2; exit 1; }
}

lammps_time() {  # N n1 n2 ranks fix -> loop seconds of steps n1..n2
  local N=$1 n1=$2 n2=$3 np=$4 fix=$5
  cat > "$TMP/bench.in" <<EOF
units           lj
atom_style      sphere
boundary        p p p
comm_modify     vel yes
read_data       $TMP/state_$N.data
pair_style      gran/hertz/history $KN 0.0 $GN 0.0 0.0 0 limit_damping
pair_coeff      * *
neighbor        $SKIN bin
neigh_modify    delay 0 every 1 check yes
fix             1 all $fix
timestep        $DT
thermo          1000000
run             $n1
run             $((n2 - n1))
EOF
  lmp_run "$TMP" "$np" lmp.log bench.in
  cp "$TMP/lmp.log" "$TMP/lmp_$np.log"
  cp "$TMP/lmp.log" "$TMP/lmp_${np}_${fix//\//_}.log"
  grep '^Loop time' "$TMP/lmp.log" | tail -n 1 | awk '{print $4}'
}

ROWS=()
NOTES=()
for N in $SIZES; do
  read -r n1 n2 <<< "$(steps_for "$N")"
  echo "N = $N: generating the initial state, timing steps $n1..$n2" \
    "($REPEATS repeats; load $(cut -d' ' -f1 /proc/loadavg))" >&2
  gen_state "$N"
  declare -A T=() R=()
  for rep in $(seq "$REPEATS"); do
    for np in $LMP_RANKS; do
      for fix in $LMP_FIXES; do
        t=$(lammps_time "$N" "$n1" "$n2" "$np" "$fix")
        T[l$np$fix]+="$t "; R[l$np$fix]+="$(calc "$N * ($n2 - $n1) / $t") "
      done
    done
    for th in $THREADS; do
      ta=$(granagg_time "$N" "$n1" "$th"); tb=$(granagg_time "$N" "$n2" "$th")
      T[a$th]+="$ta "; T[b$th]+="$tb "; R[g$th]+="$(calc "$N * ($n2 - $n1) / ($tb - $ta)") "
    done
    echo "  repeat $rep: load $(cut -d' ' -f1 /proc/loadavg); rates so far: LAMMPS $(
      for np in $LMP_RANKS; do for fix in $LMP_FIXES; do
        printf '%s ranks %s: %s; ' "$np" "$fix" "${R[l$np$fix]}"; done; done)granagg $(
      for th in $THREADS; do printf '%s threads: %s; ' "$th" "${R[g$th]}"; done)" >&2
  done
  # rate from the fastest run of each kind (load only ever slows a run down)
  declare -A LR=()
  for np in $LMP_RANKS; do
    for fix in $LMP_FIXES; do
      # shellcheck disable=SC2086
      lr=$(calc "$N * ($n2 - $n1) / $(mins ${T[l$np$fix]})")
      # the ratio is against the fastest LAMMPS set-up on as many cores
      LR[$np]=$(awk -v a="${LR[$np]:-0}" -v b="$lr" 'BEGIN {print (b > a) ? b : a}')
      # shellcheck disable=SC2086
      ROWS+=("| $N | LAMMPS gran/hertz/history + fix $fix, $([ "$np" -eq 1 ] && echo serial \
        || echo "MPI") | $np | $(printf '%.3g' "$lr") | | | $(range ${R[l$np$fix]}) |")
    done
  done
  for th in $THREADS; do
    # shellcheck disable=SC2086
    rate=$(calc "$N * ($n2 - $n1) / ($(mins ${T[b$th]}) - $(mins ${T[a$th]}))")
    ratio="" paired=""
    if [ -n "${LR[$th]:-}" ]; then
      ratio=$(calc "$rate / ${LR[$th]}" | xargs printf '%.2f')
      # the same ratio repeat by repeat (granagg against the faster LAMMPS integrator of the same
      # repeat, run minutes apart at most): the VM's speed drifts over minutes, and a ratio of two
      # fastest runs can pair a fast window of one code with a slow one of the other
      lists=()
      for fix in $LMP_FIXES; do lists+=("${R[l$th$fix]}"); done
      paired=$(printf '%s\n' "${lists[@]}" | awk -v g="${R[g$th]}" '
        {n = split($0, a, " "); for (k = 1; k <= n; ++k) if (a[k] > best[k]) best[k] = a[k]}
        END {m = split(g, b, " "); for (k = 1; k <= m; ++k) r[k] = b[k] / best[k]
             for (i = 1; i <= m; ++i) for (j = i + 1; j <= m; ++j)
               if (r[j] < r[i]) {t = r[i]; r[i] = r[j]; r[j] = t}
             med = (m % 2) ? r[(m + 1) / 2] : 0.5 * (r[m / 2] + r[m / 2 + 1])
             printf "%.2f (%.2f-%.2f)", med, r[1], r[m]}')
    fi
    # shellcheck disable=SC2086
    ROWS+=("| $N | granagg, OpenMP | $th | $(printf '%.3g' "$rate") | $ratio | $paired | $(range \
      ${R[g$th]}) |")
  done
  # what the window looks like (temperature at n1 and n2, rebuilds, time split), from the log of
  # the last LAMMPS run on the fewest ranks
  # shellcheck disable=SC2086
  log="$TMP/lmp_$(printf '%s\n' $LMP_RANKS | sort -n | head -n 1).log"
  last=$(lammps_last_run "$log")
  temps=$(awk '/^ *Step/ {getline; t = $2} END {print t}' "$log")
  temp2=$(awk '/^Loop time/ {t = prev} {prev = $2} END {print t}' "$log")
  builds=$(grep 'Neighbor list builds' <<< "$last" | awk '{print $NF}')
  brk=$(lammps_time_split "$log")
  NOTES+=("- N = $N, steps $n1..$n2: LAMMPS temperature $temps -> $temp2, $builds neighbour-list \
builds; LAMMPS time split (last run on $(basename "$log" .log | sed "s/lmp_//") rank(s)): $brk")
  np1=$(printf '%s\n' $LMP_RANKS | sort -n | head -n 1)
  NOTES+=("  temperature at step $n2 by LAMMPS integrator (the same trajectory): $(
    for fix in $LMP_FIXES; do printf 'fix %s %s; ' "$fix" "$(awk \
      '/^Loop time/ {t = prev} {prev = $2} END {print t}' "$TMP/lmp_${np1}_${fix//\//_}.log")"
    done)")
done

echo "Throughput: phi = $PHI, dt = $DT, skin $SKIN, clamped Hertz (E = $E, D = $D), T(0) = 1;" \
  "rates over steps n1..n2 from the fastest of $REPEATS runs of each kind; ratios against the" \
  "faster LAMMPS integrator on as many cores, from the fastest runs and, per repeat, from the" \
  "runs of the same repeat (median, min-max)"
echo
echo "| N | code | cores (threads or ranks) | particle-steps/s | granagg / LAMMPS, fastest runs |" \
  "granagg / LAMMPS per repeat: median (range) | range over repeats |"
echo "|---|---|---|---|---|---|---|"
printf '%s\n' "${ROWS[@]}"
echo
printf '%s\n' "${NOTES[@]}"
echo
# ---------------------------------------------------------------------------------------------
# The paper-scale neutral run, end to end (wall time of `granagg md` from start to exit, output
# included): the fixed step against the adaptive one, interleaved
if [ -n "${PAPER_SCALE:-}" ]; then
  declare -A PW PS
  for rep in $(seq 1 "$REPEATS"); do
    for rule in auto adaptive; do
      rm -rf "$TMP/paper_$rule"
      t0=$(now)
      "$G" md --preset paper --seed 1 --threads 2 --set integrator.dt=$rule \
        --out "$TMP/paper_$rule" -q
      w=$(calc "$(now) - $t0")
      PW[$rule]="${PW[$rule]:-} $w"
      PS[$rule]=$(/usr/bin/python3 -c "import h5py, sys; f = h5py.File(sys.argv[1], 'r'); \
print(int(f['granagg/observables/dt/step'][-1]))" "$TMP/paper_$rule/traj.h5")
    done
  done
  echo "Paper-scale neutral run (--preset paper: N = 50016, t = 1000, seed 1, 2 threads), end to"
  echo "end, the fastest of $REPEATS interleaved repeats"
  echo
  echo "| time step | steps | wall s (fastest) | range | speed-up |"
  echo "|---|---|---|---|---|"
  # shellcheck disable=SC2086
  fixed=$(mins ${PW[auto]})
  for rule in auto adaptive; do
    # shellcheck disable=SC2086
    best=$(mins ${PW[$rule]})
    # shellcheck disable=SC2086
    printf '| %s | %s | %.1f | %s | %.2f |\n' "$rule" "${PS[$rule]}" "$best" \
      "$(range ${PW[$rule]})" "$(calc "$fixed / $best")"
  done
  echo
fi

if [ "${BANDWIDTH:-0}" = 1 ]; then
  echo "Memory bandwidth, one thread (STREAM add, scripts/bandwidth.py):"
  echo
  /usr/bin/python3 scripts/bandwidth.py
  echo
fi

echo "Load at end: $(cut -d' ' -f1-3 /proc/loadavg)"
