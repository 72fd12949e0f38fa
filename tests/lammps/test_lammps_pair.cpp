// `granagg pair` with [md] engine = "lammps" (docs/pair.md): a small study whose runs are made by
// granagg-lammps on 2 MPI ranks, analysed from their traj.h5 like granagg md runs, and resumed
// with granagg-lammps --restart.
#include <catch2/catch.hpp>

#include <unistd.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "TestUtil.h"
#include "cli/RunCommand.h"

using namespace granagg;
namespace fs = std::filesystem;

TEST_CASE("pair with engine = lammps runs its MD through granagg-lammps, analyses it and resumes",
          "[lammps][mpi][pair][slow]") {
  const fs::path dir = test::tempDir("lammps_pair");
  const fs::path out = dir / "study";
  // Open MPI refuses root unless told, and 2 ranks may exceed this machine's cores
  std::string launcher = std::string(GRANAGG_MPIEXEC) + " --oversubscribe -np {ranks}";
  if (::geteuid() == 0) launcher += " --allow-run-as-root";
  // tiny's systems, one run per K, a small mean field: well under a minute on 2 cores
  test::spit(dir / "pair.toml",
             "[pair]\nname = \"lammps-tiny\"\nK = [0.0, 5.0]\nruns = 1\n"
             "[md]\npreset = \"quick\"\nengine = \"lammps\"\n"
             "set = [\"system.N=500\", \"run.t_end=5\", \"output.frames_per_decade=8\"]\n"
             "[charged]\nQ = 0.05\nset = [\"run.t_end=0.5\"]\n"
             "[meanfield]\nbeta = [2.0]\ns_end = 1e4\nzbeta_min = 2.0\nzbeta_max = 3.0\n"
             "zbeta_count = 2\n"
             "[lammps]\nlauncher = \"" +
                 launcher + "\"\nranks = 2\n");
  const std::string cmd = std::string(GRANAGG_BINARY) + " pair --config " +
                          (dir / "pair.toml").string() + " --no-figures --out " + out.string();
  const Run r = sh("OMP_NUM_THREADS=1 " + cmd);
  INFO(r.output);
  INFO(test::slurp(out / "pair.log"));
  REQUIRE(r.status == 0);
  for (const char* k : {"K0", "K5"}) {
    const fs::path run = out / "runs" / k / "run0";
    INFO(run);
    // made by granagg-lammps: its generated input and LAMMPS's log are there
    CHECK(fs::exists(run / "lammps.in"));
    CHECK(fs::exists(run / "log.lammps"));
    CHECK(fs::exists(run / "checkpoint.toml"));
    CHECK(fs::exists(run / "traj.h5"));
    const auto done = nlohmann::json::parse(test::slurp(run / "done.json"));
    CHECK_THAT(done.at("spec").get<std::string>(), Catch::EndsWith(" engine=lammps"));
    // granagg analyze read the run's trajectory as it reads granagg md's
    CHECK(fs::exists(out / "analysis" / k / "S_t.csv"));
    CHECK(fs::exists(out / "analysis" / k / "thermo.csv"));
  }
  CHECK_THAT(test::slurp(out / "runs" / "K5" / "run0" / "lammps.in"),
             Catch::Contains("kspace_style pppm"));
  const std::string commands = test::slurp(out / "commands.txt");
  CHECK_THAT(commands, Catch::Contains(" -np 2 ") && Catch::Contains("/granagg-lammps --config ") &&
                           Catch::Contains("--set system.seed=1 "));
  CHECK_THAT(test::slurp(out / "summary.json"), Catch::Contains("LAMMPS through granagg-lammps"));
  CHECK(fs::exists(out / "meanfield" / "S_beta2.csv"));

  // interrupted after its last checkpoint: the run continues with granagg-lammps --restart (at
  // its end already: nothing to run) and is not redone
  const fs::path k0 = out / "runs" / "K0" / "run0";
  const auto traj_time = fs::last_write_time(k0 / "traj.h5");
  fs::remove(k0 / "done.json");
  const std::size_t before = test::slurp(out / "pair.log").size();
  const Run again = sh("OMP_NUM_THREADS=1 " + cmd + " -q");
  const std::string log = test::slurp(out / "pair.log").substr(before);
  INFO(again.output);
  INFO(log);
  REQUIRE(again.status == 0);
  CHECK_THAT(log, Catch::Contains("md K0 run 0: restarting from its checkpoint"));
  CHECK_THAT(log, Catch::Contains("md K5 run 0: finished already, skipped"));
  CHECK_THAT(test::slurp(out / "logs" / "md-K0-run0.log"),
             Catch::Contains("/granagg-lammps --restart " + k0.string() + " --force -q"));
  CHECK(fs::exists(k0 / "done.json"));
  CHECK(fs::last_write_time(k0 / "traj.h5") == traj_time);

  // a key LAMMPS cannot honour: the run fails at once and the study names the key (not the
  // report mpirun appends after granagg-lammps's own line)
  test::spit(dir / "bad.toml",
             "[pair]\nname = \"bad\"\nK = [5.0]\nruns = 1\n"
             "[md]\npreset = \"quick\"\nengine = \"lammps\"\n"
             "set = [\"system.N=500\", \"coulomb.every_max=8\"]\n"
             "[lammps]\nlauncher = \"" +
                 launcher + "\"\n");
  const Run bad = sh("OMP_NUM_THREADS=1 " + std::string(GRANAGG_BINARY) + " pair --config " +
                     (dir / "bad.toml").string() + " --no-figures --out " + (dir / "bad").string());
  INFO(bad.output);
  CHECK(bad.status == 1);
  CHECK_THAT(test::slurp(dir / "bad" / "pair.log"),
             Catch::Contains("md K5 run 0: FAILED (exit status 2): granagg-lammps: "
                             "coulomb.every_max = 8 cannot run on LAMMPS"));
  fs::remove_all(dir);
}
