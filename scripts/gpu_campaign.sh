#!/usr/bin/env bash
# The GPU campaign of issue 45 (docs/gpu.md, "The finite-size campaign on a GPU"): one call of at
# most BUDGET seconds (default 540, within a 10-minute device call) on a machine with a GPU and a
# bundle made by `bash scripts/gpu_check.sh --bundle DIR` (or a CUDA build in build-cuda/):
#   1. the charged gas (K = 5, Q = 0.05, the paper preset) at L = 140 (N = 400128) to t = 1000,
#      analysed during the run, no frames stored;
#   2. with the time left, the neutral gas at L = 280 (N = 3201024, adaptive step), analysed
#      during the run, no frames stored, to t = 3000 or as far as the budget goes.
# Each run gets a share of the budget and is stopped by SIGTERM with a checkpoint when it runs
# out; a second call continues both from their checkpoints. Everything lands in OUT (default
# $OUT, else results/gpu-campaign): the run folders (checkpoint.h5, analysis-state.h5, traj.h5
# with the observables, RUN/analysis/ once a run ends), the logs, and legs.csv (one row a leg:
# wall seconds, t reached). The CPU campaign (scripts/campaign_L280.sh) continues a run whose
# folder is copied into its DIR (the engines' checkpoints are the same format).
#   usage: bash scripts/gpu_campaign.sh [--prebuilt BUNDLE] [--dry-run]
#   --dry-run: the same steps on the CPU build at test size (N = 2000, t = 5), for CI.
#   environment: OUT, BUDGET (s, 540), CHARGED_SHARE (fraction of BUDGET for run 1, 0.6)
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${OUT:-results/gpu-campaign}
BUDGET=${BUDGET:-540}
CHARGED_SHARE=${CHARGED_SHARE:-0.6}
BIN=build-cuda/bin/granagg
DRY=0
while [ $# -gt 0 ]; do
  case "$1" in
    --prebuilt) BIN=$(realpath "${2:?--prebuilt needs a bundle}")/bin/granagg
                export LD_LIBRARY_PATH="$(dirname "$BIN")/../lib:${LD_LIBRARY_PATH:-}"; shift 2 ;;
    --dry-run) DRY=1; BIN=${GRANAGG_BIN:-build/bin/granagg}; shift ;;
    *) echo "gpu_campaign: unknown option '$1'" >&2; exit 2 ;;
  esac
done
[ -x "$BIN" ] || { echo "gpu_campaign: no granagg at $BIN" >&2; exit 2; }
mkdir -p "$OUT"
LEGS="$OUT/legs.csv"
[ -f "$LEGS" ] || echo "run,start_utc,wall_s,status,t_reached,granagg" > "$LEGS"
START=$(date +%s)
nvidia-smi > "$OUT/nvidia-smi.txt" 2>&1 || echo "no nvidia-smi" > "$OUT/nvidia-smi.txt"

t_of() {  # the checkpoint's time, or "none"
  /usr/bin/python3 -c "import h5py,sys; print(float(h5py.File(sys.argv[1],'r')['state'].attrs['time']))" \
    "$1/checkpoint.h5" 2>/dev/null || echo none
}

leg() {  # leg NAME SECONDS T_END ARGS...: start or continue one run for at most SECONDS
  local name=$1 seconds=$2 t_end=$3
  shift 3
  local run="$OUT/$name" cmd
  if [ -f "$run/checkpoint.h5" ]; then
    cmd=("$BIN" md --restart "$run" --set run.t_end="$t_end" --force)
  else
    cmd=("$BIN" md "$@" --set run.t_end="$t_end" --analyze --set output.trajectory=false
         --out "$run")
  fi
  local s0 rc
  s0=$(date +%s.%N)
  set +e
  timeout -s TERM -k 60 "$seconds" "${cmd[@]}" >> "$OUT/$name.log" 2>&1
  rc=$?
  set -e
  echo "$name,$(date -u +%FT%TZ),$(echo "$(date +%s.%N) - $s0" | bc),$rc,$(t_of "$run"),$(
    "$BIN" --version | head -n 1 | tr ',' ' ')" >> "$LEGS"
  echo "gpu_campaign: $name: exit $rc, t = $(t_of "$run")"
}

if [ "$DRY" = 1 ]; then
  SIZE_C=(--set system.N=2000); SIZE_N=(--set system.N=2000); T_C=5; T_N=5
else
  SIZE_C=(--set system.N=400128); SIZE_N=(--set system.N=3201024 --set integrator.dt=adaptive)
  T_C=1000; T_N=3000
fi
charged_s=$(printf '%.0f' "$(echo "$BUDGET * $CHARGED_SHARE" | bc)")
leg charged-L140 "$charged_s" "$T_C" --preset paper "${SIZE_C[@]}" --set coulomb.K=5 \
  --set charging.Q=0.05 --seed 301
left=$(( BUDGET - ($(date +%s) - START) ))
if [ "$left" -gt 30 ]; then
  leg neutral-L280 "$left" "$T_N" --preset paper "${SIZE_N[@]}" --seed 203
fi
echo "gpu_campaign: wrote $OUT ($(du -sh "$OUT" | cut -f1))"
