# Writes the version translation unit at build time, so that `granagg --version` names the
# commit the binary was built from (and says "-dirty" for uncommitted changes).
# Invoked by common/CMakeLists.txt as: cmake -DSRC=... -DIN=... -DOUT=... -DVERSION=... -P GitVersion.cmake
execute_process(COMMAND git -C "${SRC}" describe --always --dirty --abbrev=12
                OUTPUT_VARIABLE GRANAGG_GIT OUTPUT_STRIP_TRAILING_WHITESPACE
                RESULT_VARIABLE rc ERROR_QUIET)
if(NOT rc EQUAL 0 OR GRANAGG_GIT STREQUAL "")
  set(GRANAGG_GIT "unknown")
endif()
set(GRANAGG_VERSION "${VERSION}")
configure_file("${IN}" "${OUT}.tmp" @ONLY)
# copy only when changed: no rebuild of dependants when the commit did not change
execute_process(COMMAND ${CMAKE_COMMAND} -E copy_if_different "${OUT}.tmp" "${OUT}")
file(REMOVE "${OUT}.tmp")
