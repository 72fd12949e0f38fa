#!/usr/bin/env bash
# Rewrites the golden values tests/data/backend/*.toml (text: a dense neutral gas per contact
# model, Hertz and spring-dashpot, and a charged gas with charge exchange per Coulomb method, PPPM
# with multiple time stepping and plain Ewald; forces and energies of the initial state, state,
# forces and energies after a few hundred steps, one row per particle) with the
# CPU build, for tests/md/test_backend.cpp. That test fails at any change of the trajectory, to
# the bit (a 1e-12 relative change of the Hertz constant fails it); run this only after an
# intended change, review `git diff tests/data/backend`, and say why in the commit.
#
#   usage: bash scripts/write_reference_states.sh [BUILD_DIR]   (default build)
set -euo pipefail
cd "$(dirname "$0")/.."
B=${1:-build}
[ -x "$B/tests/test_md" ] \
  || { echo "write_reference_states.sh: no $B/tests/test_md (build the CPU tests first)" >&2
       exit 2; }
"$B/tests/test_md" --write-reference "[backend]"
"$B/tests/test_md" "[backend]"
git status --short tests/data/backend
