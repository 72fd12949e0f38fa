// `granagg md`: bad configurations, output folders, trajectory layout, restart bit for bit.
#include <catch2/catch.hpp>

#include "RunCommand.h"

#include <sys/wait.h>
#include <unistd.h>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>

#include "common/Csv.h"
#include "common/H5mdReader.h"
#include "md/io/InitialState.h"

#include "TestUtil.h"

using granagg::test::tempDir;

namespace fs = std::filesystem;

namespace {
std::string writeConfig(const fs::path& dir, const std::string& body) {
  fs::create_directories(dir);
  const fs::path p = dir / "run.toml";
  std::ofstream(p) << body;
  return p.string();
}
const char* SMALL = "[input]\nversion = 1\n[system]\nN = 300\nseed = 5\n[run]\nt_end = 1.0\n";
}  // namespace

TEST_CASE("md rejects bad configurations with a message naming the key, exit 2", "[cli][md]") {
  const fs::path dir = tempDir("bad");
  struct Case {
    std::string toml, says;
  };
  for (const Case& c : {Case{"[system]\nNn = 5\n", "Nn"}, Case{"[system]\nphi = 0.7\n", "phi"},
                        Case{"[system]\nN = 1\n", "N"}, Case{"[integrator]\ndt = -1\n", "dt"},
                        Case{"[contact]\nE = -3\n", "E"}, Case{"[bogus]\nx = 1\n", "bogus"}}) {
    INFO(c.toml);
    const std::string cfg = writeConfig(dir, c.toml);
    const Run r = runGranagg("md --config " + cfg + " --out " + (dir / "o").string() + " -q");
    CHECK(r.status == 2);
    CHECK_THAT(r.output, Catch::Contains(c.says));
  }
  const Run unknown =
      runGranagg("md --config " + writeConfig(dir, "[system]\nN = 100\nNn = 5\n") + " -q");
  CHECK_THAT(unknown.output, Catch::Contains("run.toml:3"));
  CHECK(runGranagg("md --preset nosuch -q").status == 2);
  CHECK(runGranagg("md --preset quick --config " + writeConfig(dir, SMALL) + " -q").status == 2);
  // neither --config nor --preset: the defaults, changed by --set
  const Run defaults = runGranagg("md --set system.N=50 --set run.t_end=0.01 --out " +
                                  (dir / "defaults").string() + " -q");
  CHECK(defaults.status == 0);
  CHECK(fs::exists(dir / "defaults" / "traj.h5"));
  // requests that used to overflow, hang or run the defaults: one line, exit 2, nothing written
  const std::string small = writeConfig(dir, SMALL);
  for (const Case& c :
       {Case{"--set run.t_end=1e300", "run.t_end"}, Case{"--set integrator.dt=1e-300", "run.t_end"},
        Case{"--set contact.E=1e300", "integrator.dt"},
        Case{"--set output.frame_interval=1e-12", "frame_interval"},
        Case{"--set output.frames_per_decade=1000000000", "frames_per_decade"}}) {
    INFO(c.toml);
    const Run r = runGranagg("md --config " + small + " " + c.toml + " --out " +
                             (dir / "o2").string() + " -q");
    CHECK(r.status == 2);
    CHECK_THAT(r.output, Catch::Contains(c.says));
    CHECK_FALSE(fs::exists(dir / "o2"));
  }
  const Run folder =
      runGranagg("md --config " + dir.string() + " --out " + (dir / "o3").string() + " -q");
  CHECK(folder.status == 2);
  CHECK_THAT(folder.output, Catch::Contains("is a directory"));
  fs::remove_all(dir);
}

TEST_CASE("md --seed takes 0 to 2^64 - 1 and refuses the rest, --threads 0 is refused",
          "[cli][md]") {
  const fs::path dir = tempDir("seeds");
  const std::string cfg = writeConfig(dir, SMALL) + " --set run.t_end=0.01";
  for (const char* bad : {"-1", "18446744073709551616", "1e3", "abc"}) {
    INFO(bad);
    const Run r = runGranagg("md --config " + cfg + " --seed " + bad + " --out " +
                             (dir / "bad").string() + " -q");
    CHECK(r.status == 2);
    CHECK_THAT(r.output, Catch::Contains("--seed"));
  }
  CHECK(runGranagg("md --config " + cfg + " --threads 0 --out " + (dir / "t").string() + " -q")
            .status == 2);
  CHECK_FALSE(fs::exists(dir / "bad"));
  // the two largest signed and unsigned 64-bit seeds are two different runs (the option used to
  // clamp the second to the first)
  for (const char* seed : {"9223372036854775807", "18446744073709551615"})
    REQUIRE(runGranagg("md --config " + cfg + " --seed " + seed + " --out " +
                       (dir / seed).string() + " -q")
                .status == 0);
  granagg::common::H5mdReader a((dir / "9223372036854775807" / "traj.h5").string()),
      b((dir / "18446744073709551615" / "traj.h5").string());
  CHECK(granagg::md::engineFrame(a.readFrame(0)).x != granagg::md::engineFrame(b.readFrame(0)).x);
  fs::remove_all(dir);
}

TEST_CASE("md writes a readable trajectory and refuses to overwrite it", "[cli][md]") {
  const fs::path dir = tempDir("run");
  const std::string cfg = writeConfig(dir, SMALL);
  const fs::path out = dir / "out";
  const Run r = runGranagg("md --config " + cfg + " --out " + out.string());
  INFO(r.output);
  REQUIRE(r.status == 0);
  CHECK_THAT(r.output, Catch::Contains("backend"));
  CHECK_THAT(r.output, Catch::Contains("dt = "));
  REQUIRE(fs::exists(out / "traj.h5"));
  REQUIRE(fs::exists(out / "checkpoint.h5"));
  granagg::common::H5mdReader reader((out / "traj.h5").string());
  CHECK(reader.size() == 300);
  CHECK(reader.frames() >= 3);
  const auto last = granagg::md::engineFrame(reader.readFrame(reader.frames() - 1));
  CHECK(last.time == Approx(1.0).margin(0.01));

  const Run again = runGranagg("md --config " + cfg + " --out " + out.string() + " -q");
  CHECK(again.status == 2);
  CHECK_THAT(again.output, Catch::Contains("--force"));
  // a file where the run's folder would go is named as such (--force would not help)
  for (const char* sub : {"md --config ", "analyze "}) {
    const std::string cmd = std::string(sub) + (sub[0] == 'm' ? cfg : out.string()) + " --out " +
                            (out / "traj.h5").string() + " --force -q";
    const Run file = runGranagg(cmd);
    INFO(cmd);
    CHECK(file.status == 2);
    CHECK_THAT(file.output, Catch::Contains("is a file, not a folder"));
  }
  if (fs::exists("/usr/bin/python3") && sh("/usr/bin/python3 -c 'import h5py'").status == 0) {
    const Run check = sh("/usr/bin/python3 " + std::string(GRANAGG_SOURCE_DIR) +
                         "/scripts/check_h5md.py " + (out / "traj.h5").string());
    INFO(check.output);
    CHECK(check.status == 0);
  } else {
    WARN("h5py not available: scripts/check_h5md.py not run");
  }
  fs::remove_all(dir);
}

TEST_CASE("MDAnalysis reads a granagg run with the README's recipe", "[cli][md][mdanalysis]") {
  // python3-mdanalysis is a Debian package and part of the set-up (scripts/setup.sh): a peer
  // reading our files is part of the contract, so its absence fails the test.
  const fs::path dir = tempDir("mda");
  const std::string cfg = writeConfig(dir, SMALL);
  REQUIRE(runGranagg("md --config " + cfg + " --set run.t_end=0.3 --out " + (dir / "o").string() +
                     " -q")
              .status == 0);
  const Run r = sh("/usr/bin/python3 " + std::string(GRANAGG_SOURCE_DIR) +
                   "/scripts/check_mdanalysis.py " + (dir / "o" / "traj.h5").string());
  INFO(r.output);
  CHECK(r.status == 0);
  CHECK_THAT(r.output, Catch::Contains("agree with the file"));
  fs::remove_all(dir);
}

TEST_CASE("md --restart continues bit for bit", "[cli][md]") {
  const fs::path dir = tempDir("restart");
  const std::string cfg = writeConfig(dir, SMALL);
  // uninterrupted to t = 1
  REQUIRE(runGranagg("md --config " + cfg + " --out " + (dir / "a").string() + " -q").status == 0);
  // interrupted at t = 0.5, then continued to t = 1
  REQUIRE(runGranagg("md --config " + cfg + " --set run.t_end=0.5 --out " + (dir / "b").string() +
                     " -q")
              .status == 0);
  const Run r = runGranagg("md --restart " + (dir / "b").string() + " --set run.t_end=1.0 -q");
  INFO(r.output);
  REQUIRE(r.status == 0);
  granagg::common::H5mdReader ra((dir / "a" / "traj.h5").string()),
      rb((dir / "b" / "traj.h5").string());
  const auto fa = granagg::md::engineFrame(ra.readFrame(ra.frames() - 1)),
             fb = granagg::md::engineFrame(rb.readFrame(rb.frames() - 1));
  CHECK(fa.step == fb.step);
  CHECK(fa.x == fb.x);
  CHECK(fa.y == fb.y);
  CHECK(fa.vz == fb.vz);
  CHECK(fa.ix == fb.ix);
  CHECK(runGranagg("md --restart " + (dir / "b").string() + " --set system.N=5 -q").status == 2);
  const Run out =
      runGranagg("md --restart " + (dir / "b").string() + " --out " + (dir / "c").string() + " -q");
  CHECK(out.status == 2);  // the run continues in its own folder: --out would be ignored
  CHECK_THAT(out.output, Catch::Contains("--out cannot be combined with --restart"));
  CHECK_FALSE(fs::exists(dir / "c"));
  fs::remove_all(dir);
}

TEST_CASE("md and analyze log on stderr and leave stdout empty", "[cli][md][log]") {
  // A log redirected to a file (`granagg md ... > run.log 2>&1 &`) must show progress as it
  // happens: stderr is unbuffered, stdout is block-buffered when redirected.
  const fs::path dir = tempDir("log");
  const std::string cfg = writeConfig(dir, SMALL);
  const std::string md = std::string(GRANAGG_BINARY) + " md --config " + cfg +
                         " --set run.t_end=0.2 --out " + (dir / "o").string() + " --force";
  const Run out = sh("{ " + md + " 2>/dev/null; }");  // stdout alone
  CHECK(out.status == 0);
  CHECK(out.output.empty());
  const Run err = sh("{ " + md + " >/dev/null; }");  // stderr alone
  CHECK(err.status == 0);
  CHECK_THAT(err.output, Catch::Contains("md: N = 300") && Catch::Contains("md: wrote"));
  const std::string an = std::string(GRANAGG_BINARY) + " analyze " + (dir / "o").string() +
                         " --out " + (dir / "a").string() + " --force";
  const Run a_out = sh("{ " + an + " 2>/dev/null; }");
  CHECK(a_out.status == 0);
  CHECK(a_out.output.empty());
  fs::remove_all(dir);
}

TEST_CASE(
    "md stops cleanly on SIGTERM with a checkpoint, and the restart ends where an "
    "uninterrupted run ends",
    "[cli][md][signal]") {
  const fs::path dir = tempDir("sigterm");
  // a charged gas (PPPM, the slow interval following the gas, charge exchange) long enough to be
  // caught mid-run: about 3000 steps of N = 300, a few seconds
  const std::string cfg =
      writeConfig(dir, std::string(SMALL) +
                           "[charging]\nmode = \"exchange\"\nQ = 0.1\n[coulomb]\nK = 1.0\n"
                           "[output]\ncheckpoint_wall_seconds = 0.0\n");
  const std::string t_end = " --set run.t_end=10";
  REQUIRE(
      runGranagg("md --config " + cfg + t_end + " --out " + (dir / "a").string() + " -q").status ==
      0);
  // SIGTERM once the run is under way (its trajectory exists), then wait for it
  const std::string b = (dir / "b").string();
  const Run r = sh(std::string(GRANAGG_BINARY) + " md --config " + cfg + t_end + " --out " + b +
                   " -q > " + b +
                   ".log 2>&1 & pid=$!; "
                   "while [ ! -f " +
                   b +
                   "/traj.h5 ]; do sleep 0.05; done; sleep 0.3; "
                   "kill -TERM $pid; wait $pid; echo \"status=$?\"; cat " +
                   b + ".log");
  INFO(r.output);
  CHECK_THAT(r.output, Catch::Contains("status=143"));  // 128 + SIGTERM, distinct from 0/1/2
  CHECK_THAT(r.output,
             Catch::Contains("SIGTERM at step") && Catch::Contains("granagg md --restart " + b));
  REQUIRE(fs::exists(dir / "b" / "checkpoint.h5"));
  const Run resumed = runGranagg("md --restart " + b + " -q");
  INFO(resumed.output);
  REQUIRE(resumed.status == 0);
  granagg::common::H5mdReader ra((dir / "a" / "traj.h5").string()), rb(b + "/traj.h5");
  const auto fa = granagg::md::engineFrame(ra.readFrame(ra.frames() - 1)),
             fb = granagg::md::engineFrame(rb.readFrame(rb.frames() - 1));
  CHECK(fa.step == fb.step);
  CHECK(granagg::test::sameBits(fa.x, fb.x));
  CHECK(granagg::test::sameBits(fa.vz, fb.vz));
  CHECK(granagg::test::sameBits(fa.charge, fb.charge));
  fs::remove_all(dir);
}

TEST_CASE("md stops at a deep overlap naming step and particles and keeps the last checkpoint",
          "[cli][md]") {
  const fs::path dir = tempDir("abort");
  // max_overlap = 0.03 is reached by any impact faster than ~0.5 (xi_max ~ (5 v^2/(8E))^{2/5}):
  // the guard must fire within t = 1, after at least one step-based checkpoint
  const std::string cfg = writeConfig(
      dir,
      std::string(SMALL) +
          "max_overlap = 0.03\n[output]\ncheckpoint_interval = 5\ncheckpoint_wall_seconds = 0.0\n");
  const Run r = runGranagg("md --config " + cfg + " --out " + (dir / "o").string() + " -q");
  INFO(r.output);
  CHECK(r.status == 1);
  CHECK_THAT(r.output, Catch::Contains("overlap beyond run.max_overlap"));
  CHECK_THAT(r.output, Catch::Contains("step "));
  CHECK_THAT(r.output, Catch::Contains("particle"));
  CHECK_THAT(r.output, Catch::Contains("last good checkpoint"));
  CHECK(fs::exists(dir / "o" / "checkpoint.h5"));
  fs::remove_all(dir);
}

TEST_CASE("md --restart continues bit for bit with charging and PPPM, and writes forces on request",
          "[cli][md]") {
  const fs::path dir = tempDir("restart_charged");
  const std::string cfg =
      writeConfig(dir, std::string(SMALL) +
                           "[charging]\nmode = \"exchange\"\nQ = 0.1\n[coulomb]\nK = 1.0\n"
                           "[output]\nwrite_forces = true\n");
  REQUIRE(runGranagg("md --config " + cfg + " --out " + (dir / "a").string() + " -q").status == 0);
  REQUIRE(runGranagg("md --config " + cfg + " --set run.t_end=0.5 --out " + (dir / "b").string() +
                     " -q")
              .status == 0);
  const Run r = runGranagg("md --restart " + (dir / "b").string() + " --set run.t_end=1.0 -q");
  INFO(r.output);
  REQUIRE(r.status == 0);
  granagg::common::H5mdReader ra((dir / "a" / "traj.h5").string()),
      rb((dir / "b" / "traj.h5").string());
  const auto fa = granagg::md::engineFrame(ra.readFrame(ra.frames() - 1)),
             fb = granagg::md::engineFrame(rb.readFrame(rb.frames() - 1));
  CHECK(fa.step == fb.step);
  CHECK(fa.x == fb.x);
  CHECK(fa.vz == fb.vz);
  CHECK(fa.charge == fb.charge);
  double q_abs = 0.0;
  for (double q : fa.charge) q_abs += std::abs(q);
  CHECK(q_abs > 0.0);  // charges were exchanged (and compared above)
  // per-particle forces in every frame, summing to zero (Newton's third law, mesh part included)
  if (fs::exists("/usr/bin/python3") && sh("/usr/bin/python3 -c 'import h5py'").status == 0) {
    const Run check =
        sh("/usr/bin/python3 -c \"import h5py, numpy as np; f = h5py.File('" +
           (dir / "a" / "traj.h5").string() +
           "', 'r'); F = f['particles/all/force/value'][:]; P = f['particles/all/position/value']; "
           "assert F.shape == P.shape, (F.shape, P.shape); "
           "s = np.abs(F.sum(axis=1)).max() / max(np.abs(F).max(), 1e-300); assert s < 1e-9, s; "
           "assert np.abs(F[-1]).max() > 0; print('forces ok')\"");
    INFO(check.output);
    CHECK(check.status == 0);
  }
  fs::remove_all(dir);
}

TEST_CASE("md --threads sets the OpenMP thread count", "[cli][md]") {
  // The OpenMP runtime reads OMP_NUM_THREADS once at start-up: the option must set the count
  // through the runtime (an environment variable set later would be ignored).
  const fs::path dir = tempDir("threads");
  const std::string cfg = writeConfig(dir, SMALL);
  const Run r = runGranagg("md --config " + cfg + " --set run.t_end=0.05 --threads 1 --out " +
                           (dir / "a").string());
  INFO(r.output);
  REQUIRE(r.status == 0);
  if (r.output.find("OpenMP backend") != std::string::npos)
    CHECK_THAT(r.output, Catch::Contains("1 thread(s)"));
  fs::remove_all(dir);
}

TEST_CASE("md --profile writes the phases, counts and Coulomb set-up to profile.csv", "[cli][md]") {
  // profile.csv is what benchmark scripts read (scripts/bench_*.sh): the step count, the time by
  // phase adding up to the loop, and the set-up the log states for people.
  const fs::path dir = tempDir("profile");
  const std::string cfg = writeConfig(
      dir, std::string(SMALL) + "[charging]\nmode = \"exchange\"\nQ = 0.1\n[coulomb]\nK = 1.0\n");
  const Run r = runGranagg("md --config " + cfg + " --set run.t_end=0.3 --profile --out " +
                           (dir / "a").string());
  INFO(r.output);
  REQUIRE(r.status == 0);
  const granagg::common::CsvTable t =
      granagg::common::readCsv((dir / "a" / "profile.csv").string());
  REQUIRE(t.rows.size() == 1);
  const auto& row = t.rows[0];
  CHECK(row[t.column("steps")] > 0);
  double phases = 0.0;
  for (std::size_t c = 0; c < t.columns.size(); ++c)
    if (t.columns[c] != "loop_s" && t.columns[c].size() > 2 &&
        t.columns[c].compare(t.columns[c].size() - 2, 2, "_s") == 0)
      phases += row[c];
  CHECK(phases == Approx(row[t.column("loop_s")]).epsilon(1e-9));  // other_s closes the sum
  CHECK(row[t.column("neighbor_builds")] >= 1);
  CHECK(row[t.column("slow_evaluations")] >= 1);
  std::map<std::string, std::string> meta(t.meta.begin(), t.meta.end());
  CHECK(meta["coulomb_method"] == "pppm");
  CHECK(std::stod(meta["coulomb_alpha"]) > 0);
  CHECK(std::stoi(meta["coulomb_mesh"]) >= 8);
  // the log's line says the same (the log is for people, the table for scripts)
  CHECK_THAT(r.output, Catch::Contains("mesh " + meta["coulomb_mesh"] + "^3"));
  CHECK(std::stod(meta["t_end"]) == Approx(0.3).margin(0.01));
  fs::remove_all(dir);
}
