#!/usr/bin/env bash
# The fuzz campaign (issue 47; docs/robustness.md, "Fuzzed readers"): builds the libFuzzer
# harnesses of tests/fuzz with Debian's clang 14 (-DGRANAGG_FUZZ=ON: AddressSanitizer, UBSan,
# coverage) and runs each for RUNS executions or SECONDS seconds, whichever ends first, from its
# committed seed corpus. An input that fails is kept in OUT/artifacts/NAME/; after the cause is
# fixed, copy it into tests/fuzz/corpus/NAME/ so that the README test command replays it.
#
#   usage: bash scripts/fuzz.sh [HARNESS...]     (default: all of tests/fuzz/CMakeLists.txt)
#   environment: RUNS (1000000), SECONDS_EACH (1800), OUT (build-fuzz/campaign), JOBS (nproc),
#                NICE (0)
# Limits per input, as the issue sets them: 1 s (-timeout), 1 GB (-rss_limit_mb and
# -malloc_limit_mb). OUT/summary.csv has one row per harness: executions, seconds, coverage
# (edges of granagg's code; libhdf5 is not instrumented), features, corpus size and failures.
set -euo pipefail
cd "$(dirname "$0")/.."
RUNS=${RUNS:-1000000}
SECONDS_EACH=${SECONDS_EACH:-1800}
OUT=${OUT:-build-fuzz/campaign}
JOBS=${JOBS:-$(nproc)}
NICE=${NICE:-0}
CXX=${FUZZ_CXX:-clang++-14}
CC=${FUZZ_CC:-clang-14}
command -v "$CXX" >/dev/null || { echo "scripts/fuzz.sh: $CXX not found (apt install clang-14)" >&2;
                                  exit 2; }
HARNESSES=("$@")
if [ ${#HARNESSES[@]} -eq 0 ]; then
  read -r -a HARNESSES <<< \
    "$(sed -n 's/^set(FUZZ_HARNESSES \(.*\))$/\1/p' tests/fuzz/CMakeLists.txt)"
fi
REV=$(git rev-parse --short=12 HEAD)$(git diff --quiet HEAD -- . ':!docs' || echo +)  # as built
cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER="$CXX" \
      -DCMAKE_C_COMPILER="$CC" -DGRANAGG_FUZZ=ON -DGRANAGG_PYTHON=OFF >/dev/null
cmake --build build-fuzz -j "$JOBS" --target "${HARNESSES[@]/#/fuzz_}"
mkdir -p "$OUT"
SUMMARY="$OUT/summary.csv"
[ -f "$SUMMARY" ] ||
  echo "harness,executions,seconds,coverage,features,corpus,granagg_failures,utc,granagg" \
    > "$SUMMARY"
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:halt_on_error=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$PWD/tests/sanitizers/lsan.supp}
failed=0
for h in "${HARNESSES[@]}"; do
  work="$OUT/corpus/$h"; art="$OUT/artifacts/$h"; log="$OUT/$h.log"
  mkdir -p "$work" "$art"
  max_len=$(find "tests/fuzz/corpus/$h" -type f -printf '%s\n' | sort -n | tail -n 1)
  max_len=$(( max_len > 4096 ? max_len : 4096 ))
  # The HDF5 harnesses feed libhdf5 bytes it decodes itself: its own huge malloc()s return NULL
  # (allocator_may_return_null; HDF5 checks them) and its own crashes (known decoder bugs of
  # 1.10.8) are kept going past (-fork, -ignore_crashes) and triaged below. granagg's C++
  # allocations go through operator new, which ASan still reports above the 1 GB rss limit.
  extra=(-malloc_limit_mb=1024)
  case "$h" in
    h5md_raw|checkpoint) extra=(-malloc_limit_mb=1048576 -fork=1 -ignore_crashes=1
                                -ignore_ooms=1 -ignore_timeouts=1) ;;
  esac
  # libhdf5 leaks on many of its error paths with malformed files; leaks of granagg's own code
  # are the sanitizer stage's (scripts/test.sh, detect_leaks=1 over the whole test suite)
  leaks=1
  case "$h" in h5md_raw|checkpoint) leaks=0 ;; esac
  echo "== fuzz_$h: $RUNS runs or $SECONDS_EACH s (log $log)"
  t0=$(date +%s)
  set +e
  ASAN_OPTIONS="$ASAN_OPTIONS:allocator_may_return_null=1:detect_leaks=$leaks" nice -n "$NICE" \
    "build-fuzz/tests/fuzz/fuzz_$h" -runs="$RUNS" -max_total_time="$SECONDS_EACH" \
    -timeout=1 -rss_limit_mb=1024 "${extra[@]}" -max_len="$max_len" \
    -print_final_stats=1 -artifact_prefix="$art/" "$work" "tests/fuzz/corpus/$h" > "$log" 2>&1
  rc=$?
  set -e
  # Triage: an input whose report's first frame outside the sanitizer and libc lies in libhdf5
  # is HDF5's (docs/robustness.md lists them); any other is granagg's and fails the campaign.
  # (the first frame of the report that is either libhdf5's or granagg's decides; an input that
  # does not fail again when replayed alone is "unreproduced", listed but not counted)
  ours=0
  for a in "$art"/*; do
    [ -f "$a" ] || continue
    # (an out-of-memory input is replayed with a higher rss limit than its malloc limit, so that
    # the report is the large malloc's, with its stack, not the rss watchdog's, without one)
    limits=(-rss_limit_mb=1024)
    case "$(basename "$a")" in
      oom-*|timeout-*) limits=(-rss_limit_mb=8192 -malloc_limit_mb=1024) ;;
    esac
    report=$( { ASAN_OPTIONS="$ASAN_OPTIONS:allocator_may_return_null=1:detect_leaks=$leaks" \
                "build-fuzz/tests/fuzz/fuzz_$h" "${limits[@]}" -timeout=10 "$a" 2>&1 || true; } )
    frame=$(echo "$report" | grep -E '^ +#[0-9]+ ' |
            grep -E 'libhdf5|granagg|fuzz_[a-z_]+\.cpp' | head -n 1 || true)
    owner=granagg
    case "$frame" in *libhdf5*) owner=libhdf5 ;; esac
    echo "$report" | grep -qE 'ERROR|DEFECT|SUMMARY' || owner=unreproduced
    [ "$owner" = granagg ] && ours=$((ours + 1))
    echo "$h,$(basename "$a"),$owner,$(echo "$frame" | sed 's/^ *//; s/,/;/g' | cut -c1-160)" \
      >> "$OUT/artifacts.csv"
  done
  [ "$ours" -eq 0 ] && [ "$rc" -ne 0 ] && [ -n "$(ls "$art")" ] && rc=0  # only HDF5's crashes
  secs=$(( $(date +%s) - t0 ))
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -n 1)
  # (fork mode prints no final stats: its last status line "#N: cov: ..." counts the runs)
  [ -n "$execs" ] || execs=$(sed -n 's/^#\([0-9]*\): cov:.*/\1/p' "$log" | tail -n 1)
  cov=$(grep -o 'cov: [0-9]*' "$log" | tail -n 1 | grep -o '[0-9]*' || echo 0)
  ft=$(grep -o 'ft: [0-9]*' "$log" | tail -n 1 | grep -o '[0-9]*' || echo 0)
  corpus=$(find "$work" -type f | wc -l)
  fails=$ours
  [ "$rc" -eq 0 ] || failed=1
  echo "$h,${execs:-0},$secs,$cov,$ft,$corpus,$fails,$(date -u +%FT%TZ),$REV" >> "$SUMMARY"
  tail -n 3 "$log"
done
column -s, -t < "$SUMMARY"
exit "$failed"
