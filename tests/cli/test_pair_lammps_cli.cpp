// `granagg pair` with [md] engine = "lammps" from the command line: bad keys and launchers exit 2
// naming them, and --emit-batch slurm writes srun on nodes x tasks per node where granagg-lammps
// is built (else exit 2 saying when it is built). The runs themselves:
// tests/lammps/test_lammps_pair.cpp.
#include <catch2/catch.hpp>

#include <filesystem>
#include <string>

#include "RunCommand.h"
#include "TestUtil.h"

using granagg::test::slurp;
using granagg::test::spit;
using granagg::test::tempDir;

namespace fs = std::filesystem;

namespace {

/// A pair configuration on tiny's MD with `lines` appended.
fs::path pairFile(const fs::path& dir, const std::string& name, const std::string& lines) {
  spit(dir / name, "[pair]\nname = \"l\"\nK = [0.0]\nruns = 1\n[md]\npreset = \"quick\"\n" +
                       std::string("set = [\"system.N=500\", \"run.t_end=1\"]\n") + lines);
  return dir / name;
}

}  // namespace

TEST_CASE("pair on LAMMPS: an unknown engine, a bad count or launcher exit 2 naming the key",
          "[cli][pair]") {
  const fs::path dir = tempDir("pair_lammps_bad");
  const std::string out = " -q --out " + (dir / "o").string();
  struct Case {
    std::string file, lines, args, says;
  };
  for (const Case& c :
       {Case{"engine.toml", "engine = \"lamps\"\n", "",
             "md.engine = \"lamps\" is not known (allowed: \"granagg\", \"lammps\")"},
        Case{"ranks.toml", "engine = \"lammps\"\n[lammps]\nranks = 0\n", "",
             "lammps.ranks must lie in 1..1048576 (got 0)"},
        Case{"nodes.toml", "engine = \"lammps\"\n[lammps]\nnodes = 0\n", " --emit-batch slurm",
             "lammps.nodes must lie in"},
        Case{"quote.toml", "engine = \"lammps\"\n[lammps]\nlauncher = \"mpirun -np '2'\"\n", "",
             "lammps.launcher = \"mpirun -np '2'\""},
        Case{"given.toml", "engine = \"lammps\"\n", " --launcher \"\"", "--launcher is empty"},
        Case{"own.toml", "", " --launcher mpirun", "--launcher applies only to a study with"}}) {
    INFO(c.file);
    const Run r =
        runGranagg("pair --config " + pairFile(dir, c.file, c.lines).string() + c.args + out);
    INFO(r.output);
    CHECK(r.status == 2);
    CHECK_THAT(r.output, Catch::Contains(c.says));
  }
  CHECK_FALSE(fs::exists(dir / "o"));
  fs::remove_all(dir);
}

TEST_CASE(
    "pair on LAMMPS --emit-batch slurm: srun on nodes x tasks per node, or exit 2 where "
    "granagg-lammps is not built",
    "[cli][pair]") {
  const fs::path dir = tempDir("pair_lammps_slurm");
  const fs::path out = dir / "study";
  const fs::path cfg =
      pairFile(dir, "pair.toml", "engine = \"lammps\"\n[lammps]\nnodes = 3\ntasks_per_node = 16\n");
  const Run r =
      runGranagg("pair --config " + cfg.string() + " --emit-batch slurm --out " + out.string());
  INFO(r.output);
  const fs::path lammps = fs::path(GRANAGG_BINARY).parent_path() / "granagg-lammps";
  if (!fs::exists(lammps)) {  // this build has no LAMMPS
    CHECK(r.status == 2);
    CHECK_THAT(r.output, Catch::Contains(lammps.string() + " not found): it is built when "
                                                           "liblammps-dev"));
    CHECK_FALSE(fs::exists(out));
  } else {
    REQUIRE(r.status == 0);
    const std::string s = slurp(out / "batch.slurm");
    CHECK_THAT(s, Catch::Contains("#SBATCH --nodes=3\n"));
    CHECK_THAT(s, Catch::Contains("#SBATCH --ntasks-per-node=16\n"));
    CHECK_THAT(s, Catch::Contains("--launcher 'srun --nodes=3 --ntasks-per-node=16'"));
    CHECK_FALSE(fs::exists(out / "runs"));
  }
  fs::remove_all(dir);
}
