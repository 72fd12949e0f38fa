#!/usr/bin/env bash
# Time per MD step of granagg's PPPM against its plain Ewald sum at equal accuracy (issue 4,
# "Performance": the crossover and the scaling N log N against N^1.5, with a plot).
#
# The gas: phi = 0.076, fixed +-1 charges (bipolar, zero net), K = 5, coulomb.accuracy = ACC
# (default 1e-4), the clamped Hertz contact of the paper, dt = 0.002, skin 0.3, granagg's own
# random initial state (seed 1). Both methods choose their parameters for the accuracy
# (docs/coulomb.md): PPPM its cutoff, mesh and order by its cost model; plain Ewald (`--set
# coulomb.method=ewald`, EwaldReference) alpha for r_cut = L/2 and the smallest k_max. Plain Ewald
# here is the reference implementation: its real space visits every pair within r_cut <= L/2, i.e.
# O(N^2), and it runs on the host; an optimally tuned Ewald (alpha, r_cut and k_max balanced, cell
# lists) would scale as N^1.5 -- the plot draws that as a dashed guide, it is not measured.
#
# Time per step: difference of the wall times of two whole `granagg md` runs of n1 and n2 steps
# (start-up, parameter choice, FFT plans and the initial force evaluation cancel), divided by
# n2 - n1; the smallest of REPEATS runs. The per-step time includes the contact part (a few 1e-7 s
# per particle, negligible against the Coulomb part at every N measured).
#
#   usage: bash scripts/bench_ewald_pppm.sh [GRANAGG_BINARY]     (default build/bin/granagg)
#   environment: EWALD_SIZES="100 250 500 1000 1414 2000 2828 4000 5657 8000"
#                PPPM_SIZES="100 250 500 1000 2000 4000 10000 20000 50000 100000"
#                THREADS=1  ACC=1e-4  K=5  REPEATS=2
#                EWALD_MAX_STEP_S=6 (stop the Ewald series once a step took longer than this)
#                CSV=docs/img/ewald_pppm.csv  PNG=docs/img/ewald_pppm.png  (PNG= "" skips the plot)
#
# Writes the CSV (method,N,L,threads,alpha,r_cut,mesh_or_kmax,order,n1,n2,seconds_per_step,
# range_low,range_high) and calls scripts/plot_ewald_pppm.py, which fits power laws, finds the
# crossover and draws the log-log plot; its summary is printed at the end.
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
G=$(realpath "${1:-build/bin/granagg}")
[ -x "$G" ] || { echo "bench_ewald_pppm: no granagg binary at $G (build it first)" >&2; exit 1; }
EWALD_SIZES=${EWALD_SIZES-"100 250 500 1000 1414 2000 2828 4000 5657 8000"}
PPPM_SIZES=${PPPM_SIZES-"100 250 500 1000 2000 4000 10000 20000 50000 100000"}
THREADS=${THREADS:-1}
ACC=${ACC:-1e-4}
K=${K:-5}
REPEATS=${REPEATS:-2}
EWALD_MAX_STEP_S=${EWALD_MAX_STEP_S:-6}
CSV=${CSV:-docs/img/ewald_pppm.csv}
PNG=${PNG-docs/img/ewald_pppm.png}
DT=0.002; PHI=0.076
. scripts/bench_common.sh   # calc, now, granagg_output_toml
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT

cat > "$TMP/base.toml" <<EOF
[system]
phi = $PHI
seed = 1
[contact]
model = "hertz"
E = 278.6
D = 27.7
clamp = true
[integrator]
dt = $DT
[neighbor]
skin = 0.3
[charging]
mode = "fixed"
initial = "bipolar"
[coulomb]
K = $K
accuracy = $ACC
EOF
granagg_output_toml >> "$TMP/base.toml"

run_time() {  # method N steps -> wall seconds of the whole process; the set-up into $TMP/coul
  local t0 t1
  t0=$(now)
  OMP_NUM_THREADS=$THREADS "$G" md --config "$TMP/base.toml" --set system.N="$2" \
    --set coulomb.method="$1" --set run.t_end="$(calc "$3 * $DT")" --threads "$THREADS" \
    --out "$TMP/out" --force --profile \
    > "$TMP/log" 2>&1 || { cat "$TMP/log" >&2; exit 1; }
  t1=$(now)
  # steps, box and the Coulomb parameters from profile.csv (machine-readable; the log is for
  # people): "L alpha r_cut mesh-or-k_max order" into $TMP/coul
  /usr/bin/python3 - "$ROOT/scripts" "$TMP/out/profile.csv" "$3" > "$TMP/coul" <<'PY' \
    || { cat "$TMP/log" >&2; exit 1; }
import sys
sys.path.insert(0, sys.argv[1])
import granagg_tables as gt
r, m = gt.read(sys.argv[2]), gt.meta(sys.argv[2])
if r is None or int(r["steps"][0]) != int(sys.argv[3]):
    sys.exit(f"granagg did not run {sys.argv[3]} steps ({sys.argv[2]})")
pppm = m["coulomb_method"] == "pppm"
print(m["box_L"], m["coulomb_alpha"], m["coulomb_r_cut"],
      m["coulomb_mesh"] if pppm else m["coulomb_k_max"], m.get("coulomb_order", ""))
PY
  calc "$t1 - $t0"
}
steps_for() {  # method N -> "n1 n2": about 1-2 s of timed work where affordable
  if [ "$1" = ewald ]; then
    if [ "$2" -le 250 ]; then echo "10 210"
    elif [ "$2" -le 1000 ]; then echo "2 12"
    elif [ "$2" -le 2828 ]; then echo "1 5"
    else echo "1 3"; fi
  else
    if [ "$2" -le 2000 ]; then echo "20 220"
    elif [ "$2" -le 20000 ]; then echo "10 60"
    else echo "3 13"; fi
  fi
}

mkdir -p "$(dirname "$CSV")"
echo "method,N,L,threads,alpha,r_cut,mesh_or_kmax,order,n1,n2,seconds_per_step,range_low,\
range_high" > "$CSV"
echo "Machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs);" \
  "granagg $("$G" --version 2>&1 | head -n 1); $THREADS thread(s);" \
  "load at start $(cut -d' ' -f1-3 /proc/loadavg)"
echo
echo "| method | N | parameters (granagg's choice for accuracy $ACC) | steps timed | s per step |" \
  "range over $REPEATS repeats |"
echo "|---|---|---|---|---|---|"
for method in pppm ewald; do
  sizes=$PPPM_SIZES; [ "$method" = pppm ] || sizes=$EWALD_SIZES
  for N in $sizes; do
    read -r n1 n2 <<< "$(steps_for "$method" "$N")"
    per=()
    for rep in $(seq "$REPEATS"); do
      ta=$(run_time "$method" "$N" "$n1"); tb=$(run_time "$method" "$N" "$n2")
      per+=("$(calc "($tb - $ta) / ($n2 - $n1)")")
    done
    best=$(printf '%s\n' "${per[@]}" | sort -g | head -n 1)
    worst=$(printf '%s\n' "${per[@]}" | sort -g | tail -n 1)
    read -r L alpha rc mk order < "$TMP/coul"
    if [ "$method" = pppm ]; then
      coul="pppm: alpha = $alpha, r_cut = $rc, mesh $mk^3, order $order"
    else
      coul="ewald: alpha = $alpha, r_cut = $rc, k_max $mk"
    fi
    echo "$method,$N,$L,$THREADS,$alpha,$rc,$mk,$order,$n1,$n2,$best,$best,$worst" >> "$CSV"
    printf '| %s | %s | %s | %s..%s | %.4g | %.3g-%.3g |\n' "$method" "$N" "$coul" "$n1" "$n2" \
      "$best" "$best" "$worst"
    echo "  $method N = $N: $best s/step (load $(cut -d' ' -f1 /proc/loadavg))" >&2
    if [ "$method" = ewald ] && awk "BEGIN {exit !($best > $EWALD_MAX_STEP_S)}"; then
      echo "  plain Ewald took $best s per step at N = $N: stopping the series" \
        "(EWALD_MAX_STEP_S = $EWALD_MAX_STEP_S)" >&2
      break
    fi
  done
done
echo
echo "Load at end: $(cut -d' ' -f1-3 /proc/loadavg)"
echo
if [ -n "$PNG" ]; then
  /usr/bin/python3 "$ROOT/scripts/plot_ewald_pppm.py" "$CSV" "$PNG"
fi
