#!/usr/bin/env bash
# The test command (README, .ci/run): installs what is missing, builds, runs the whole Catch2
# suite through CTest, and -- when nvcc is present -- compiles the CUDA build without running it,
# so that it never rots (no GPU on the CI machines), runs pytest and the GPU scripts' dry runs,
# and ends with the sanitizer stage (scripts/sanitize.sh --subset).
set -euo pipefail
cd "$(dirname "$0")/.."
T0=$SECONDS
bash scripts/setup.sh
T_BUILD=$((SECONDS - T0))
BUILD_DIR=${GRANAGG_BUILD_DIR:-build}
JOBS=${GRANAGG_JOBS:-$(nproc)}

LOG=$(mktemp)
trap 'rm -f "$LOG"' EXIT
# Every TEST_CASE must reach CTest. catch_discover_tests builds a CMake list from the names: a
# ';' split one test into two that ran nothing, and an unmatched '[' swallowed every later name
# of its suite (5 common, 3 analysis and 1 cli test case had silently not run, b9085c6).
CATCH_CASES=0
for t in "$BUILD_DIR"/tests/test_*; do
  [ -x "$t" ] && [ -f "$t" ] || continue
  # (Catch2 v2's --list-* exit with the number listed: not an error)
  n=$("$t" --list-test-names-only | grep -c . || true)
  CATCH_CASES=$((CATCH_CASES + n))
done
CTEST_CASES=$(ctest --test-dir "$BUILD_DIR" -N | sed -n 's/^Total Tests: //p')
# (tests labelled "script", such as the crash trials, are not Catch2 cases)
SCRIPT_CASES=$(ctest --test-dir "$BUILD_DIR" -N -L '^script$' | sed -n 's/^Total Tests: //p')
CTEST_CASES=$((CTEST_CASES - ${SCRIPT_CASES:-0}))
if [ "$CATCH_CASES" != "$CTEST_CASES" ]; then
  echo "scripts/test.sh: the suites hold $CATCH_CASES test cases but CTest registered" \
    "$CTEST_CASES: a test name with ';' or '[' (see tests/CMakeLists.txt). Such names:" >&2
  for t in "$BUILD_DIR"/tests/test_*; do
    [ -x "$t" ] && [ -f "$t" ] || continue
    { "$t" --list-test-names-only || true; } | grep '[;[]' | sed "s|^|  $(basename "$t"): |" >&2
  done
  exit 1
fi
set +e
ctest --test-dir "$BUILD_DIR" --output-on-failure -j "$JOBS" | tee "$LOG"
CTEST_RC=${PIPESTATUS[0]}
set -e
T_CTEST=$((SECONDS - T0 - T_BUILD))
# "N tests passed, M failed out of T" -> the plain summary printed last (after the CUDA build)
TOTAL=$(sed -n 's/.*tests failed out of \([0-9]*\).*/\1/p' "$LOG" | tail -n 1)
FAILED=$(sed -n 's/.*tests passed, \([0-9]*\) tests failed out of.*/\1/p' "$LOG" | tail -n 1)
[ -n "$TOTAL" ] || { echo "scripts/test.sh: ctest printed no summary" >&2; exit 1; }

NVCC=${NVCC:-$(command -v nvcc || echo /usr/local/cuda/bin/nvcc)}
if [ -x "$NVCC" ]; then
  echo "== CUDA build (compile and link only; $("$NVCC" --version | tail -n 1))"
  CUDA_DIR=${GRANAGG_CUDA_BUILD_DIR:-build-cuda}
  # granagg and the GPU test suite (test_md_gpu; run by scripts/gpu_check.sh on a GPU machine)
  cmake -S . -B "$CUDA_DIR" -DCMAKE_BUILD_TYPE=Release -DENABLE_CUDA=ON -DBUILD_TESTING=ON \
        -DCMAKE_CUDA_COMPILER="$NVCC" -DCMAKE_CUDA_ARCHITECTURES=90 >/dev/null
  cmake --build "$CUDA_DIR" -j "$JOBS" --target granagg test_md_gpu
  test -x "$CUDA_DIR/bin/granagg" && test -x "$CUDA_DIR/tests/test_md_gpu"
  echo "CUDA build OK: $CUDA_DIR/bin/granagg, $CUDA_DIR/tests/test_md_gpu"
else
  echo "== nvcc not found: CUDA build skipped"
fi

T_CUDA=$((SECONDS - T0 - T_BUILD - T_CTEST))

# The Python package's pytest suite (issue 46; docs/python.md), with Debian's interpreter, from
# a folder outside the source tree, so that `import granagg` can only find the built package.
# Each pytest test counts as one test in the summary line.
echo "== Python package: pytest tests/python"
PY_DIR="$PWD/$BUILD_DIR/python"
if [ -f "$PY_DIR/granagg/__init__.py" ] && ls "$PY_DIR"/granagg/_granagg*.so >/dev/null 2>&1; then
  mkdir -p "$BUILD_DIR/pytest"
  set +e
  ROOT=$PWD
  (cd "$BUILD_DIR/pytest" && PYTHONPATH="$PY_DIR" GRANAGG_BIN="$ROOT/$BUILD_DIR/bin/granagg" \
     MPLBACKEND=Agg /usr/bin/python3 -m pytest -q -p no:cacheprovider \
     --junitxml=pytest.xml "$ROOT/tests/python") | tee "$BUILD_DIR/pytest.log"
  PYTEST_RC=${PIPESTATUS[0]}
  set -e
  PY_SUMMARY=$(tail -n 1 "$BUILD_DIR/pytest.log")   # "== 40 passed, 1 failed in 12.3s =="
  PY_PASSED=$(echo "$PY_SUMMARY" | grep -o '[0-9]* passed' | grep -o '[0-9]*' || true)
  PY_FAILED=$( { echo "$PY_SUMMARY" | grep -o '[0-9]* \(failed\|errors\?\)' || true; } |
              awk '{ n += $1 } END { print n + 0 }')
  PY_PASSED=${PY_PASSED:-0}; PY_FAILED=${PY_FAILED:-0}
  if [ "$PYTEST_RC" -ne 0 ] && [ "$PY_FAILED" -eq 0 ]; then PY_FAILED=1; fi
  TOTAL=$((TOTAL + PY_PASSED + PY_FAILED)); FAILED=$((FAILED + PY_FAILED))
  [ "$PYTEST_RC" -eq 0 ] || CTEST_RC=1
else
  echo "scripts/test.sh: the Python package was not built (see the configure output)" >&2
  TOTAL=$((TOTAL + 1)); FAILED=$((FAILED + 1)); CTEST_RC=1
fi
T_PY=$((SECONDS - T0 - T_BUILD - T_CTEST - T_CUDA))
# The GPU check script's dry run (the CPU build in place of the CUDA one), so that it cannot rot
echo "== scripts/gpu_check.sh --dry-run"
TOTAL=$((TOTAL + 1))   # counted as one more test in the summary line
GPU_DRY_RC=0
bash scripts/gpu_check.sh --dry-run --out "$BUILD_DIR/gpu_check_dry" \
  > "$BUILD_DIR/gpu_check_dry.log" 2>&1 || GPU_DRY_RC=$?
if [ "$GPU_DRY_RC" -ne 0 ]; then
  cat "$BUILD_DIR/gpu_check_dry.log"
  echo "scripts/gpu_check.sh --dry-run failed (exit $GPU_DRY_RC)"
  FAILED=$((FAILED + 1)); CTEST_RC=1
else
  echo "gpu_check dry run OK: $BUILD_DIR/gpu_check_dry/summary.md"
fi

# The GPU campaign's dry run (issue 45): the same two legs at test size on the CPU build
echo "== scripts/gpu_campaign.sh --dry-run"
TOTAL=$((TOTAL + 1))
rm -rf "$BUILD_DIR/gpu_campaign_dry"
if OUT="$BUILD_DIR/gpu_campaign_dry" BUDGET=120 GRANAGG_BIN="$BUILD_DIR/bin/granagg" \
    bash scripts/gpu_campaign.sh --dry-run > "$BUILD_DIR/gpu_campaign_dry.log" 2>&1 &&
    [ -f "$BUILD_DIR/gpu_campaign_dry/neutral-L280/analysis/S_t.csv" ]; then
  echo "gpu_campaign dry run OK: $BUILD_DIR/gpu_campaign_dry/legs.csv"
else
  cat "$BUILD_DIR/gpu_campaign_dry.log"
  echo "scripts/gpu_campaign.sh --dry-run failed"
  FAILED=$((FAILED + 1)); CTEST_RC=1
fi

T_DRY=$((SECONDS - T0 - T_BUILD - T_CTEST - T_CUDA - T_PY))

# The sanitizer stage (issue 47; docs/robustness.md): AddressSanitizer, LeakSanitizer and UBSan
# over the readers, the parsers, the unit suites that need no MD engine and the fuzz corpus
# replays (scripts/sanitize.sh says what --subset leaves out). Its cases count in the summary.
echo "== sanitizer stage: scripts/sanitize.sh --subset (ASan, LSan, UBSan)"
SAN_LOG="$BUILD_DIR/sanitize.log"
set +e
GRANAGG_JOBS=$JOBS bash scripts/sanitize.sh --subset > "$SAN_LOG" 2>&1
SAN_RC=$?
set -e
SAN_TOTAL=$(sed -n 's/.*tests failed out of \([0-9]*\).*/\1/p' "$SAN_LOG" | tail -n 1)
SAN_FAILED=$(sed -n 's/.*tests passed, \([0-9]*\) tests failed out of.*/\1/p' "$SAN_LOG" |
             tail -n 1)
if [ -z "$SAN_TOTAL" ]; then
  tail -n 40 "$SAN_LOG"
  echo "scripts/sanitize.sh --subset failed before its tests ran (exit $SAN_RC)"
  TOTAL=$((TOTAL + 1)); FAILED=$((FAILED + 1)); CTEST_RC=1
else
  TOTAL=$((TOTAL + SAN_TOTAL)); FAILED=$((FAILED + SAN_FAILED))
  if [ "$SAN_RC" -ne 0 ]; then
    sed -n '/The following tests FAILED/,$p' "$SAN_LOG"
    grep -B2 -A30 -m 3 'ERROR: \(AddressSanitizer\|LeakSanitizer\)\|runtime error:' "$SAN_LOG" ||
      true
    CTEST_RC=1
  fi
  echo "sanitizer stage: $((SAN_TOTAL - SAN_FAILED)) of $SAN_TOTAL passed (log $SAN_LOG)"
fi
T_SAN=$((SECONDS - T0 - T_BUILD - T_CTEST - T_CUDA - T_PY - T_DRY))
echo "time: set-up and build ${T_BUILD} s, tests ${T_CTEST} s, CUDA build ${T_CUDA} s," \
  "pytest ${T_PY} s, GPU dry run ${T_DRY} s, sanitizer stage ${T_SAN} s"
echo "tests: $((TOTAL - FAILED)) passed, $FAILED failed"
exit "$CTEST_RC"
