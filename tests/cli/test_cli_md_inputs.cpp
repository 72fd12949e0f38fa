// `granagg md` inputs through the command line: a file-given initial state sets N and phi (and a
// contradicting system.N or system.phi is bad input, exit 2, nothing written).
#include <catch2/catch.hpp>

#include "RunCommand.h"

#include <filesystem>
#include <fstream>
#include <string>

#include "TestUtil.h"

using granagg::test::tempDir;

namespace fs = std::filesystem;

namespace {

/// Four atoms in a LAMMPS data file's box of edge 10: phi = 4 pi / 6000 = 0.0020944.
const char* FOUR_ATOMS =
    "LAMMPS data file: 4 atoms\n\n4 atoms\n1 atom types\n\n"
    "0 10 xlo xhi\n0 10 ylo yhi\n0 10 zlo zhi\n\nMasses\n\n1 1.0\n\nAtoms # atomic\n\n"
    "1 1 1.0 1.0 1.0\n2 1 3.0 1.0 1.0\n3 1 5.0 5.0 5.0\n4 1 8.0 2.0 7.0\n\n"
    "Velocities\n\n1 0.5 0 0\n2 -0.5 0 0\n3 0 0.3 0\n4 0 0 -0.3\n";

}  // namespace

TEST_CASE("md from a LAMMPS data file logs the file's N and phi; contradictions exit 2",
          "[cli][md]") {
  const fs::path dir = tempDir("md_inputs_lammps");
  const std::string data = (dir / "four.data").string();
  std::ofstream(data) << FOUR_ATOMS;
  const std::string md = "md --set system.initial=" + data + " --set run.t_end=0.05 --out ";
  const Run ok = runGranagg(md + (dir / "ok").string());
  INFO(ok.output);
  CHECK(ok.status == 0);
  CHECK_THAT(ok.output, Catch::Contains("md: N = 4, phi = 0.0020944, box L = 10,"));

  const Run n = runGranagg(md + (dir / "n").string() + " --set system.N=1000");
  CHECK(n.status == 2);
  CHECK_THAT(n.output, Catch::Contains("system.N = 1000 (--set system.N=1000) contradicts") &&
                           Catch::Contains("holds 4 particles"));
  CHECK_FALSE(fs::exists(dir / "n"));
  const Run phi = runGranagg(md + (dir / "phi").string() + " --set system.phi=0.076");
  CHECK(phi.status == 2);
  CHECK_THAT(phi.output, Catch::Contains("system.phi = 0.076 (--set system.phi=0.076)") &&
                             Catch::Contains("phi = 0.0020943951"));
  CHECK_FALSE(fs::exists(dir / "phi"));
  fs::remove_all(dir);
}
