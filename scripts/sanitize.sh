#!/usr/bin/env bash
# The sanitizer suite (issue 47; docs/robustness.md): the C++ built with AddressSanitizer,
# LeakSanitizer and UndefinedBehaviorSanitizer (GCC's, -DGRANAGG_SANITIZE=address,undefined) in
# build-sanitize, and the CTest suite run on it without its [slow] cases. Any report fails the
# test it happens in: ASan and LSan abort on the first report, UBSan is built not to recover.
#
#   usage: bash scripts/sanitize.sh [--subset] [ctest arguments, e.g. -R common]
#   --subset  the README test command's stage: only what needs no MD engine -- the suites of
#             common/, analysis/ and meanfield/, md's file formats and configuration
#             (test_md_io: tests/md/test_{config,checkpoint,h5md}.cpp) and the fuzz corpus
#             replays. Left out, for time (the engine's ASan build alone takes longer than the
#             rest of the test command): the md engine suite (test_md), the CLI, study and
#             LAMMPS suites, the crash trials and pytest. Without --subset: everything.
#   environment: GRANAGG_SANITIZE_DIR (build-sanitize), GRANAGG_JOBS (nproc)
# Reports inside Debian's libraries are suppressed, each with its reason, in
# tests/sanitizers/lsan.supp (leaks) and tests/sanitizers/ubsan.supp (undefined behaviour).
set -euo pipefail
cd "$(dirname "$0")/.."
SUBSET=0
if [ "${1:-}" = "--subset" ]; then SUBSET=1; shift; fi
GRANAGG_SETUP_NO_BUILD=1 bash scripts/setup.sh
DIR=${GRANAGG_SANITIZE_DIR:-build-sanitize}
JOBS=${GRANAGG_JOBS:-$(nproc)}
# -O1: a third of -O2's compile time, and the sanitizers' own advice for readable reports
cmake -S . -B "$DIR" -DCMAKE_BUILD_TYPE=RelWithDebInfo "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g" \
      -DGRANAGG_SANITIZE=address,undefined -DPython_EXECUTABLE=/usr/bin/python3 \
      -DGRANAGG_PYTHON=OFF >/dev/null
export ASAN_OPTIONS=halt_on_error=1:abort_on_error=1:detect_leaks=1:strict_string_checks=1
export LSAN_OPTIONS=suppressions=$PWD/tests/sanitizers/lsan.supp:print_suppressions=0
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
UBSAN_OPTIONS+=:suppressions=$PWD/tests/sanitizers/ubsan.supp
if [ "$SUBSET" = 1 ]; then
  HARNESSES=$(sed -n 's/^set(FUZZ_HARNESSES \(.*\))$/\1/p' tests/fuzz/CMakeLists.txt)
  TARGETS=(test_common test_analysis test_meanfield test_md_io)
  for h in $HARNESSES; do TARGETS+=("fuzz_replay_$h"); done
  cmake --build "$DIR" -j "$JOBS" --target "${TARGETS[@]}"
  ctest --test-dir "$DIR" --output-on-failure -j "$JOBS" \
        -R '^(common|analysis|meanfield|md_io|fuzz):' "$@"
else
  cmake --build "$DIR" -j "$JOBS"
  rc=0
  ctest --test-dir "$DIR" --output-on-failure -j "$JOBS" -E '^lammps:' "$@" || rc=$?
  # The LAMMPS suite without leak checking: Open MPI's components are dlopen'ed and unloaded
  # again at MPI_Finalize, so LSan reports their allocations from "<unknown module>", which no
  # suppression can name exactly. ASan's and UBSan's other checks stay on.
  ASAN_OPTIONS=${ASAN_OPTIONS/detect_leaks=1/detect_leaks=0} \
    ctest --test-dir "$DIR" --output-on-failure -j "$JOBS" -R '^lammps:' "$@" || rc=$?
  exit "$rc"
fi
