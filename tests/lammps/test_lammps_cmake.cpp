// Building against a site's LAMMPS (docs/lammps.md, "A site's LAMMPS"): CMake configured with
// -DLAMMPS_DIR naming an install prefix, or a source tree with src/lammps.h and a built
// liblammps, uses that LAMMPS and no other, also where the system has one (Debian's here).
// Configure only (no build): the LAMMPS are stand-ins that CMake can find but not link.
#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <regex>
#include <string>

#include "TestUtil.h"
#include "cli/RunCommand.h"

namespace fs = std::filesystem;
using granagg::test::slurp;
using granagg::test::spit;

namespace {

/// The value of `key` in a CMake cache ("" if absent).
std::string cacheValue(const fs::path& build, const std::string& key) {
  std::smatch m;
  const std::string cache = slurp(build / "CMakeCache.txt");
  return std::regex_search(cache, m, std::regex("\n" + key + ":[A-Z]+=([^\n]*)")) ? m.str(1) : "";
}

/// granagg configured into `build` with -DLAMMPS_DIR=`lammps`; the configure output.
Run configure(const fs::path& build, const fs::path& lammps) {
  return sh("cmake -S " + std::string(GRANAGG_SOURCE_DIR) + " -B " + build.string() +
            " -DBUILD_TESTING=OFF -DLAMMPS_DIR=" + lammps.string());
}

}  // namespace

TEST_CASE("CMake uses the LAMMPS named by -DLAMMPS_DIR: an install prefix or a source tree",
          "[lammps][cmake][slow]") {
  const fs::path dir = granagg::test::tempDir("lammps_cmake");
  {  // an install prefix: <prefix>/lib/cmake/LAMMPS/LAMMPSConfig.cmake, of a version of its own
    const fs::path config = dir / "prefix" / "lib" / "cmake" / "LAMMPS";
    fs::create_directories(config);
    fs::create_directories(dir / "prefix" / "include" / "lammps");
    spit(config / "LAMMPSConfig.cmake",
         "add_library(LAMMPS::lammps INTERFACE IMPORTED)\n"
         "set_target_properties(LAMMPS::lammps PROPERTIES INTERFACE_INCLUDE_DIRECTORIES\n"
         "  \"${CMAKE_CURRENT_LIST_DIR}/../../../include/lammps\")\n");
    spit(config / "LAMMPSConfigVersion.cmake",
         "set(PACKAGE_VERSION 20991231)\nset(PACKAGE_VERSION_COMPATIBLE TRUE)\n");
    const fs::path build = dir / "build-prefix";
    const Run r = configure(build, dir / "prefix");
    INFO(r.output);
    REQUIRE(r.status == 0);
    CHECK_THAT(r.output, Catch::Contains("granagg-lammps: built (LAMMPS library LAMMPS::lammps "
                                         "20991231"));
    CHECK(fs::equivalent(cacheValue(build, "LAMMPS_DIR"), config));
  }
  {  // a source tree: src/lammps.h and the library that LAMMPS's make builds there
    fs::create_directories(dir / "tree" / "src");
    spit(dir / "tree" / "src" / "lammps.h", "");
    spit(dir / "tree" / "src" / "liblammps_mpi.so", "");
    const fs::path build = dir / "build-tree";
    const Run r = configure(build, dir / "tree");
    INFO(r.output);
    REQUIRE(r.status == 0);
    CHECK_THAT(r.output,
               Catch::Contains("granagg-lammps: built (LAMMPS library granagg_lammps_api"));
    CHECK(cacheValue(build, "LAMMPS_INCLUDE_DIR") == (dir / "tree" / "src").string());
    CHECK(cacheValue(build, "LAMMPS_LIBRARY") ==
          (dir / "tree" / "src" / "liblammps_mpi.so").string());
    // configured again (find_package has set LAMMPS_DIR to LAMMPS_DIR-NOTFOUND): the same tree
    const Run again = sh("cmake " + build.string());
    INFO(again.output);
    CHECK_THAT(again.output, Catch::Contains("LAMMPS library granagg_lammps_api"));
    CHECK(cacheValue(build, "GRANAGG_LAMMPS_ROOT") == (dir / "tree").string());
  }
  {  // a folder with neither: not built, and CMake names the folder
    fs::create_directories(dir / "empty");
    const Run r = configure(dir / "build-empty", dir / "empty");
    INFO(r.output);
    CHECK(r.status == 0);  // the rest of granagg still builds
    CHECK_THAT(r.output, Catch::Contains("granagg-lammps: not built: no LAMMPS in -DLAMMPS_DIR=" +
                                         (dir / "empty").string()));
  }
  fs::remove_all(dir);
}
