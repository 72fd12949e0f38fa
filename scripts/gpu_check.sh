#!/usr/bin/env bash
# The GPU check (issue 15; docs/gpu.md): on a machine with an NVIDIA GPU, builds the CUDA variant,
# runs the GPU test suite (test_md_gpu: the engine-level md test bodies on the GPU backend, and the
# CPU backend's reference states, tests/md/test_backend.cpp) and a short benchmark (neutral and
# charged paper-preset gases at N = 1e5 and 1e6: particle-steps/s and the paper-scale
# extrapolation), and writes everything into one folder. Meant to finish in under 8 minutes.
#
#   bash scripts/gpu_check.sh [--out DIR]            build (build-cuda/) and check on this GPU
#   bash scripts/gpu_check.sh --bundle DIR           build here (nvcc, no GPU needed) and pack the
#                                                    binaries with the shared libraries that a GPU
#                                                    machine without granagg's Debian packages lacks
#   bash scripts/gpu_check.sh --prebuilt DIR [--out D]   check with a bundle made by --bundle
#   bash scripts/gpu_check.sh --dry-run [--out DIR]  no GPU: the same steps with the CPU build at
#                                                    test size (CI runs it: the script cannot rot)
#
# Output (default results/gpu_check/): summary.md (device, build, tests, benchmark table),
# bench.csv (one row per run: case, N, steps, seconds, particle-steps/s, paper-scale hours),
# tests.log (Catch2, with durations), bench.log, build.log, env.txt. Exit status: 0 when the tests
# passed and every benchmark run finished, 1 otherwise, 2 for bad arguments or no GPU.
# Environment: GPU_CHECK_TEST_TIMEOUT (s, default 300), GPU_CHECK_RUN_TIMEOUT (s per benchmark
# run, default 120), GPU_CHECK_JOBS (compile jobs, default nproc).
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD

OUT=results/gpu_check
MODE=gpu
BUNDLE=""
PREBUILT=""
usage() { sed -n '2,/^set -euo/p' "$0" | grep '^#' | sed -E 's/^# ?//'; }
while [ $# -gt 0 ]; do
  case "$1" in
    --out) OUT=${2:?--out needs a folder}; shift 2 ;;
    --dry-run) MODE=dry; shift ;;
    --bundle) MODE=bundle; BUNDLE=${2:?--bundle needs a folder}; shift 2 ;;
    --prebuilt) PREBUILT=${2:?--prebuilt needs a folder}; shift 2 ;;
    -h|--help) usage; exit 0 ;;
    *) echo "gpu_check: unknown option '$1' (see --help)" >&2; exit 2 ;;
  esac
done
[ -z "$PREBUILT" ] || PREBUILT=$(realpath "$PREBUILT")
JOBS=${GPU_CHECK_JOBS:-$(nproc)}
TEST_TIMEOUT=${GPU_CHECK_TEST_TIMEOUT:-300}
RUN_TIMEOUT=${GPU_CHECK_RUN_TIMEOUT:-120}
NVCC=${NVCC:-$(command -v nvcc || echo /usr/local/cuda/bin/nvcc)}
CUDA_DIR=${GRANAGG_CUDA_BUILD_DIR:-build-cuda}

build_cuda() {  # configure and build granagg + test_md_gpu in $CUDA_DIR; log to $1
  [ -x "$NVCC" ] || { echo "gpu_check: nvcc not found (set NVCC)" >&2; exit 2; }
  GRANAGG_SETUP_NO_BUILD=1 bash scripts/setup.sh > "$1" 2>&1   # the Debian packages
  cmake -S . -B "$CUDA_DIR" -DCMAKE_BUILD_TYPE=Release -DENABLE_CUDA=ON -DBUILD_TESTING=ON \
        -DCMAKE_CUDA_COMPILER="$NVCC" -DCMAKE_CUDA_ARCHITECTURES=90 >> "$1" 2>&1
  cmake --build "$CUDA_DIR" -j "$JOBS" --target granagg test_md_gpu >> "$1" 2>&1 \
    || { tail -n 30 "$1" >&2; echo "gpu_check: CUDA build failed (log: $1)" >&2; exit 1; }
}

# ---- --bundle: build here, pack binaries + the libraries outside glibc and the CUDA toolkit
if [ "$MODE" = bundle ]; then
  mkdir -p "$BUNDLE/bin" "$BUNDLE/lib"
  build_cuda "$BUNDLE/build.log"
  cp "$CUDA_DIR/bin/granagg" "$CUDA_DIR/tests/test_md_gpu" "$BUNDLE/bin/"
  strip "$BUNDLE/bin/granagg" "$BUNDLE/bin/test_md_gpu"
  # glibc (all of its libraries: libresolv & co. must match its libc), the dynamic loader,
  # libstdc++ and libgcc_s come from the GPU machine (newer versions run binaries built against
  # older ones); libcuda is the driver's; the CUDA toolkit's libraries (cudart, cufft) must be the
  # GPU machine's own toolkit of the same major version (CUDA 13 here).
  ldd "$BUNDLE/bin/granagg" "$BUNDLE/bin/test_md_gpu" | awk '/=> \// {print $3}' | sort -u |
    grep -Ev '/(libc|libm|libdl|librt|libpthread|libresolv|libnsl|libutil|libanl)\.so' |
    grep -Ev '/(ld-linux[^/]*|libstdc\+\+|libgcc_s)\.so' |
    grep -Ev '/(libcuda|libcudart|libcufft)\.so' |
    while read -r lib; do cp -L "$lib" "$BUNDLE/lib/"; done
  # compressed: 30 MB of binaries become 12, so that bundle and checkout (~5 MB) stay well inside
  # a 64 MiB transfer; --prebuilt unpacks them
  gzip -f "$BUNDLE/bin/granagg" "$BUNDLE/bin/test_md_gpu"
  git rev-parse HEAD > "$BUNDLE/commit" 2>/dev/null || true
  echo "gpu_check: bundle in $BUNDLE ($(du -sh "$BUNDLE" | cut -f1)); on the GPU machine, from a" \
       "checkout of the same commit: bash scripts/gpu_check.sh --prebuilt $BUNDLE" >&2
  exit 0
fi

mkdir -p "$OUT"
SUMMARY="$OUT/summary.md"
: > "$OUT/bench.log"
{
  echo "date: $(date -u +%FT%TZ)"
  echo "commit: $(git rev-parse HEAD 2>/dev/null || cat "$PREBUILT/commit" 2>/dev/null || echo ?)"
  echo "mode: $MODE${PREBUILT:+ (prebuilt $PREBUILT)}"
  echo "host: $(uname -srm), $(nproc) cores"
  command -v nvidia-smi >/dev/null && nvidia-smi --query-gpu=name,memory.total,driver_version \
    --format=csv,noheader 2>&1 || echo "nvidia-smi: not available"
  [ -x "$NVCC" ] && "$NVCC" --version | tail -n 1 || true
} > "$OUT/env.txt"

if [ "$MODE" = gpu ]; then
  nvidia-smi -L 2>/dev/null | grep -q GPU \
    || { echo "gpu_check: no GPU found (nvidia-smi lists none); --dry-run checks the script" \
              "on the CPU build" >&2; exit 2; }
  if [ -n "$PREBUILT" ]; then
    BIN=$(mktemp -d)
    for b in granagg test_md_gpu; do
      if [ -f "$PREBUILT/bin/$b.gz" ]; then gunzip -c "$PREBUILT/bin/$b.gz" > "$BIN/$b"
      else cp "$PREBUILT/bin/$b" "$BIN/$b"; fi
      chmod +x "$BIN/$b"
    done
    G="$BIN/granagg"; T="$BIN/test_md_gpu"
    LD_LIBRARY_PATH="$PREBUILT/lib:/usr/local/cuda/lib64${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
    export LD_LIBRARY_PATH
    echo "prebuilt bundle $PREBUILT (built from $(cat "$PREBUILT/commit" 2>/dev/null))" \
      > "$OUT/build.log"
  else
    build_cuda "$OUT/build.log"
    G="$CUDA_DIR/bin/granagg"; T="$CUDA_DIR/tests/test_md_gpu"
  fi
  TEST_FILTER=()                       # every test body of the GPU suite
  SIZES="100000 1000000"
  T_END_100000=10; T_END_1000000=2     # ~2900 and ~580 steps at the paper preset's dt
else
  # dry run: the CPU build stands in for the CUDA one; only the backend test cases, tiny runs
  [ -x build/bin/granagg ] && [ -x build/tests/test_md ] \
    || bash scripts/setup.sh > "$OUT/build.log" 2>&1
  echo "dry run: CPU build (build/) in place of the CUDA build" >> "$OUT/build.log"
  G=build/bin/granagg; T=build/tests/test_md
  TEST_FILTER=("[backend]")
  SIZES="2000"
  T_END_2000=0.2
fi
export GRANAGG_TEST_SOURCE_DIR="$ROOT"   # the backend reference files (tests/data/backend)

# ---- tests
TESTS_OK=1
set +e
timeout "$TEST_TIMEOUT" "$T" "${TEST_FILTER[@]}" --durations yes > "$OUT/tests.log" 2>&1
TEST_RC=$?
set -e
[ "$TEST_RC" -eq 0 ] || TESTS_OK=0
TEST_LINE=$(grep -E '^(All tests passed|test cases:)' "$OUT/tests.log" | tail -n 1 || true)
[ "$TEST_RC" -eq 124 ] && TEST_LINE="timed out after $TEST_TIMEOUT s ($TEST_LINE)"

# ---- benchmark: paper preset (phi = 0.076, Hertz), neutral and charged (K = 5, Q = 0.05, the
# validation study's charge scale), no frames; the rate is the MD loop's ("md: n steps in t s"),
# start-up and the initial state excluded. Paper scale: N = 50016 to t = 1000 at this rate (the
# early, homogeneous gas: clustering later makes runs slower, docs/validation.md).
echo "case,N,steps,seconds,particle_steps_per_s,dt,paper_scale_hours,status" > "$OUT/bench.csv"
BENCH_OK=1
for N in $SIZES; do
  t_end_var="T_END_$N"; t_end=${!t_end_var}
  for case in neutral charged; do
    extra=()
    [ "$case" = charged ] && extra=(--set coulomb.K=5 --set charging.Q=0.05)
    dir=$(mktemp -d)
    set +e
    timeout "$RUN_TIMEOUT" "$G" md --preset paper --set system.N="$N" --set run.t_end="$t_end" \
      --set output.frames_per_decade=0 "${extra[@]}" --out "$dir/run" > "$dir/log" 2>&1
    rc=$?
    set -e
    { echo "== $case N = $N (exit $rc)"; cat "$dir/log"; } >> "$OUT/bench.log"
    line=$(grep -E '^md: [0-9]+ steps in ' "$dir/log" | tail -n 1 || true)
    dtl=$(sed -n 's/^md: dt = \([0-9.eE+-]*\).*/\1/p' "$dir/log" | head -n 1)
    if [ "$rc" -eq 0 ] && [ -n "$line" ]; then
      steps=$(echo "$line" | awk '{print $2}'); secs=$(echo "$line" | awk '{print $5}')
      awk -v c="$case" -v n="$N" -v s="$steps" -v t="$secs" -v dt="$dtl" 'BEGIN {
        r = n * s / t; printf "%s,%d,%d,%.4g,%.4g,%.6g,%.3g,ok\n", c, n, s, t, r, dt,
        50016 * (1000 / dt) / r / 3600 }' >> "$OUT/bench.csv"
    else
      BENCH_OK=0
      echo "$case,$N,,,,${dtl},,failed (exit $rc)" >> "$OUT/bench.csv"
    fi
    rm -rf "$dir"
  done
done

{
  echo "# GPU check ($(date -u +%F))"
  echo
  echo '```'
  cat "$OUT/env.txt"
  echo '```'
  echo
  echo "## Tests"
  echo
  echo "\`$(basename "$T") ${TEST_FILTER[*]}\`:" \
       "${TEST_LINE:-no summary (see tests.log)} (exit $TEST_RC)"
  echo
  echo "## Benchmark (paper preset, no frames; paper scale = N 50016 to t = 1000 at this rate)"
  echo
  echo "| case | N | steps | s | particle-steps/s | paper scale (h) | status |"
  echo "|---|---|---|---|---|---|---|"
  tail -n +2 "$OUT/bench.csv" | awk -F, '{printf "| %s | %s | %s | %s | %s | %s | %s |\n",
    $1, $2, $3, $4, $5, $7, $8}'
} > "$SUMMARY"
cat "$SUMMARY"
[ "$TESTS_OK" -eq 1 ] && [ "$BENCH_OK" -eq 1 ]
