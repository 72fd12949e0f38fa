# granagg-lammps (docs/lammps.md): granagg's model on LAMMPS across MPI ranks. Built when MPI and
# LAMMPS are found: Debian's liblammps-dev (LAMMPS 29 Sep 2021, its CMake config LAMMPS::lammps),
# or a site's LAMMPS given as -DLAMMPS_DIR=... (the folder of its LAMMPSConfig.cmake, its install
# prefix, or a source tree with src/lammps.h and a built liblammps). Neither `granagg` nor
# granagg_md links MPI. Sets GRANAGG_LAMMPS_TARGET (the LAMMPS library target) when found.
#
# A LAMMPS named with -DLAMMPS_DIR is the only one looked at (NO_DEFAULT_PATH): a system LAMMPS
# must not win over the site's. It is kept in GRANAGG_LAMMPS_ROOT, because find_package replaces
# LAMMPS_DIR by LAMMPS_DIR-NOTFOUND where that folder holds no LAMMPSConfig.cmake (a prefix
# searched by its suffixes, or a source tree), and the fallback below still needs it.
if(LAMMPS_DIR)
  set(GRANAGG_LAMMPS_ROOT "${LAMMPS_DIR}" CACHE PATH "The LAMMPS given with -DLAMMPS_DIR" FORCE)
endif()
if(GRANAGG_LAMMPS_ROOT)
  set(granagg_lammps_where PATHS ${GRANAGG_LAMMPS_ROOT} NO_DEFAULT_PATH)
  set(granagg_lammps_hints HINTS ${GRANAGG_LAMMPS_ROOT} NO_DEFAULT_PATH)
else()
  set(granagg_lammps_where "")
  set(granagg_lammps_hints "")
endif()
set(GRANAGG_LAMMPS_TARGET "")
set(granagg_lammps_missing "")
find_package(MPI COMPONENTS CXX QUIET)
if(NOT MPI_CXX_FOUND)
  set(granagg_lammps_missing "no MPI for C++ found (Debian: libopenmpi-dev)")
else()
  find_package(LAMMPS CONFIG QUIET ${granagg_lammps_where})
  if(LAMMPS_FOUND AND TARGET LAMMPS::lammps)
    set(GRANAGG_LAMMPS_TARGET LAMMPS::lammps)   # carries LAMMPS's integer sizes (LAMMPS_SMALLBIG)
    get_target_property(granagg_lammps_inc LAMMPS::lammps INTERFACE_INCLUDE_DIRECTORIES)
  else()
    find_path(LAMMPS_INCLUDE_DIR lammps.h ${granagg_lammps_hints}
              PATH_SUFFIXES include/lammps src lammps)
    find_library(LAMMPS_LIBRARY NAMES lammps lammps_mpi ${granagg_lammps_hints}
                 PATH_SUFFIXES lib lib64 build src)
    if(LAMMPS_INCLUDE_DIR AND LAMMPS_LIBRARY)
      add_library(granagg_lammps_api INTERFACE)
      target_include_directories(granagg_lammps_api SYSTEM INTERFACE ${LAMMPS_INCLUDE_DIR})
      # LAMMPS's default integer sizes; a LAMMPS built otherwise ships a CMake config that says so
      target_compile_definitions(granagg_lammps_api INTERFACE LAMMPS_SMALLBIG)
      target_link_libraries(granagg_lammps_api INTERFACE ${LAMMPS_LIBRARY} MPI::MPI_CXX)
      set(GRANAGG_LAMMPS_TARGET granagg_lammps_api)
      set(granagg_lammps_inc ${LAMMPS_INCLUDE_DIR})
    else()
      if(GRANAGG_LAMMPS_ROOT)
        string(CONCAT granagg_lammps_missing "no LAMMPS in -DLAMMPS_DIR=${GRANAGG_LAMMPS_ROOT} "
               "(neither LAMMPSConfig.cmake nor lammps.h and liblammps below it)")
      else()
        set(granagg_lammps_missing
            "no LAMMPS library found (Debian: liblammps-dev; a site's LAMMPS: -DLAMMPS_DIR=...)")
      endif()
    endif()
  endif()
  if(GRANAGG_LAMMPS_TARGET)
    # LAMMPS's headers include fmt/format.h; Debian's liblammps-dev does not ship it
    # (md/lammps/FmtCompat.h): a LAMMPS install's own copy, or libfmt-dev's
    find_path(GRANAGG_FMT_INCLUDE_DIR fmt/format.h HINTS ${granagg_lammps_inc})
    if(NOT GRANAGG_FMT_INCLUDE_DIR)
      set(granagg_lammps_missing
          "LAMMPS's headers include fmt/format.h, which neither LAMMPS nor the system provides "
          "(Debian: libfmt-dev)")
      set(GRANAGG_LAMMPS_TARGET "")
    endif()
  endif()
endif()
if(ENABLE_CUDA AND GRANAGG_LAMMPS_TARGET)
  set(granagg_lammps_missing "not part of the CUDA build (configure a CPU build for it)")
  set(GRANAGG_LAMMPS_TARGET "")
endif()
if(GRANAGG_LAMMPS_TARGET)
  message(STATUS "granagg-lammps: built (LAMMPS library ${GRANAGG_LAMMPS_TARGET} "
                 "${LAMMPS_VERSION}, MPI ${MPI_CXX_VERSION})")
else()
  message(STATUS "granagg-lammps: not built: ${granagg_lammps_missing}")
endif()
