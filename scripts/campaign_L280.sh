#!/usr/bin/env bash
# The neutral gas in the box of L = 280 (issue 45, part 2): the paper preset (Hertz contacts,
# phi = 0.076) with N = 3201024 (L = 280.4, 64x the paper's volume), on the adaptive time step, to
# t = 3000, two runs with distinct seeds (SEEDS). Resumable: run it again and each run continues
# from its checkpoint (every 10 minutes of wall time), so the campaign spans sessions; a run at
# its t_end is skipped. The wall time of each leg is appended to DIR/legs.csv.
#
#   usage: bash scripts/campaign_L280.sh [DIR]        (default results/campaign-L280)
#   environment: GRANAGG_BIN (default build/bin/granagg), THREADS (2), T_END (3000),
#                SEEDS ("201 202"), NICE (19: the campaign yields the cores to builds and tests),
#                TRAJECTORY (true: also store the particle frames)
# Each run is analysed while it runs (`granagg md --analyze`: RUN/analysis at the end, the tables
# of `granagg analyze RUN`). With TRAJECTORY=true it also stores its frames with velocities
# (log-spaced, 10 frames per decade: about 57 frames of 0.2 GB), from which a later analysis can
# be redone and a lost analysis state rebuilt.
#
# SIGTERM or SIGINT stops the run in progress with a checkpoint (granagg md's own handling);
# the next call continues it. docs/validation.md ("The box of L = 280") records the outcome.
{
set -euo pipefail
cd "$(dirname "$0")/.."
DIR=${1:-results/campaign-L280}
BIN=${GRANAGG_BIN:-build/bin/granagg}
THREADS=${THREADS:-2}
T_END=${T_END:-3000}
SEEDS=${SEEDS:-201 202}
NICE=${NICE:-19}
TRAJECTORY=${TRAJECTORY:-true}
N=3201024
mkdir -p "$DIR"
LEGS="$DIR/legs.csv"
[ -f "$LEGS" ] || echo "seed,leg,start_utc,end_utc,wall_s,t_start,t_end,status,granagg" > "$LEGS"

stop=0
child=0
trap 'stop=1; [ "$child" -gt 0 ] && kill -TERM "$child" 2>/dev/null || true' TERM INT

checkpoint_time() {
  /usr/bin/python3 -c \
    "import h5py,sys; print(float(h5py.File(sys.argv[1],'r')['state'].attrs['time']))" \
    "$1/checkpoint.h5" 2>/dev/null || echo nan
}

for seed in $SEEDS; do
  [ "$stop" = 1 ] && break
  run="$DIR/seed$seed"
  t_start=0
  if [ -f "$run/checkpoint.h5" ]; then
    t_start=$(checkpoint_time "$run")
    if /usr/bin/python3 -c "import sys; sys.exit(0 if float(sys.argv[1]) >= float(sys.argv[2]) \
        - 1e-9 else 1)" "$t_start" "$T_END"; then
      continue  # this run is at its t_end
    fi
    cmd=("$BIN" md --restart "$run" --set run.t_end="$T_END" --threads "$THREADS")
  else
    cmd=("$BIN" md --preset paper --set system.N=$N --set run.t_end="$T_END"
         --set integrator.dt=adaptive --seed "$seed" --threads "$THREADS"
         --analyze --set output.trajectory="$TRAJECTORY" --out "$run")
  fi
  leg=$(grep -c "^$seed," "$LEGS" || true)
  start=$(date -u +%FT%TZ); s0=$(date +%s.%N)
  echo "[$start] seed $seed leg $leg: ${cmd[*]}" >> "$DIR/campaign.log"
  set +e
  OMP_NUM_THREADS=$THREADS nice -n "$NICE" "${cmd[@]}" >> "$run.log" 2>&1 &
  child=$!
  wait "$child"
  rc=$?
  # a trapped signal interrupts wait: wait again for the checkpoint to be written
  while kill -0 "$child" 2>/dev/null; do wait "$child"; rc=$?; done
  child=0
  set -e
  s1=$(date +%s.%N)
  echo "$seed,$leg,$start,$(date -u +%FT%TZ),$(echo "$s1 - $s0" | bc),$t_start,$(
    checkpoint_time "$run"),$rc,$("$BIN" --version | head -n 1 | tr ',' ' ')" >> "$LEGS"
  [ "$rc" = 0 ] || { [ "$stop" = 1 ] && break; echo "seed $seed: exit $rc" >&2; exit "$rc"; }
done
}
