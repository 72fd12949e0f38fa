// `granagg pair`: bad inputs (exit 2 naming the option), --emit-batch slurm, and an end-to-end
// study on the tiny preset (data/pair/tiny.toml: N = 500, 2 runs each of K = 0 and K = 5) that
// must produce every table, every figure file, report.html and summary.json, then resume after
// an interruption without redoing finished runs.
#include <catch2/catch.hpp>

#include "RunCommand.h"

#include <unistd.h>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "TestUtil.h"

using granagg::test::slurp;
using granagg::test::tempDir;

namespace fs = std::filesystem;

namespace {}  // namespace

TEST_CASE("pair rejects bad input with exit status 2 and a message naming it", "[cli][pair]") {
  const fs::path dir = tempDir("bad");
  const fs::path cfg = dir / "bad.toml";
  std::ofstream(cfg)
      << "[input]\nversion = 1\n[pair]\nK = [0.0]\nrunz = 2\n[md]\npreset = \"quick\"\n";
  const fs::path nomd = dir / "nomd.toml";
  std::ofstream(nomd) << "[pair]\nK = [0.0]\n";
  const std::string out = " --out " + (dir / "o").string();
  struct Case {
    std::string args, says;
  };
  for (const Case& c :
       {Case{"pair --preset nosuch" + out, "nosuch"},
        Case{"pair --preset tiny --runs 0" + out, "--runs"},
        Case{"pair --preset tiny --K -1" + out, "--K"},
        Case{"pair --preset tiny --K 0,abc" + out, "--K"},
        Case{"pair --preset tiny --K 5,5" + out, "twice"},
        Case{"pair --preset tiny --jobs -2" + out, "--jobs"},
        // bounds (issue 17): these used to run out of memory, write a 2e5-task Slurm array,
        // fall back to a default or start the whole study from a batch task
        Case{"pair --preset tiny --runs 1000000000 --emit-batch slurm" + out, "--runs"},
        Case{"pair --preset tiny --runs 100000 --emit-batch slurm" + out, "--runs"},
        Case{"pair --preset tiny --jobs 0" + out, "--jobs"},
        Case{"pair --preset tiny --threads 0" + out, "--threads"},
        Case{"pair --preset tiny --K \"\"" + out, "--K"},
        Case{"pair --preset tiny --run-index -1" + out, "--run-index"},
        Case{"pair --preset tiny --emit-batch pbs" + out, "--emit-batch"},
        Case{"pair" + out, "--preset"},
        Case{"pair --preset tiny --config " + cfg.string() + out, "--preset"},
        Case{"pair --config " + cfg.string() + out, "runz"},
        Case{"pair --config " + nomd.string() + out, "[md]"},
        Case{"pair --config " + (dir / "missing.toml").string() + out, "missing.toml"}}) {
    INFO(c.args);
    const Run r = runGranagg(c.args + " -q");
    CHECK(r.status == 2);
    CHECK_THAT(r.output, Catch::Contains(c.says));
  }
  CHECK_FALSE(fs::exists(dir / "o" / "runs"));
  // A folder that holds something else is not taken over.
  fs::create_directories(dir / "other");
  std::ofstream(dir / "other" / "mine.txt") << "x\n";
  const Run r = runGranagg("pair --preset tiny -q --out " + (dir / "other").string());
  CHECK(r.status == 2);
  CHECK_THAT(r.output, Catch::Contains("--force"));
  fs::remove_all(dir);
}

TEST_CASE("pair --emit-batch slurm writes a job-array script and runs nothing", "[cli][pair]") {
  const fs::path dir = tempDir("slurm");
  const fs::path out = dir / "study";
  const Run r = runGranagg("pair --preset tiny --runs 3 --emit-batch slurm --out " + out.string());
  INFO(r.output);
  REQUIRE(r.status == 0);
  const std::string s = slurp(out / "batch.slurm");
  CHECK_THAT(s, Catch::Contains("#SBATCH --array=0-5"));   // 2 values of K x 3 runs
  CHECK_THAT(s, Catch::Contains("--run-index"));           // each task runs one run
  CHECK_THAT(s, Catch::Contains("--dependency=afterok"));  // then the follow-up job
  CHECK_THAT(s, Catch::Contains((out / "config" / "pair.toml").string()));
  CHECK(fs::exists(out / "config" / "md_K0.toml"));
  CHECK(fs::exists(out / "config" / "md_K5.toml"));
  CHECK_FALSE(fs::exists(out / "runs"));
  // The resolved configuration reads back (what resume and the batch tasks use).
  const Run again = runGranagg("pair --config " + (out / "config" / "pair.toml").string() +
                               " --emit-batch slurm -q --out " + out.string());
  INFO(again.output);
  CHECK(again.status == 0);
  fs::remove_all(dir);
}

TEST_CASE("pair on the tiny preset makes every output and resumes without redoing finished runs",
          "[cli][pair][slow]") {
  const fs::path dir = tempDir("e2e");
  const fs::path out = dir / "study";
  const std::string cmd = "pair --preset tiny --jobs 2 --out " + out.string();
  const Run r = runGranagg(cmd);
  INFO(r.output);
  INFO(slurp(out / "pair.log"));
  REQUIRE(r.status == 0);

  for (const char* k : {"K0", "K5"}) {
    for (int run = 0; run < 2; ++run) {
      const fs::path rd = out / "runs" / k / ("run" + std::to_string(run));
      CHECK(fs::exists(rd / "traj.h5"));
      CHECK(fs::exists(rd / "done.json"));
      // analysed while it ran: its tables, and no particle frame stored (--keep-trajectories)
      CHECK(fs::exists(rd / "analysis" / "S_t.csv"));
      CHECK(fs::file_size(rd / "traj.h5") < 2u * 1024u * 1024u);
    }
    for (const char* t : {"S_t", "N_s_grid", "N_s_particle", "fisher", "thermo", "msd",
                          "speed_dist", "nstick", "fits"})
      CHECK(fs::exists(out / "analysis" / k / (std::string(t) + ".csv")));
    CHECK(fs::exists(out / "analysis" / k / "per_run" / "charge_speed.csv"));
    CHECK(fs::exists(out / "analysis" / k / "analysis.h5"));
  }
  for (const char* t : {"S_beta2.csv", "S_beta3.csv", "zbeta.csv", "cooling.csv", "charging.csv"})
    CHECK(fs::exists(out / "meanfield" / t));
  for (const char* f : {"fig1_temperature", "fig2_snapshots", "fig3_nstick", "fig4_charge",
                        "fig5_growth", "fig6_meanfield", "fig7_speed", "fig8_charge_speed"}) {
    CHECK(fs::exists(out / "figures" / (std::string(f) + ".png")));
    CHECK(fs::exists(out / "figures" / (std::string(f) + ".pdf")));
  }
  const std::string report = slurp(out / "report.html");
  CHECK_THAT(report, Catch::Contains("data:image/png;base64,"));
  CHECK_THAT(report, Catch::Contains("granagg md --config"));
  const std::string summary = slurp(out / "summary.json");
  for (const char* key :
       {"\"z_analyze\"", "\"beta_fit\"", "\"z_neutral\": 1.21", "\"z_charged\": 1.49",
        "\"z_meanfield_beta2\": 1.19", "\"timings_s\"", "\"commands\"", "\"K\": 5"})
    CHECK_THAT(summary, Catch::Contains(key));
  // fit-beta either fitted (its outputs are there) or said why these data allow no fit.
  if (!fs::exists(out / "fit" / "K0" / "fit_beta.json"))
    CHECK_THAT(summary, Catch::Contains("fit"));
  CHECK_THAT(r.output, Catch::Contains("paper: 1.21 +- 0.04"));

  // Interrupt: one run lost its completion marker (killed after the last checkpoint), another
  // run's folder is gone (killed before anything was written).
  const auto mtime = [&](const char* k, int run) {
    return fs::last_write_time(out / "runs" / k / ("run" + std::to_string(run)) / "traj.h5");
  };
  const auto t_k0r0 = mtime("K0", 0), t_k5r0 = mtime("K5", 0);
  fs::remove(out / "runs" / "K0" / "run1" / "done.json");
  fs::remove_all(out / "runs" / "K5" / "run1");
  const std::size_t log_before = slurp(out / "pair.log").size();
  const Run again = runGranagg(cmd + " --no-figures");
  INFO(again.output);
  const std::string log = slurp(out / "pair.log").substr(log_before);
  INFO(log);
  REQUIRE(again.status == 0);
  CHECK_THAT(again.output, Catch::Contains("md: 2 of 4 runs to do (2 finished already)"));
  CHECK_THAT(log, Catch::Contains("md K0 run 0: finished already, skipped"));
  CHECK_THAT(log, Catch::Contains("md K5 run 0: finished already, skipped"));
  CHECK_THAT(log, Catch::Contains("md K0 run 1: restarting from its checkpoint"));
  CHECK_THAT(log, Catch::Contains("md K5 run 1: started"));
  CHECK(mtime("K0", 0) == t_k0r0);  // finished runs untouched
  CHECK(mtime("K5", 0) == t_k5r0);
  CHECK(fs::exists(out / "runs" / "K0" / "run1" / "done.json"));
  CHECK(fs::exists(out / "runs" / "K5" / "run1" / "done.json"));

  // Nothing left to do: no MD, no analysis.
  const std::size_t log_before3 = slurp(out / "pair.log").size();
  const Run third = runGranagg(cmd + " --no-figures -q");
  REQUIRE(third.status == 0);
  const std::string log3 = slurp(out / "pair.log").substr(log_before3);
  INFO(log3);
  CHECK_THAT(log3, Catch::Contains("md: all 4 runs finished already"));
  CHECK_THAT(log3, Catch::Contains("analysis K0: up to date, skipped"));
  CHECK(third.output.empty());
  fs::remove_all(dir);
}
