#!/usr/bin/env bash
# Charged-gas MD throughput of granagg against LAMMPS (issue 4, "Performance"): the viscoelastic
# Hertz gas of scripts/bench_md_lammps.sh (phi = 0.076, E = 278.6, D = 27.7, clamped, d = m = 1,
# T = 1) with fixed +-1 charges (bipolar: a random half +1, the other half -1, zero net charge) and
# the long-range Coulomb force K q_i q_j / r^2, K = 5, Ewald-split at relative accuracy 1e-4 (RMS
# force error over K, the force between two unit charges at distance 1). Same initial state, same
# fixed time step, same skin for both codes, run in one go on this machine. Prints Markdown tables
# for docs/benchmarks-coulomb.md: the two-charge check of the Coulomb prefactor, LAMMPS's measured
# force accuracy, then N, code, cutoff, cores (granagg OpenMP threads, LAMMPS MPI ranks),
# particle-steps/s and the ratio granagg / LAMMPS on the same number of cores.
#
#   usage: bash scripts/bench_coulomb_lammps.sh [GRANAGG_BINARY]      (default build/bin/granagg)
#   environment: SIZES="10000 100000"  STEPS_10000="24 120"  STEPS_100000="8 48"  DT=0.002
#                REPEATS=2  THREADS="1 2"  LMP_RANKS="1 2"  K=5  ACC=1e-4
#                RC_ISSUE=8 (the issue's LAMMPS cutoff)  RC_SCAN="3 4 5 6" (LAMMPS cutoffs tried on
#                one rank; the fastest is then also run on every rank count)
#                STATE_DIR=dir (keep the generated initial states there and reuse them)
#                EVERY_ALSO="1" (also time granagg with coulomb.every = 1: the total force at every
#                step, as LAMMPS integrates; the default rows use granagg's default multiple time
#                stepping, coulomb.every = 8, whose accuracy the tests check)
#                LMP_RESPA="8" (also time LAMMPS's own multiple time stepping, run_style respa
#                2 k with the contacts every step and coul/long + pppm every k steps, for each k
#                listed, at each cutoff and rank count; "" skips it)
#                LMP_ACC (default ACC*K, see below)  ISSUE_LITERAL=1 (also time the issue's literal
#                `kspace_style pppm 1e-4` at cutoff 8 on one rank)  SKIP_CHECKS=1
#
# LAMMPS set-up (scripts/lammps/charged.in): units lj, d = 1, density 6/pi (mass 1), atom_style
# hybrid sphere charge, pair_style hybrid/overlay gran/hertz/history (kn = 2E, gamma_n = 4D,
# limit_damping; mapping checked by scripts/bench_md_lammps.sh) + coul/long RC, kspace_style pppm
# (ik differentiation, order 5, LAMMPS chooses G and the grid), dielectric 1/K, so that
# F = qqrd2e q_i q_j / (dielectric r^2) = K q_i q_j / r^2 (qqrd2e = 1 in lj units; checked below
# with two static charges).
#
# Accuracy: LAMMPS's kspace accuracy is relative to two_charge_force = qqr2e qe^2/A^2 = 1 in lj
# units, which ignores the dielectric, while its error estimates use q^2 qqrd2e = K q^2: the
# LAMMPS number is an absolute force error. granagg's coulomb.accuracy is relative to K. Equal
# accuracy therefore means LMP_ACC = ACC * K (5e-4); `pppm 1e-4` in LAMMPS would be 5x stricter
# than granagg's 1e-4. (LAMMPS holds real and k space each at LMP_ACC, granagg each at ACC/sqrt 2.)
# The script measures LAMMPS's actual RMS Coulomb force error against a converged Ewald sum
# (LAMMPS ewald 1e-10) on the N = 1000 state to show where each setting lands.
#
# Timing as in bench_md_lammps.sh: two lengths n1 < n2 from the same state; granagg: difference of
# the wall times of two whole processes (start-up, PPPM set-up, input and output cancel); LAMMPS:
# "Loop time" of `run n2-n1` after `run n1`. Each time is the smallest of REPEATS runs.
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
G=$(realpath "${1:-build/bin/granagg}")
[ -x "$G" ] \
  || { echo "bench_coulomb_lammps: no granagg binary at $G (build it first)" >&2; exit 1; }
SIZES=${SIZES-"10000 100000"}
DT=${DT:-0.002}
REPEATS=${REPEATS:-2}
THREADS=${THREADS:-"1 2"}
LMP_RANKS=${LMP_RANKS:-"1 2"}
K=${K:-5}
ACC=${ACC:-1e-4}
RC_ISSUE=${RC_ISSUE:-8}
RC_SCAN=${RC_SCAN-"3 4 5 6"}
LMP_RESPA=${LMP_RESPA-8}
EVERY_ALSO=${EVERY_ALSO-1}  # also time granagg with these coulomb.every values (default: 1)
E=278.6; D=27.7; PHI=0.076; SKIN=0.3
. scripts/bench_common.sh
KN=$(calc "2 * $E"); GN=$(calc "4 * $D")
LMP_ACC=${LMP_ACC:-$(calc "$ACC * $K")}

bench_need_lmp bench_coulomb_lammps
command -v mpirun >/dev/null 2>&1 || LMP_RANKS=1

TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT

steps_for() {  # N -> "n1 n2"
  local var="STEPS_$1"
  if [ -n "${!var:-}" ]; then echo "${!var}"
  elif [ "$1" -le 20000 ]; then echo "24 120"
  else echo "8 48"; fi  # windows of whole multiples of coulomb.every = 8
}

echo "Machine: $(bench_machine)"
echo "granagg: $("$G" --version 2>&1 | head -n 1); $G"
echo "LAMMPS:  $(bench_lmp_version); $LMP"
echo "Load at start: $(cut -d' ' -f1-3 /proc/loadavg)"
echo "Settings: K = $K, granagg coulomb.accuracy = $ACC, LAMMPS kspace accuracy = $LMP_ACC" \
  "(absolute, = ACC K), dt = $DT, skin = $SKIN"
echo

# ---------------------------------------------------------------------------------------------
# Initial states: random sequential insertion, Maxwell velocities at T_g = 1 exactly (as in
# bench_md_lammps.sh), and a random +-1 charge assignment with zero net charge.
gen_state() {  # N -> $TMP/state_N.csv (granagg, with a q column) and $TMP/state_N.data (LAMMPS)
  if [ -n "${STATE_DIR:-}" ] && [ -s "$STATE_DIR/state_$1.csv" ] \
    && [ -s "$STATE_DIR/state_$1.data" ]; then
    cp "$STATE_DIR/state_$1.csv" "$STATE_DIR/state_$1.data" "$TMP/"; return
  fi
  /usr/bin/python3 "$ROOT/scripts/lammps/make_state.py" "$1" "$PHI" "$TMP" --charged
  if [ -n "${STATE_DIR:-}" ]; then
    mkdir -p "$STATE_DIR" && cp "$TMP/state_$1.csv" "$TMP/state_$1.data" "$STATE_DIR/"
  fi
}

# ---------------------------------------------------------------------------------------------
if [ -z "${SKIP_CHECKS:-}" ]; then
  # (1) Coulomb prefactor: two static charges, force on atom 1 against K q1 q2 / r^2, with plain
  # coul/cut in an open box (exact) and with the benchmark's pair/kspace set-up in a periodic box
  # of edge 60 (images change the force by ~1e-4 relative).
  two_charge() {  # q2 r mode(cut|pppm) -> fx on atom 1 (atom 2 at +r along x)
    cat > "$TMP/two.in" <<EOF
units           lj
atom_style      hybrid sphere charge
atom_modify     map array
boundary        $([ "$3" = cut ] && echo "f f f" || echo "p p p")
comm_modify     vel yes
region          box block -30 30 -30 30 -30 30
create_box      1 box
create_atoms    1 single 0 0 0
create_atoms    1 single $2 0 0
set             type 1 diameter 1.0
set             type 1 density \$(6.0/PI)
set             atom 1 charge 1.0
set             atom 2 charge $1
velocity        all set 0 0 0
EOF
    if [ "$3" = cut ]; then
      printf 'pair_style coul/cut 25.0\npair_coeff * *\n' >> "$TMP/two.in"
    else
      printf 'pair_style hybrid/overlay gran/hertz/history %s 0.0 %s 0.0 0.0 0 limit_damping '\
'coul/long %s\npair_coeff * * gran/hertz/history\npair_coeff * * coul/long\n'\
'kspace_style pppm %s\n' \
        "$KN" "$GN" "$RC_ISSUE" "$(calc "$LMP_ACC / 10")" >> "$TMP/two.in"
    fi
    cat >> "$TMP/two.in" <<EOF
dielectric      $(calc "1 / $K")
neighbor        $SKIN bin
fix             1 all nve/sphere
run             0
variable        f equal fx[1]
print           "TWO_CHARGE fx=\$(v_f:%.8f)"
EOF
    (cd "$TMP" && "$LMP" -in two.in -log none -nocite -echo none 2>&1) \
      | sed -n 's/^TWO_CHARGE fx=\(.*\)/\1/p'
  }
  echo "Coulomb prefactor: force on charge +1 at the origin from charge q2 at distance r on the x" \
    "axis (LAMMPS, dielectric 1/K)"
  echo
  echo "| q2 | r | K q1 q2 / r^2 (repulsion > 0) | expected fx on atom 1 |" \
    "LAMMPS coul/cut, open box | LAMMPS coul/long + pppm, periodic L = 60 |"
  echo "|---|---|---|---|---|---|"
  for qr in "-1 2" "1 1.5" "-1 5"; do
    read -r q2 r <<< "$qr"
    f=$(calc "$K * $q2 / ($r * $r)")
    printf '| %s | %s | %.6f | %.6f | %s | %s |\n' "$q2" "$r" "$f" "$(calc "-1 * $f")" \
      "$(two_charge "$q2" "$r" cut)" "$(two_charge "$q2" "$r" pppm)"
  done
  echo

  # (2) LAMMPS's actual Coulomb force error on the N = 1000 state, relative to K (granagg's
  # definition), against LAMMPS ewald 1e-10 as the converged reference.
  gen_state 1000
  lmp_forces() {  # rc kspace-command out -> per-atom Coulomb forces (no contacts in the state)
    cat > "$TMP/acc.in" <<EOF
units           lj
atom_style      hybrid sphere charge
boundary        p p p
read_data       $TMP/state_1000.data
pair_style      coul/long $1
pair_coeff      * *
dielectric      $(calc "1 / $K")
kspace_style    $2
neighbor        $SKIN bin
run             0
write_dump      all custom $3 id fx fy fz modify sort id
EOF
    (cd "$TMP" && "$LMP" -in acc.in -log none -nocite -echo none > acc.log 2>&1) \
      || { cat "$TMP/acc.log" >&2; exit 1; }
    grep -E 'grid =|G vector|estimated (absolute|relative)' "$TMP/acc.log" | sed 's/^ *//' \
      | paste -sd';' -
  }
  rms_err() {  # file -> RMS |F - F_ref| / K
    /usr/bin/python3 - "$1" "$TMP/ref.dump" "$K" <<'EOF'
import math, sys
def read(fn):
    rows = [l.split() for l in open(fn)]
    i = next(k for k, r in enumerate(rows) if r[:2] == ["ITEM:", "ATOMS"])
    return [tuple(map(float, r[1:4])) for r in rows[i + 1:]]
a, b, K = read(sys.argv[1]), read(sys.argv[2]), float(sys.argv[3])
se = sum((x[0] - y[0])**2 + (x[1] - y[1])**2 + (x[2] - y[2])**2 for x, y in zip(a, b)) / len(a)
sf = sum(y[0]**2 + y[1]**2 + y[2]**2 for y in b) / len(b)
print(f"{math.sqrt(se) / K:.2e} {math.sqrt(se / sf):.2e}")
EOF
  }
  lmp_forces 9.0 "ewald 1e-10" "$TMP/ref.dump" > /dev/null
  echo "LAMMPS's Coulomb force error on the N = 1000 state (+-1, phi = $PHI, K = $K) against" \
    "LAMMPS ewald 1e-10: RMS |F - F_ref| / K (granagg's definition of coulomb.accuracy) and /" \
    "RMS force"
  echo
  echo "| kspace_style | cutoff | error / K | error / RMS force | LAMMPS's log |"
  echo "|---|---|---|---|---|"
  for acc in "$LMP_ACC" 1e-4; do
    for rc in "$RC_ISSUE" 5; do
      info=$(lmp_forces "$rc" "pppm $acc" "$TMP/p.dump")
      read -r e1 e2 <<< "$(rms_err "$TMP/p.dump")"
      echo "| pppm $acc | $rc | $e1 | $e2 | $info |"
    done
  done
  echo
fi

# ---------------------------------------------------------------------------------------------
granagg_time() {  # N steps threads [coulomb.every] -> wall seconds of the whole process
  local N=$1 n=$2 th=$3 every=${4:-8}
  { granagg_model_toml "$N" "$PHI" "$TMP/state_$N.csv" "$E" "$D" "$DT" "$SKIN"
    cat <<EOF
initial = "file"
[coulomb]
K = $K
method = "pppm"
accuracy = $ACC
every = $every
EOF
    granagg_timing_toml "$(calc "$n * $DT")"; } > "$TMP/g.toml"
  local t0 t1
  t0=$(now)
  OMP_NUM_THREADS=$th "$G" md --config "$TMP/g.toml" --out "$TMP/gout" --force --threads "$th" \
    --profile > "$TMP/g.log" 2>&1 || { cat "$TMP/g.log" >&2; exit 1; }
  t1=$(now)
  # the step count and the Coulomb set-up from profile.csv (machine-readable; the log is for
  # people): a line for the notes into g_coulomb_N.txt, the run's counts into g_run.txt
  /usr/bin/python3 - "$ROOT/scripts" "$TMP/gout/profile.csv" "$n" "$TMP/g_coulomb_$N.txt" \
    "$TMP/g_run.txt" <<'PY' || { cat "$TMP/g.log" >&2; exit 1; }
import sys
sys.path.insert(0, sys.argv[1])
import granagg_tables as gt
r, m = gt.read(sys.argv[2]), gt.meta(sys.argv[2])
if r is None or int(r["steps"][0]) != int(sys.argv[3]):
    sys.exit(f"granagg did not run {sys.argv[3]} steps ({sys.argv[2]})")
with open(sys.argv[4], "w") as f:
    f.write(f"{m['coulomb_method']}: alpha = {float(m['coulomb_alpha']):.6g}, "
            f"r_cut = {float(m['coulomb_r_cut']):.6g}, mesh {m.get('coulomb_mesh', '?')}^3, "
            f"order {m.get('coulomb_order', '?')}; estimated relative force error "
            f"{float(m['coulomb_estimated_error']):.2g}; slow part every {m['coulomb_every']} "
            f"(at most {m['coulomb_every_max']}), r_fast {m['coulomb_r_fast']}\n")
with open(sys.argv[5], "w") as f:
    f.write(f"{int(r['steps'][0])} steps to t = {float(m['t_end']):.6g} in "
            f"{float(r['loop_s'][0]):.4g} s, {int(r['neighbor_builds'][0])} list builds, "
            f"{int(r['slow_evaluations'][0])} slow Coulomb evaluations\n")
PY
  calc "$t1 - $t0"
}

lammps_time() {  # N n1 n2 ranks rc acc [respa] -> loop seconds of steps n1..n2
  local N=$1 n1=$2 n2=$3 np=$4 rc=$5 acc=$6 respa=${7:-1}
  lmp_run "$TMP" "$np" lmp.log "$ROOT/scripts/lammps/charged.in" \
    -var data "$TMP/state_$N.data" -var rc "$rc" -var acc "$acc" -var K "$K" -var kn "$KN" \
    -var gn "$GN" -var dt "$DT" -var skin "$SKIN" -var n1 "$n1" -var n2 "$n2" -var respa "$respa"
  cp "$TMP/lmp.log" "$TMP/lmp_${N}_${np}_${rc}_${acc}$([ "$respa" = 1 ] || echo "_respa$respa").log"
  grep '^Loop time' "$TMP/lmp.log" | tail -n 1 | awk '{print $4}'
}
lammps_info() {  # log -> "grid, G, estimated accuracy; time split of the timed run"
  local log=$1
  local grid g est brk
  grid=$(grep -m1 'grid =' "$log" | sed 's/.*grid = //')
  g=$(grep -m1 'G vector' "$log" | sed 's/.*= *//')
  est=$(grep -m1 'estimated relative force accuracy' "$log" | sed 's/.*= *//')
  brk=$(lammps_time_split "$log")
  echo "grid $grid, G = $g, LAMMPS-estimated error $est (absolute); $brk"
}

ROWS=()
NOTES=()
for N in $SIZES; do
  read -r n1 n2 <<< "$(steps_for "$N")"
  echo "N = $N: generating the initial state, timing steps $n1..$n2" \
    "($REPEATS repeats; load $(cut -d' ' -f1 /proc/loadavg))" >&2
  gen_state "$N"
  declare -A T=() R=() LR=()
  tl() {  # key ranks rc acc [respa]: one LAMMPS timing appended to T[key], R[key]
    local t
    t=$(lammps_time "$N" "$n1" "$n2" "$2" "$3" "$4" "${5:-1}")
    T[$1]+="$t "; R[$1]+="$(calc "$N * ($n2 - $n1) / $t") "
  }
  # cutoff scan on one rank (one run each), then repeats of the issue's cutoff and the fastest one
  best_rc=$RC_ISSUE
  if [ -n "$RC_SCAN" ]; then
    best_rate=0
    for rc in $RC_SCAN; do
      tl "s$rc" 1 "$rc" "$LMP_ACC"
      r=${R[s$rc]% }
      echo "  LAMMPS cutoff $rc, 1 rank: $r particle-steps/s" >&2
      NOTES+=("- N = $N, LAMMPS cutoff scan (1 rank, pppm $LMP_ACC): cutoff $rc: $(printf '%.3g' \
        "$r") particle-steps/s; $(lammps_info "$TMP/lmp_${N}_1_${rc}_${LMP_ACC}.log")")
      if awk "BEGIN {exit !($r > $best_rate)}"; then best_rate=$r; best_rc=$rc; fi
    done
  fi
  RCS="$RC_ISSUE"; [ "$best_rc" = "$RC_ISSUE" ] || RCS+=" $best_rc"
  for rep in $(seq "$REPEATS"); do
    for rc in $RCS; do
      for np in $LMP_RANKS; do
        tl "l${np}_$rc" "$np" "$rc" "$LMP_ACC"
        for k in $LMP_RESPA; do tl "r${k}_${np}_$rc" "$np" "$rc" "$LMP_ACC" "$k"; done
      done
    done
    if [ -n "${ISSUE_LITERAL:-}" ]; then tl "lit" 1 "$RC_ISSUE" 1e-4; fi
    for th in $THREADS; do
      ta=$(granagg_time "$N" "$n1" "$th"); tb=$(granagg_time "$N" "$n2" "$th")
      T[a$th]+="$ta "; T[b$th]+="$tb "; R[g$th]+="$(calc "$N * ($n2 - $n1) / ($tb - $ta)") "
      for ev in $EVERY_ALSO; do
        ta=$(granagg_time "$N" "$n1" "$th" "$ev"); tb=$(granagg_time "$N" "$n2" "$th" "$ev")
        T[a${th}_$ev]+="$ta "; T[b${th}_$ev]+="$tb "
        R[g${th}_$ev]+="$(calc "$N * ($n2 - $n1) / ($tb - $ta)") "
      done
    done
    echo "  repeat $rep: load $(cut -d' ' -f1 /proc/loadavg); granagg $(for th in $THREADS; do
      printf '%s threads: %s; ' "$th" "${R[g$th]}"; done)" >&2
  done
  for rc in $RCS; do
    which="issue's cutoff"
    [ "$rc" = "$RC_ISSUE" ] || which="tuned cutoff (fastest of $RC_SCAN on 1 rank)"
    for np in $LMP_RANKS; do
      # shellcheck disable=SC2086
      LR[${np}_$rc]=$(calc "$N * ($n2 - $n1) / $(mins ${T[l${np}_$rc]})")
      # shellcheck disable=SC2086
      ROWS+=("| $N | LAMMPS pppm $LMP_ACC, $which | $rc | $np | $(printf '%.3g' \
        "${LR[${np}_$rc]}") | | $(range ${R[l${np}_$rc]}) |")
      NOTES+=("- N = $N, LAMMPS cutoff $rc, $np rank(s): $(lammps_info \
        "$TMP/lmp_${N}_${np}_${rc}_${LMP_ACC}.log")")
      for k in $LMP_RESPA; do
        # shellcheck disable=SC2086
        LR[r${k}_${np}_$rc]=$(calc "$N * ($n2 - $n1) / $(mins ${T[r${k}_${np}_$rc]})")
        # shellcheck disable=SC2086
        ROWS+=("| $N | LAMMPS pppm $LMP_ACC, run_style respa 2 $k (coul/long + pppm every $k \
steps), $which | $rc | $np | $(printf '%.3g' "${LR[r${k}_${np}_$rc]}") | | $(range \
          ${R[r${k}_${np}_$rc]}) |")
        NOTES+=("- N = $N, LAMMPS respa 2 $k, cutoff $rc, $np rank(s): $(lammps_info \
          "$TMP/lmp_${N}_${np}_${rc}_${LMP_ACC}_respa$k.log")")
      done
    done
  done
  if [ -n "${ISSUE_LITERAL:-}" ]; then
    # shellcheck disable=SC2086
    ROWS+=("| $N | LAMMPS literal pppm 1e-4 (5x stricter), issue's cutoff | $RC_ISSUE | 1 | $(
      printf '%.3g' "$(calc "$N * ($n2 - $n1) / $(mins ${T[lit]})")") | | $(range ${R[lit]}) |")
    NOTES+=("- N = $N, LAMMPS literal pppm 1e-4, cutoff $RC_ISSUE, 1 rank: $(lammps_info \
      "$TMP/lmp_${N}_1_${RC_ISSUE}_1e-4.log")")
  fi
  for th in $THREADS; do
    # shellcheck disable=SC2086
    rate=$(calc "$N * ($n2 - $n1) / ($(mins ${T[b$th]}) - $(mins ${T[a$th]}))")
    ratios=""
    for rc in $RCS; do
      [ -z "${LR[${th}_$rc]:-}" ] \
        || ratios+="$(calc "$rate / ${LR[${th}_$rc]}" | xargs printf '%.2f') (cutoff $rc); "
      for k in $LMP_RESPA; do
        [ -z "${LR[r${k}_${th}_$rc]:-}" ] || ratios+="$(calc "$rate / ${LR[r${k}_${th}_$rc]}" \
          | xargs printf '%.2f') (respa $k, cutoff $rc); "
      done
    done
    # shellcheck disable=SC2086
    ROWS+=("| $N | granagg pppm $ACC, own choice, coulomb.every = 8 (default) | $(sed \
      's/.*r_cut = \([0-9.]*\).*/\1/' "$TMP/g_coulomb_$N.txt") | $th | $(printf '%.3g' \
      "$rate") | ${ratios%; } | $(range ${R[g$th]}) |")
  done
  for ev in $EVERY_ALSO; do
    for th in $THREADS; do
      # shellcheck disable=SC2086
      rate=$(calc "$N * ($n2 - $n1) / ($(mins ${T[b${th}_$ev]}) - $(mins ${T[a${th}_$ev]}))")
      ratios=""
      for rc in $RCS; do
        [ -z "${LR[${th}_$rc]:-}" ] \
          || ratios+="$(calc "$rate / ${LR[${th}_$rc]}" | xargs printf '%.2f') (cutoff $rc); "
      done
      # shellcheck disable=SC2086
      ROWS+=("| $N | granagg pppm $ACC, coulomb.every = $ev | $(sed \
        's/.*r_cut = \([0-9.]*\).*/\1/' "$TMP/g_coulomb_$N.txt") | $th | $(printf '%.3g' \
        "$rate") | ${ratios%; } | $(range ${R[g${th}_$ev]}) |")
    done
  done
  NOTES+=("- N = $N, granagg: $(cat "$TMP/g_coulomb_$N.txt")")
  NOTES+=("- N = $N, steps $n1..$n2; granagg's last run: $(cat "$TMP/g_run.txt")")
done

if [ -n "$SIZES" ]; then
  echo "Throughput: phi = $PHI, K = $K, fixed +-1 charges (zero net), dt = $DT, skin $SKIN," \
    "clamped Hertz (E = $E, D = $D), T(0) = 1; rates over steps n1..n2 from the fastest of" \
    "$REPEATS runs of each kind (LAMMPS cutoff scan: one run each)"
  echo
  echo "| N | code, Coulomb set-up | real-space cutoff | cores (threads or ranks) |" \
    "particle-steps/s | granagg / LAMMPS on as many cores | range over repeats |"
  echo "|---|---|---|---|---|---|---|"
  printf '%s\n' "${ROWS[@]}"
  echo
  printf '%s\n' "${NOTES[@]}"
  echo
fi
echo "Load at end: $(cut -d' ' -f1-3 /proc/loadavg)"
