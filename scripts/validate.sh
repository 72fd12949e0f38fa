#!/usr/bin/env bash
# The validation study (issue 14, docs/validation.md): does granagg reproduce Singh & Mazza 2018?
# Runs paired MD / mean-field studies with `granagg pair` (each resumable: run the same command
# again and finished runs are not redone), re-analyses them with other cluster definitions, fits
# z and beta over several windows, and collects tables and figures into OUT/report/.
#
#   usage: bash scripts/validate.sh [--out DIR] [PART ...]
#     DIR   default results/validate (reused: that is how the study resumes)
#     PART  any of the parts below, in the order given; default: all but charged5paper (about 5 h
#           on 2 cores: run it by name), in this order
#
# part       what                                                         cost on 2 cores (measured)
# neutral    K = 0, N = 50016, 20 runs to t = 1000 (data/pair/validate-neutral.toml)   ~30 min
# charged5   K = 5, N = 1e4, Q = 0.05, 5 runs to t = 150 (validate-charged.toml)       ~9 min
# box        K = 0, N = 400128 (L = 140), 1 run to t = 1000 (validate-box.toml)      ~45 min
# box3000    K = 0, N = 400128 (L = 140) to t = 3000 on the adaptive time step: 2 runs with new
#            seeds (102-103), frames every 50 (else as box): the large box past the paper's time
#            (issue 30); also issue 29's L = 140 benchmark (the md log times each run)
# charged1   K = 1, as charged5                                                        ~7 min
# charged025 K = 0.25, as charged5                                                     ~7 min
# qscan      K = 5 with Q = 0.025 and 0.1, 2 runs each to t = 100 (else as charged5)    ~3 min
# charged5big  K = 5 at the paper's N = 50016 (L = 70.1), 5 runs to t = 150 (else as
#            charged5): the size dependence of the onset (issue 15 made it affordable) ~40 min
# charged5paper  K = 5 at the paper's N = 50016 to the paper's t = 1000: 5 runs with new seeds
#            (100-104), frames every 50 (else as charged5); the verdict's charged ensemble at the
#            paper's size and time (issue 30)                                   ~1 h per run
# fits       z and beta (fit-beta) over several windows, grid and particle clusters     ~1 min
# sensitivity  grid spacing 1.5 / 2 / 3 d, threshold 3 / 4 / 5 centres per 2 d cell on the
#            neutral and K = 5 ensembles (granagg analyze --no-particle), z over the windows  ~5 min
# report     tables and figures of everything present: OUT/report/ (scripts/validation_report.py)
#
# Parts whose MD is not finished are resumed by running the same command again; `report` works
# on whatever is present and says what is missing. Environment: GRANAGG_BUILD_DIR (default build),
# VALIDATE_JOBS / VALIDATE_THREADS (passed to pair as --jobs / --threads when set).
# The whole script is one brace group ending in exit: bash parses it completely before running
# it, so editing this file while a long study runs cannot change what the running study does.
{
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${GRANAGG_BUILD_DIR:-build}
G="$BUILD_DIR/bin/granagg"
PY=/usr/bin/python3

OUT=results/validate
PARTS=()
while [ $# -gt 0 ]; do
  case "$1" in
    --out) OUT=$2; shift 2 ;;
    -h|--help) sed -n '2,/^set -euo/p' "$0" | grep '^#' | sed -E 's/^# ?//'; exit 0 ;;
    neutral|charged5|box|box3000|charged1|charged025|qscan|charged5big|charged5paper|fits|\
    sensitivity|report)
      PARTS+=("$1"); shift ;;
    *) echo "validate.sh: unknown part or option '$1' (see --help)" >&2; exit 2 ;;
  esac
done
[ ${#PARTS[@]} -gt 0 ] \
  || PARTS=(neutral charged5 box charged1 qscan charged025 charged5big fits sensitivity report)
[ -x "$G" ] || bash scripts/setup.sh
mkdir -p "$OUT"
LOG="$OUT/validate.log"
say() { echo "[$(date -u +%FT%TZ)] $*" | tee -a "$LOG" >&2; }

PAIR_OPTS=(-q)
FAILED_PARTS=()
[ -n "${VALIDATE_JOBS:-}" ] && PAIR_OPTS+=(--jobs "$VALIDATE_JOBS")
[ -n "${VALIDATE_THREADS:-}" ] && PAIR_OPTS+=(--threads "$VALIDATE_THREADS")

# pair NAME ARGS...: one resumable pair study into OUT/NAME, timed into OUT/cost.csv
pair() {
  local name=$1; shift
  local t0; t0=$(date +%s)
  # Tables written by an older granagg (before the onset time and the asymptotic beta existed)
  # are redone: their markers go, the MD runs stay.
  local f
  for f in "$OUT/$name"/analysis/K*/fits.csv; do
    [ -f "$f" ] && ! grep -q onset_time_grid "$f" && rm -f "${f%/fits.csv}.done"
  done
  for f in "$OUT/$name"/fit/K*/fit_beta.json; do
    [ -f "$f" ] && ! grep -q beta_asymptotic "$f" && rm -f "${f%/fit_beta.json}.done"
  done
  say "part $name: granagg pair $* --out $OUT/$name"
  if ! "$G" pair "$@" --out "$OUT/$name" "${PAIR_OPTS[@]}"; then
    # a part whose runs stop (e.g. a Coulomb collapse at a large Q) is a result, not the end of
    # the study: recorded, the other parts still run, and the script exits 1 at the end
    say "part $name: FAILED after $(( $(date +%s) - t0 )) s (see $OUT/$name/pair.log)"
    echo "$name,failed,$(date -u +%FT%TZ)" >> "$OUT/cost.csv"
    FAILED_PARTS+=("$name")
    return 0
  fi
  local dt=$(( $(date +%s) - t0 ))
  say "part $name: done in $dt s (wall time of this call; resumed parts count only what was left)"
  echo "$name,$dt,$(date -u +%FT%TZ)" >> "$OUT/cost.csv"
}

# A pair configuration for the Q scan: validate-charged.toml with charged.Q replaced, 2 runs (seeds
# 1-2, paired with the first two runs of charged5) to t = 100: the quantities Q can move (the onset
# time, the charge, S and its local slope at t = 100) are all there by t = 100, and the scan then
# costs 2 x 2 x ~6.5 min instead of 2 x 3 x 10.
q_config() {
  local q=$1 f="$OUT/config/validate-charged-Q$1.toml"
  mkdir -p "$OUT/config"
  sed -e "s/^Q = 0.05 .*/Q = $q/" \
      -e "s/^name = \"validate-charged\"/name = \"validate-charged-Q$q\"/" \
      -e "s/^runs = 5/runs = 2/" -e "s/run.t_end=150/run.t_end=100/" \
      -e 's/"--fit-window", "50", "150"/"--fit-window", "50", "100"/' \
      -e "s/^window = \[50.0, 150.0\]/window = [50.0, 100.0]/" \
      data/pair/validate-charged.toml > "$f"
  grep -q "^Q = $q\$" "$f" && grep -q "^runs = 2" "$f" && grep -q "run.t_end=100" "$f" \
    && grep -q '"50", "100"' "$f" && grep -q "^window = \[50.0, 100.0\]" "$f" \
    || { echo "validate.sh: could not set Q, runs or t_end in $f" >&2; exit 1; }
  echo "$f"
}

# The K = 5 study at the paper's N: validate-charged.toml with N = 50016 (same seeds, Q, t_end).
big_config() {
  local f="$OUT/config/validate-charged-N50016.toml"
  mkdir -p "$OUT/config"
  sed -e "s/system.N=10000/system.N=50016/" \
      -e "s/^name = \"validate-charged\"/name = \"validate-charged-N50016\"/" \
      data/pair/validate-charged.toml > "$f"
  grep -q "system.N=50016" "$f" && grep -q '^name = "validate-charged-N50016"' "$f" \
    || { echo "validate.sh: could not set N in $f" >&2; exit 1; }
  echo "$f"
}

# The neutral gas in the large box to t = 3000: validate-box.toml with 2 runs, seeds 102-103,
# t_end 3000 on the adaptive time step, the fit windows to 3000.
box3000_config() {
  local f="$OUT/config/validate-box-t3000.toml"
  mkdir -p "$OUT/config"
  local more='"run.t_end=3000", "integrator.dt=adaptive"'
  sed -e "s/\"output.frame_interval=50\"]/\"output.frame_interval=50\", $more]/" \
      -e "s/^name = \"validate-box\"/name = \"validate-box-t3000\"/" \
      -e "s/^runs = 1 .*/runs = 2/" -e "s/^seed = 101 .*/seed = 102/" \
      -e 's/"--fit-window", "100", "1000"/"--fit-window", "100", "3000"/' \
      -e "s/^window = \[100.0, 1000.0\]/window = [100.0, 3000.0]/" \
      data/pair/validate-box.toml > "$f"
  grep -q "run.t_end=3000" "$f" && grep -q "integrator.dt=adaptive" "$f" \
    && grep -q "^runs = 2" "$f" \
    && grep -q "^seed = 102" "$f" && grep -q '"100", "3000"' "$f" \
    && grep -q "^window = \[100.0, 3000.0\]" "$f" \
    || { echo "validate.sh: could not write $f" >&2; exit 1; }
  echo "$f"
}

# The charged gas at the paper's size and time: validate-charged.toml with N = 50016, t = 1000,
# frames every 50, seeds 100-104 (none shared with the other ensembles), the fit windows to 1000.
paper_config() {
  local f="$OUT/config/validate-charged-N50016-t1000.toml"
  mkdir -p "$OUT/config"
  sed -e "s/system.N=10000/system.N=50016/" -e "s/run.t_end=150/run.t_end=1000/" \
      -e "s/^name = \"validate-charged\"/name = \"validate-charged-N50016-t1000\"/" \
      -e "s/^seed = 1 .*/seed = 100/" \
      -e 's/"--fit-window", "50", "150"/"--fit-window", "100", "1000"/' \
      -e "s/^window = \[50.0, 150.0\]/window = [100.0, 1000.0]/" \
      data/pair/validate-charged.toml > "$f"
  grep -q "system.N=50016" "$f" && grep -q "run.t_end=1000" "$f" && grep -q "^seed = 100" "$f" \
    && grep -q '"100", "1000"' "$f" && grep -q "^window = \[100.0, 1000.0\]" "$f" \
    || { echo "validate.sh: could not write $f" >&2; exit 1; }
  echo "$f"
}

# sensitivity NAME WINDOW0 WINDOW1: grid-cluster variants of the ensemble OUT/NAME
sensitivity() {
  local name=$1 w0=$2 w1=$3 dir="$OUT/sensitivity/$1"
  # only a finished study (its analysis exists): a running one holds its trajectories open
  compgen -G "$OUT/$name/analysis/K*/S_t.csv" > /dev/null \
    || { say "sensitivity: $OUT/$name has no finished analysis yet, skipped"; return 0; }
  mkdir -p "$dir"
  local variant spacing fill
  # The threshold is an integer count of centres per cell: filling 0.25 is 4 centres in the 2.003 d
  # cells of L = 70 but 5 in the 2.05 d cells of L = 41 (N = 1e4), and 0.2 gives the same count as
  # 0.25 at L = 70; so the threshold scan is by count (3, 4, 5 centres) beside the default.
  for variant in "1.5 fill0.25" "2 fill0.25" "3 fill0.25" "2 count3" "2 count4" "2 count5"; do
    read -r spacing thr <<< "$variant"
    local v="grid${spacing}_${thr}" opt
    case "$thr" in
      fill*) opt=(--grid-min-fill "${thr#fill}") ;;
      count*) opt=(--grid-min-count "${thr#count}") ;;
    esac
    if [ ! -f "$dir/$v/S_t.csv" ]; then
      say "sensitivity $name $v: granagg analyze --grid-spacing $spacing ${opt[*]}"
      rm -rf "$dir/$v"
      "$G" analyze "$OUT/$name"/runs/K*/run* --no-particle --grid-spacing "$spacing" "${opt[@]}" \
        --fit-window "$w0" "$w1" --msd-origins t0 -q --out "$dir/$v"
    fi
    if [ ! -f "$dir/$v/fit/fit_beta.json" ]; then
      "$G" fit-beta "$dir/$v" --window "$w0" "$w1" --no-curve-fit -q --out "$dir/$v/fit"
    fi
  done
}

# fits NAME COLUMN "T0 T1" ...: fit-beta (z, beta from z, asymptotic beta) over several windows
fits() {
  local name=$1 column=$2; shift 2
  local w
  for w in "$@"; do
    local w0 w1; read -r w0 w1 <<< "$w"
    local dir="$OUT/$name/windows/${column}_${w0}_${w1}"
    compgen -G "$OUT/$name/analysis/K*/S_t.csv" > /dev/null \
      || { say "fits: $OUT/$name has no finished analysis yet, skipped"; return 0; }
    [ -f "$dir/fit_beta.json" ] && grep -q beta_asymptotic "$dir/fit_beta.json" && continue
    local a; for a in "$OUT/$name"/analysis/K*; do
      [ -f "$a/S_t.csv" ] || continue
      "$G" fit-beta "$a" --column "$column" --window "$w0" "$w1" --no-curve-fit -q --force \
        --out "$dir" \
        || say "fits: $name $column [$w0, $w1]: fit-beta refused (see above)"
    done
  done
}

for part in "${PARTS[@]}"; do
  case "$part" in
    neutral)    pair neutral --preset validate-neutral ;;
    charged5)   pair charged-K5 --preset validate-charged --K 5 ;;
    box)        pair box --preset validate-box ;;
    box3000)    pair box-t3000 --config "$(box3000_config)" ;;
    charged1)   pair charged-K1 --preset validate-charged --K 1 ;;
    charged025) pair charged-K0.25 --preset validate-charged --K 0.25 ;;
    qscan)      pair charged-K5-Q0.025 --config "$(q_config 0.025)" --K 5
                pair charged-K5-Q0.1 --config "$(q_config 0.1)" --K 5 ;;
    charged5big) pair charged-K5-N50016 --config "$(big_config)" --K 5 ;;
    charged5paper) pair charged-K5-N50016-t1000 --config "$(paper_config)" --K 5 ;;
    fits)       fits neutral S_grid_mean "100 1000" "300 1000" "631 1000"
                fits box S_grid_mean "100 1000" "631 1000"
                for c in charged-K5 charged-K1 charged-K0.25 charged-K5-N50016; do
                  fits "$c" S_grid_mean "10 150" "50 150" "80 150"
                  fits "$c" S_particle_mean "10 150" "50 150" "80 150"
                done
                # the Q scan ends at t = 100: its windows, and Q = 0.05's over the same
                for c in charged-K5 charged-K5-Q0.025 charged-K5-Q0.1; do
                  fits "$c" S_grid_mean "10 100" "50 100"
                  fits "$c" S_particle_mean "10 100" "50 100"
                done ;;
    sensitivity) sensitivity neutral 100 1000
                 sensitivity charged-K5 50 150 ;;
    report)     say "report: $PY scripts/validation_report.py $OUT"
                "$PY" scripts/validation_report.py "$OUT" ;;
  esac
done
if [ ${#FAILED_PARTS[@]} -gt 0 ]; then
  say "validate.sh: parts ${PARTS[*]} done; FAILED: ${FAILED_PARTS[*]} (rerun to retry their runs)"
  exit 1
fi
say "validate.sh: parts ${PARTS[*]} finished; report in $OUT/report/"
exit
}
