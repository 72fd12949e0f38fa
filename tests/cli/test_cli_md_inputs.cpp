// `granagg md` inputs through the command line: a file-given initial state sets N and phi (and a
// contradicting system.N or system.phi is bad input, exit 2, nothing written); a system.N beyond
// the machine's memory is refused before anything is allocated; one recommended charge scale
// (Q = 0.05 at K = 5) in the abort message, the README and the presets; what a failed run keeps.
#include <catch2/catch.hpp>

#include "RunCommand.h"

#include <filesystem>
#include <fstream>
#include <regex>
#include <string>

#include "common/H5mdReader.h"

#include "TestUtil.h"

using granagg::test::slurp;
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

TEST_CASE("md from a LAMMPS data file logs the file's N and phi, contradictions exit 2",
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

TEST_CASE("md refuses a system.N beyond the machine's memory, naming the estimate, exit 2",
          "[cli][md]") {
  const fs::path dir = tempDir("md_inputs_memory");
  // 2e9 particles need at least 1 TB: more than any machine the tests run on
  const Run r = runGranagg("md --set system.N=2000000000 -q --out " + (dir / "big").string());
  CHECK(r.status == 2);
  CHECK_THAT(r.output, Catch::Contains("system.N = 2000000000 needs about 1 TB of memory") &&
                           Catch::Contains("more than this machine's") &&
                           Catch::Contains("lower system.N"));
  CHECK_FALSE(fs::exists(dir / "big"));
  fs::remove_all(dir);
}

TEST_CASE("a charged run that collapses names the recommended charge scale and keeps its folder",
          "[cli][md]") {
  const fs::path dir = tempDir("md_inputs_charge_scale");
  const std::string md =
      "md --preset quick --set coulomb.K=5 --set system.N=500 --set run.t_end=1 -q --out ";
  // the default Q = 1 at K = 5: an oppositely charged pair collapses within a few dozen steps
  const Run collapsed = runGranagg(md + (dir / "q1").string());
  INFO(collapsed.output);
  CHECK(collapsed.status == 1);
  CHECK_THAT(collapsed.output, Catch::Contains("lower charging.Q (here 1; recommended: 0.05 at "
                                               "K = 5") &&
                                   Catch::Contains("--set charging.Q=0.05)"));
  // what a run that fails part-way keeps (README, "Errors"): its folder and the trajectory up to
  // its last frame
  REQUIRE(fs::exists(dir / "q1" / "traj.h5"));
  CHECK(granagg::common::H5mdReader((dir / "q1" / "traj.h5").string()).frames() >= 1);
  // the recommended value runs
  const Run stable = runGranagg(md + (dir / "q005").string() + " --set charging.Q=0.05");
  CHECK(stable.status == 0);
  // at another K the same K Q^2
  const Run k1 = runGranagg("md --preset quick --set coulomb.K=1 --set system.N=500 "
                            "--set run.t_end=1 -q --out " + (dir / "k1").string());
  CHECK(k1.status == 1);
  CHECK_THAT(k1.output, Catch::Contains("so 0.11 at K = 1, the same K Q^2: --set charging.Q=0.11"));
  fs::remove_all(dir);
}

TEST_CASE("README, presets and docs give one charge scale for K = 5 and say what runs leave",
          "[cli][md]") {
  const std::string root = GRANAGG_SOURCE_DIR;
  const std::string readme = slurp(root + "/README.md");
  // every charging.Q the README sets is the recommended 0.05
  const std::regex set_q("charging\\.Q=([0-9.e-]+)");
  int seen = 0;
  for (auto it = std::sregex_iterator(readme.begin(), readme.end(), set_q);
       it != std::sregex_iterator(); ++it, ++seen)
    CHECK((*it)[1].str() == "0.05");
  CHECK(seen >= 1);
  // the pair presets' charged runs
  for (const char* preset : {"tiny", "quick", "paper"}) {
    INFO(preset);
    CHECK_THAT(slurp(root + "/data/pair/" + preset + ".toml"), Catch::Contains("\nQ = 0.05 "));
  }
  // the md presets (K = 0, Q = 1) say what to use with K = 5; docs/config.md says it too
  for (const char* preset : {"quick", "paper"}) {
    INFO(preset);
    CHECK_THAT(slurp(root + "/data/presets/" + preset + ".toml"),
               Catch::Contains("coulomb.K = 5 use\n") && Catch::Contains("# Q = 0.05"));
  }
  CHECK_THAT(slurp(root + "/docs/config.md"), Catch::Contains("**With K = 5, use Q = 0.05**"));
  // the md presets' usage lines write folders, and say so
  for (const char* preset : {"quick", "paper", "haff"}) {
    INFO(preset);
    const std::string text = slurp(root + "/data/presets/" + preset + ".toml");
    CHECK_FALSE(std::regex_search(text, std::regex("--out [^ \n]*\\.h5")));
    CHECK_THAT(text, Catch::Contains("# writes the folder runs/"));
  }
  // a failed run keeps its folder: the README says so instead of "no output folder"
  CHECK_THAT(readme, !Catch::Contains("and no output folder it created"));
  CHECK_THAT(readme, Catch::Contains("an MD run that fails part-way keeps its folder"));
}
