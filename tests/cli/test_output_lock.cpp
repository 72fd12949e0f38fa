// Output folders in use: md, analyze, fit-beta and pair refuse a folder another process holds
// (exit 2, naming it, touching nothing), a trajectory damaged behind a run's back fails the run,
// stale locks need --force, and md's end-of-run messages say what happened.
#include <catch2/catch.hpp>

#include "RunCommand.h"

#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "common/FolderLock.h"
#include "TestUtil.h"

using granagg::common::FolderLock;
using granagg::test::slurp;
using granagg::test::tempDir;
namespace fs = std::filesystem;

namespace {

const std::string SMALL_RUN = "md --preset quick --set system.N=300 --set run.t_end=1 -q ";

std::string ownPid() { return "in use by pid " + std::to_string(::getpid()); }

/// A CSV S(t) that fit-beta accepts: S = t^1.2 on a log grid.
std::string growthCsv(const fs::path& dir) {
  const fs::path p = dir / "S.csv";
  std::ofstream f(p);
  f << "t,S\n";
  for (int k = 0; k <= 40; ++k) {
    const double t = std::pow(10.0, 0.05 * k);
    f << t << "," << std::pow(t, 1.2) << "\n";
  }
  return p.string();
}

}  // namespace

TEST_CASE("md, analyze, fit-beta and pair refuse a folder in use, exit 2, touching nothing",
          "[cli][lock]") {
  const fs::path dir = tempDir("lock-cli");
  const std::string run = (dir / "run").string();
  REQUIRE(runGranagg(SMALL_RUN + "--out " + run).status == 0);
  const std::string traj_before = slurp(dir / "run" / "traj.h5");
  const std::string ck_before = slurp(dir / "run" / "checkpoint.h5");
  const fs::path held = dir / "held";
  fs::create_directories(held);
  std::ofstream(held / "traj.h5") << "the running command's file";
  {
    // this test process stands for the running command: it holds both folders
    FolderLock held_lock = FolderLock::acquire(held, "granagg md --out held", false);
    FolderLock run_lock = FolderLock::acquire(run, "granagg md --restart run", false);

    Run r = runGranagg("md --preset quick --set run.t_end=0.1 --force --out " + held.string());
    INFO(r.output);
    CHECK(r.status == 2);
    CHECK_THAT(r.output, Catch::Contains("--out '" + held.string() + "' is in use by") &&
                             Catch::Contains(ownPid()) &&
                             Catch::Contains("granagg md --out held"));
    CHECK(slurp(held / "traj.h5") == "the running command's file");

    r = runGranagg("md --restart " + run + " --set run.t_end=2 --force");
    INFO(r.output);
    CHECK(r.status == 2);
    CHECK_THAT(r.output, Catch::Contains(ownPid()));
    CHECK(slurp(dir / "run" / "traj.h5") == traj_before);
    CHECK(slurp(dir / "run" / "checkpoint.h5") == ck_before);

    r = runGranagg("analyze " + run + " --out " + (dir / "ana").string());
    INFO(r.output);
    CHECK(r.status == 2);
    CHECK_THAT(r.output, Catch::Contains("is being written by pid " + std::to_string(::getpid())));
    CHECK_FALSE(fs::exists(dir / "ana"));

    run_lock.release();
    r = runGranagg("analyze " + run + " --out " + held.string() + " --force -q");
    INFO(r.output);
    CHECK(r.status == 2);
    CHECK_THAT(r.output, Catch::Contains(ownPid()));

    r = runGranagg("fit-beta " + growthCsv(dir) + " --no-curve-fit --force -q --out " +
                   held.string());
    INFO(r.output);
    CHECK(r.status == 2);
    CHECK_THAT(r.output, Catch::Contains(ownPid()));

    r = runGranagg("pair --preset tiny --force --no-figures --out " + held.string());
    INFO(r.output);
    CHECK(r.status == 2);
    CHECK_THAT(r.output, Catch::Contains(ownPid()));
    CHECK(slurp(held / "traj.h5") == "the running command's file");
    CHECK_FALSE(fs::exists(held / "runs"));
  }
  // released: the same commands go through
  CHECK(runGranagg("analyze " + run + " --out " + (dir / "ana").string() + " -q").status == 0);
  CHECK_FALSE(fs::exists(dir / "ana" / granagg::common::FOLDER_LOCK_FILE));
  fs::remove_all(dir);
}

TEST_CASE("a second md into a running md's folder is refused and the first run ends intact",
          "[cli][lock]") {
  const fs::path dir = tempDir("lock-race");
  const std::string a = (dir / "a").string();
  // the first run (a few seconds); the second starts once the first has written its trajectory
  const Run r = sh(std::string(GRANAGG_BINARY) +
                   " md --preset quick --set system.N=6000 --set run.t_end=40 -q --out " + a +
                   " > " + a + ".log 2>&1 & pid=$!; while [ ! -f " + a +
                   "/traj.h5 ]; do sleep 0.05; done; " + GRANAGG_BINARY +
                   " md --preset quick --set run.t_end=1 --force --out " + a +
                   " 2>&1; echo \"second=$?\"; wait $pid; echo \"first=$?\"; cat " + a + ".log");
  INFO(r.output);
  CHECK_THAT(r.output, Catch::Contains("second=2") && Catch::Contains("is in use by pid"));
  CHECK_THAT(r.output, Catch::Contains("first=0"));
  // the first run's trajectory reads back whole, and its restart finds nothing to do
  const Run check = runGranagg("analyze " + a + " --out " + (dir / "ana").string() + " -q");
  INFO(check.output);
  CHECK(check.status == 0);
  fs::remove_all(dir);
}

TEST_CASE("a run whose trajectory is truncated behind its back fails and never reports success",
          "[cli][lock]") {
  const fs::path dir = tempDir("lock-damage");
  const std::string a = (dir / "a").string();
  const Run r = sh(std::string(GRANAGG_BINARY) +
                   " md --preset quick --set system.N=6000 --set run.t_end=40 --out " + a +
                   " > " + a + ".log 2>&1 & pid=$!; while [ ! -s " + a +
                   "/traj.h5 ]; do sleep 0.05; done; sleep 0.2; truncate -s 0 " + a +
                   "/traj.h5; wait $pid; echo \"status=$?\"; cat " + a + ".log");
  INFO(r.output);
  CHECK_THAT(r.output, Catch::Contains("status=1"));
  CHECK_THAT(r.output, Catch::Contains("was damaged while this run wrote it"));
  CHECK_THAT(r.output, !Catch::Contains("md: wrote") && !Catch::Contains("md: done at"));
  fs::remove_all(dir);
}

TEST_CASE("md --restart takes over this host's stale lock, another host's needs --force",
          "[cli][lock]") {
  const fs::path dir = tempDir("lock-stale-cli");
  const std::string run = (dir / "run").string();
  REQUIRE(runGranagg(SMALL_RUN + "--out " + run).status == 0);
  // a lock left by a killed run: a pid that no longer runs, on this host
  const pid_t dead = ::fork();
  if (dead == 0) ::_exit(0);
  ::waitpid(dead, nullptr, 0);
  char host[256] = {};
  ::gethostname(host, sizeof host - 1);
  const auto writeLock = [&](const std::string& on) {
    std::ofstream(dir / "run" / granagg::common::FOLDER_LOCK_FILE)
        << "pid = " << dead << "\nhost = " << on << "\ncommand = granagg md\nsince = x\n";
  };
  // another host's: its owner may still run there, so --restart refuses without --force
  writeLock("elsewhere.invalid");
  Run r = runGranagg("md --restart " + run + " --set run.t_end=1.2");
  INFO(r.output);
  CHECK(r.status == 2);
  CHECK_THAT(r.output, Catch::Contains("stale lock") &&
                           Catch::Contains("pid " + std::to_string(dead)) &&
                           Catch::Contains("Pass --force"));
  r = runGranagg("md --restart " + run + " --set run.t_end=1.2 --force");
  INFO(r.output);
  CHECK(r.status == 0);
  CHECK_THAT(r.output, Catch::Contains("took over the stale lock of pid " + std::to_string(dead)));
  CHECK_FALSE(fs::exists(dir / "run" / granagg::common::FOLDER_LOCK_FILE));
  // this host's (a SIGKILL, a time limit): the owner is gone, --restart takes over by itself
  writeLock(host);
  r = runGranagg("md --restart " + run + " --set run.t_end=1.5");
  INFO(r.output);
  CHECK(r.status == 0);
  CHECK_THAT(r.output, Catch::Contains("took over the stale lock of pid " +
                                       std::to_string(dead) + " on host " + host));
  CHECK_FALSE(fs::exists(dir / "run" / granagg::common::FOLDER_LOCK_FILE));

  // at its run.t_end: nothing to do, nothing written, and the way to go further
  const std::string traj = slurp(dir / "run" / "traj.h5");
  const std::string ck = slurp(dir / "run" / "checkpoint.h5");
  r = runGranagg("md --restart " + run);
  INFO(r.output);
  CHECK(r.status == 0);
  CHECK_THAT(r.output, Catch::Contains("complete at run.t_end = 1.5") &&
                           Catch::Contains("nothing to do") &&
                           Catch::Contains("granagg md --restart " + run + " --set run.t_end=T"));
  CHECK_THAT(r.output, !Catch::Contains("0 steps"));
  CHECK(slurp(dir / "run" / "traj.h5") == traj);
  CHECK(slurp(dir / "run" / "checkpoint.h5") == ck);
  fs::remove_all(dir);
}

TEST_CASE("md --restart of a run killed before its first checkpoint says how to start again",
          "[cli][lock]") {
  const fs::path dir = tempDir("lock-no-checkpoint");
  const std::string run = (dir / "run").string();
  REQUIRE(runGranagg(SMALL_RUN + "--out " + run).status == 0);
  fs::remove(dir / "run" / "checkpoint.h5");  // what a kill -9 before the first one leaves
  const Run r = runGranagg("md --restart " + run);
  INFO(r.output);
  CHECK(r.status == 2);
  CHECK_THAT(r.output, Catch::Contains("no checkpoint at") &&
                           Catch::Contains("before its first checkpoint") &&
                           Catch::Contains("--force") && Catch::Contains("config_toml"));
  fs::remove_all(dir);
}

TEST_CASE("an interrupted md says it stopped, never that it is done", "[cli][lock][signal]") {
  const fs::path dir = tempDir("lock-stopped");
  const std::string a = (dir / "a").string();
  const Run r = sh(std::string(GRANAGG_BINARY) +
                   " md --preset quick --set system.N=6000 --set run.t_end=40 --out " + a +
                   " > " + a + ".log 2>&1 & pid=$!; while [ ! -s " + a +
                   "/traj.h5 ]; do sleep 0.05; done; sleep 0.2; kill -INT $pid; wait $pid; "
                   "echo \"status=$?\"; cat " + a + ".log");
  INFO(r.output);
  CHECK_THAT(r.output, Catch::Contains("status=130"));
  CHECK_THAT(r.output, Catch::Contains("md: stopped at t = ") && !Catch::Contains("md: done at"));
  CHECK_FALSE(fs::exists(dir / "a" / granagg::common::FOLDER_LOCK_FILE));
  fs::remove_all(dir);
}

TEST_CASE("pair refuses another host's stale lock with advice that keeps the study",
          "[cli][lock]") {
  const fs::path dir = tempDir("lock-pair-host");
  fs::create_directories(dir / "study");
  std::ofstream(dir / "study" / granagg::common::FOLDER_LOCK_FILE)
      << "pid = 4242\nhost = some-other-node\ncommand = granagg pair\nsince = x\n";
  const Run r = runGranagg("pair --preset tiny --no-figures --out " + (dir / "study").string());
  INFO(r.output);
  CHECK(r.status == 2);
  CHECK_THAT(r.output, Catch::Contains("stale lock") && Catch::Contains("some-other-node") &&
                           Catch::Contains("delete") &&
                           Catch::Contains("--force would start the study over"));
  CHECK_FALSE(fs::exists(dir / "study" / "runs"));
  fs::remove_all(dir);
}
