#!/usr/bin/env bash
# The sanitizer suite (issue 47; docs/robustness.md): the C++ built with AddressSanitizer and
# UndefinedBehaviorSanitizer (GCC's, -DGRANAGG_SANITIZE=address,undefined) in build-sanitize, and
# the whole CTest suite run on it, the crash trials included. Any report fails the test it
# happens in: ASan aborts on the first memory error, and UBSan is built not to recover.
#   usage: bash scripts/sanitize.sh [ctest arguments, e.g. -R common]
#   environment: GRANAGG_SANITIZE_DIR (build-sanitize), GRANAGG_JOBS (nproc)
# Leak checking is off (detect_leaks=0): Open MPI and HDF5 keep their allocations to exit.
set -euo pipefail
cd "$(dirname "$0")/.."
GRANAGG_SETUP_NO_BUILD=1 bash scripts/setup.sh
DIR=${GRANAGG_SANITIZE_DIR:-build-sanitize}
JOBS=${GRANAGG_JOBS:-$(nproc)}
cmake -S . -B "$DIR" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DGRANAGG_SANITIZE=address,undefined \
      -DPython_EXECUTABLE=/usr/bin/python3 -DGRANAGG_PYTHON=OFF >/dev/null
cmake --build "$DIR" -j "$JOBS"
export ASAN_OPTIONS=detect_leaks=0:abort_on_error=1:strict_string_checks=1
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
ctest --test-dir "$DIR" --output-on-failure -j "$JOBS" "$@"
