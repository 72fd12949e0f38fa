# shellcheck shell=bash
# Helpers shared by the benchmark scripts (bench_md_lammps.sh, bench_coulomb_lammps.sh,
# bench_lammps_engine.sh). Source it after `set -euo pipefail` and `cd` to the repository root:
#
#     . scripts/bench_common.sh
#
# It defines functions only, plus LMP (the plain `lmp` binary) once bench_need_lmp has run.
# Performance is measured by these scripts, never in tests.

calc() {  # awk expression -> its value, 10 significant digits
  awk "BEGIN {printf \"%.10g\", $1}"
}
now() {  # wall clock, seconds
  date +%s.%N
}
mins() {  # numbers... -> the smallest
  printf '%s\n' "$@" | sort -g | head -n 1
}
range() {  # rates... -> "min-max"
  printf '%s\n' "$@" | sort -g | awk '{a[NR] = $1} END {printf "%.3g-%.3g", a[1], a[NR]}'
}
load1() {  # the 1-minute load average
  cut -d' ' -f1 /proc/loadavg
}

bench_machine() {  # -> one line: cores, CPU model, memory
  echo "$(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs)," \
    "$(free -g | awk '/Mem:/ {print $2}') GiB"
}

bench_need_lmp() {  # NAME -> sets LMP to Debian's plain `lmp`, installing package lammps if absent
  if ! command -v lmp >/dev/null 2>&1; then
    echo "$1: installing Debian's lammps" >&2
    local sudo=""
    [ "$(id -u)" -eq 0 ] || sudo=sudo
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y lammps >/dev/null \
      || { $sudo apt-get update >/dev/null \
           && DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y lammps >/dev/null; }
  fi
  LMP=$(command -v lmp)
}

bench_lmp_version() {  # -> "29 Sep 2021 - Update 2 (Debian 20210929...)"
  echo "$("$LMP" -h | grep -m1 'Large-scale' | sed 's/.*Simulator - //')" \
    "(Debian $(dpkg-query -W -f='${Version}' lammps 2>/dev/null || echo '?'))"
}

lmp_launch() {  # ranks -> the launcher words, one per line (none for 1 rank: a serial run)
  if [ "$1" -gt 1 ]; then
    printf '%s\n' mpirun -np "$1" --bind-to core
    [ "$(id -u)" -ne 0 ] || echo --allow-run-as-root
    # more ranks than cores: Open MPI refuses unless told
    [ "$1" -le "$(nproc)" ] || echo --oversubscribe
  fi
}

lmp_run() {  # DIR RANKS LOG INPUT [lmp words...] -> runs Debian's `lmp` on INPUT in DIR on RANKS
  # MPI ranks (one OpenMP thread each), its screen output in DIR/LOG; on failure prints it, exits
  local dir=$1 np=$2 log=$3 input=$4 launch
  shift 4
  mapfile -t launch < <(lmp_launch "$np")
  (cd "$dir" && OMP_NUM_THREADS=1 "${launch[@]}" "$LMP" -in "$input" -log none -nocite -echo none \
     "$@" > "$log" 2>&1) || { cat "$dir/$log" >&2; exit 1; }
}

granagg_model_toml() {  # N PHI STATE_CSV E D DT SKIN -> the [system] .. [charging] part of a
  # `granagg md` configuration from a state file: Hertz contacts, a fixed time step and skin,
  # charges fixed (`[charging]` is last, so that a caller can add keys to it)
  cat <<EOF
[system]
N = $1
phi = $2
initial = "$3"
[contact]
model = "hertz"
E = $4
D = $5
clamp = true
[integrator]
dt = $6
[neighbor]
skin = $7
[charging]
mode = "fixed"
EOF
}

granagg_timing_toml() {  # T_END -> the [run] and [output] part of a timed `granagg md` run
  printf '[run]\nt_end = %s\n' "$1"
  granagg_output_toml
}

granagg_output_toml() {  # -> the [output] part of a timed `granagg md` run: no frames, no
  # checkpoints, observables only at the end
  cat <<EOF
[output]
frames_per_decade = 0
frame_interval = 0.0
observable_interval = 1000000
checkpoint_interval = 0
checkpoint_wall_seconds = 0.0
write_velocities = false
EOF
}

granagg_loop_seconds() {  # PROFILE_CSV STEPS -> loop_s of `granagg md --profile` (checks steps)
  /usr/bin/python3 - "$PWD/scripts" "$1" "$2" <<'PY'
import sys
sys.path.insert(0, sys.argv[1])
import granagg_tables as gt
r = gt.read(sys.argv[2])
if r is None or int(r["steps"][0]) != int(sys.argv[3]):
    sys.exit(f"granagg did not run {sys.argv[3]} steps ({sys.argv[2]})")
print(repr(float(r["loop_s"][0])))
PY
}

lammps_loop_seconds() {  # LOG FIRST -> sum of the "Loop time" of every run in LOG with steps,
  # from the FIRST-th such run on (1-based; LAMMPS prints one line per `run`)
  awk -v first="$2" '/^Loop time of/ && $9 > 0 {if (++k >= first) s += $4}
                     END {if (k < first) exit 1; printf "%.9g\n", s}' "$1"
}

lammps_last_run() {  # LOG -> LOG's lines from its last "Loop time" on (the last run's summary)
  awk '/^Loop time/ {buf = ""} {buf = buf $0 "\n"} END {printf "%s", buf}' "$1"
}
lammps_time_split() {  # LOG -> "Pair 60.1%, Kspace 30.2%, ..." of the last run in LOG (its
  # timing breakdown: a run with `post yes`)
  lammps_last_run "$1" \
    | awk '/^Section/ {s = 1; next} s && /^---/ {next}
           s && /\|/ {gsub(/ /, ""); split($0, a, "|"); printf "%s %s%%, ", a[1], a[6]; next}
           {s = 0}' | sed 's/, $//'
}
