#!/usr/bin/env bash
# Installs what granagg needs from Debian's packages (idempotent: quiet when all is there) and
# configures + builds the CPU build in ./build. Used by scripts/test.sh and scripts/demo.sh.
# LAMMPS, fmt and Open MPI are for granagg-lammps (docs/lammps.md; `lammps` for the lmp binary
# of the benchmarks); the build works without them and then leaves granagg-lammps out.
#   GRANAGG_BUILD_DIR   build folder (default: build)
#   GRANAGG_JOBS        parallel compile jobs (default: nproc)
#   GRANAGG_SETUP_NO_BUILD=1   install the packages only (scripts/gpu_check.sh builds its own)
set -euo pipefail
cd "$(dirname "$0")/.."

PACKAGES=(build-essential cmake pkg-config git
          libsundials-dev libeigen3-dev libboost-dev libgsl-dev libhdf5-dev catch2 libfftw3-dev
          librandom123-dev libcli11-dev libtomlplusplus-dev nlohmann-json3-dev libthrust-dev
          libomp-dev
          liblammps-dev libfmt-dev libopenmpi-dev openmpi-bin lammps
          python3-matplotlib python3-numpy python3-h5py python3-mdanalysis
          python3-dev pybind11-dev python3-pybind11 python3-pytest python3-scipy python3-pandas)

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "granagg setup: installing ${missing[*]}"
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends \
    "${missing[@]}" >/dev/null
fi

[ "${GRANAGG_SETUP_NO_BUILD:-0}" = 1 ] && exit 0

BUILD_DIR=${GRANAGG_BUILD_DIR:-build}
JOBS=${GRANAGG_JOBS:-$(nproc)}
# Configure every time (a second configure takes about a second): a folder left by a configure
# that failed (say, before the packages above were installed) holds a CMakeCache.txt but no
# Makefile, and skipping the configure then failed the build with "No rule to make target".
if [ -f "$BUILD_DIR/CMakeCache.txt" ]; then
  cmake -S . -B "$BUILD_DIR" -DPython_EXECUTABLE=/usr/bin/python3 >/dev/null
else
  cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release -DPython_EXECUTABLE=/usr/bin/python3 \
    >/dev/null
fi
cmake --build "$BUILD_DIR" -j "$JOBS"
