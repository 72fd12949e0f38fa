#pragma once
/// \file LammpsApi.h
/// The LAMMPS C++ API as granagg uses it (Debian's liblammps-dev, LAMMPS 29 Sep 2021; or a
/// site's LAMMPS found through -DLAMMPS_DIR). The one place that includes LAMMPS headers, after
/// the fmt compatibility declaration they need (FmtCompat.h). Compiled with OMPI_SKIP_MPICXX
/// (no Open MPI C++ bindings: LAMMPS uses the C API) and LAMMPS_SMALLBIG (the integer sizes
/// liblammps.so was built with: 32-bit atom ids, 64-bit step counts), both set by CMake.
/// Rule: no LAMMPS function that takes fmt types is called (FmtCompat.h); error->all and
/// error->one get a std::string.
#include "md/lammps/FmtCompat.h"

#include <atom.h>
#include <comm.h>
#include <domain.h>
#include <error.h>
#include <fix.h>
#include <force.h>
#include <input.h>
#include <kspace.h>
#include <lammps.h>
#include <memory.h>
#include <modify.h>
#include <neigh_list.h>
#include <neighbor.h>
#include <pair.h>
#include <update.h>
