// A study whose MD runs on LAMMPS ([md] engine = "lammps", docs/pair.md): the [lammps] keys read
// back and checked, the command lines of granagg-lammps runs, the Slurm script with srun on
// nodes x tasks per node, and the job pool with stand-ins for the launcher and granagg-lammps
// (found beside the granagg binary; its records, restarts and stop signal). The real chain on
// LAMMPS is tests/lammps/test_lammps_pair.cpp.
#include <catch2/catch.hpp>

#include <sys/wait.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "TestUtil.h"
#include "common/Interrupted.h"
#include "study/MdLaunch.h"
#include "study/PairConfig.h"
#include "study/PairStudy.h"
#include "study/Process.h"
#include "study/Slurm.h"

namespace fs = std::filesystem;
using namespace granagg::study;
using granagg::test::slurp;
using granagg::test::spit;
using granagg::test::tempDir;

namespace {

const std::string TINY = std::string(GRANAGG_SOURCE_DIR) + "/data/pair/tiny.toml";

void executable(const fs::path& p, const std::string& text) {
  spit(p, text);
  fs::permissions(p, fs::perms::owner_all);
}

/// A folder `dir`/bin with stand-ins: `granagg` (every post-processing step succeeds) and, with
/// `lammps`, `granagg-lammps`, which appends its arguments to dir/lammps_calls.txt and exits 0,
/// or, while dir/slow exists, waits for SIGTERM, notes "rank" in dir/terms.txt and exits 143.
/// Also dir/launch.sh, a launcher that notes its arguments in dir/launch_calls.txt, drops its
/// first two (-np N) and runs the rest, with their exit status. As Open MPI's mpirun does, it
/// answers a SIGTERM of its own by killing the rank (here at once), noted as "launcher" in
/// dir/terms.txt.
fs::path standIns(const fs::path& dir, bool lammps) {
  fs::create_directories(dir / "bin");
  executable(dir / "bin" / "granagg", "#!/bin/sh\nexit 0\n");
  const std::string d = dir.string();
  if (lammps)
    executable(dir / "bin" / "granagg-lammps",
               "#!/bin/sh\necho \"$@\" >> " + d + "/lammps_calls.txt\n" + "[ -f " + d +
                   "/slow ] || exit 0\n" + "trap 'echo rank >> " + d +
                   "/terms.txt; exit 143' TERM\n" + "while :; do sleep 0.05; done\n");
  executable(dir / "launch.sh", "#!/bin/sh\necho \"$@\" >> " + d + "/launch_calls.txt\n" +
                                    "shift 2\n\"$@\" &\nrank=$!\n" + "trap 'echo launcher >> " + d +
                                    "/terms.txt; kill -KILL $rank' TERM\n" + "wait $rank\n");
  return dir / "bin" / "granagg";
}

/// Services with `exe` for the granagg binary and a fixed MD plan: no md/ needed.
StudyServices services(const fs::path& exe) {
  StudyServices s;
  s.exe = exe.string();
  s.command_line = "test";
  s.backend = "none";
  s.find_md_preset = [](const std::string& name) { return "/presets/" + name + ".toml"; };
  s.resolve_md = [](const std::string& base, const std::vector<std::string>& set) {
    MdPlan p;
    p.toml = base;
    for (const auto& x : set) p.toml += "\n" + x;
    p.N = 100;
    p.phi = 0.076;
    p.t_end = 1;
    p.steps = 10;
    return p;
  };
  s.classify_growth = [](const std::vector<double>&, const std::vector<double>&,
                         const std::vector<double>&) { return GrowthSummary{}; };
  return s;
}

/// tiny's study with 2 K x 2 runs on LAMMPS, started by `launcher`.
PairConfig onLammps(const std::string& launcher) {
  PairConfig c = parsePairConfig(TINY);
  c.K = {0.0, 5.0};
  c.runs = 2;
  c.md_engine = "lammps";
  c.lammps_launcher = launcher;
  return c;
}

StudyRequest quietRequest(const fs::path& out) {
  StudyRequest req;
  req.out = out.string();
  req.quiet = true;
  req.no_figures = true;
  return req;
}

}  // namespace

TEST_CASE("pair configuration: md.engine and the lammps keys read back and are checked",
          "[study][lammps]") {
  const fs::path dir = tempDir("study_lammps_keys");
  PairConfig defaults = parsePairConfig(TINY);
  CHECK(defaults.md_engine == "granagg");  // granagg's own engine unless a study says otherwise
  CHECK(defaults.lammps_launcher == "mpirun -np {ranks}");
  CHECK(defaults.lammps_ranks == 2);
  CHECK(defaults.lammps_slurm_launcher == "srun");
  CHECK(defaults.lammps_nodes == 1);
  CHECK(defaults.lammps_tasks_per_node == 2);

  spit(dir / "pair.toml",
       "[md]\npreset = \"quick\"\nengine = \"lammps\"\n[lammps]\n"
       "launcher = \"mpirun --oversubscribe -np {ranks}\"\nranks = 6\n"
       "slurm_launcher = \"srun --mpi=pmix\"\nnodes = 4\ntasks_per_node = 32\n");
  const PairConfig c = parsePairConfig((dir / "pair.toml").string());
  CHECK(c.md_engine == "lammps");
  CHECK(c.lammps_launcher == "mpirun --oversubscribe -np {ranks}");
  CHECK(c.lammps_ranks == 6);
  CHECK(c.lammps_slurm_launcher == "srun --mpi=pmix");
  CHECK(c.lammps_nodes == 4);
  CHECK(c.lammps_tasks_per_node == 32);
  validate(c);
  spit(dir / "resolved.toml", toToml(c));  // the resolved form gives the same back
  const PairConfig b = parsePairConfig((dir / "resolved.toml").string());
  CHECK(b.md_engine == c.md_engine);
  CHECK(b.lammps_launcher == c.lammps_launcher);
  CHECK(b.lammps_ranks == c.lammps_ranks);
  CHECK(b.lammps_slurm_launcher == c.lammps_slurm_launcher);
  CHECK(b.lammps_nodes == c.lammps_nodes);
  CHECK(b.lammps_tasks_per_node == c.lammps_tasks_per_node);

  const auto parseFails = [&](const std::string& text, const std::string& expected) {
    spit(dir / "bad.toml", "[md]\npreset = \"quick\"\n" + text);
    INFO(text);
    CHECK_THROWS_WITH(parsePairConfig((dir / "bad.toml").string()), Catch::Contains(expected));
  };
  parseFails("engine = 1\n", "md.engine must be a string");
  parseFails("[lammps]\nranks = \"2\"\n", "bad.toml:4:9: lammps.ranks must be an integer");
  parseFails("[lammps]\nnode = 2\n", "unknown key 'lammps.node'");
  const auto invalid = [&](const std::string& text, const std::string& expected) {
    spit(dir / "bad.toml", "[md]\npreset = \"quick\"\n" + text);
    INFO(text);
    CHECK_THROWS_WITH(validate(parsePairConfig((dir / "bad.toml").string())),
                      Catch::Contains(expected));
  };
  invalid("engine = \"lamps\"\n",
          "md.engine = \"lamps\" is not known (allowed: \"granagg\", \"lammps\")");
  invalid("[lammps]\nranks = 0\n", "lammps.ranks must lie in 1..1048576 (got 0)");
  invalid("[lammps]\nnodes = -3\n", "lammps.nodes must lie in 1..1048576 (got -3)");
  invalid("[lammps]\ntasks_per_node = 9999999999\n", "lammps.tasks_per_node must lie in 1..");
  invalid("[lammps]\nlauncher = \" \"\n", "lammps.launcher is empty");
  invalid("[lammps]\nlauncher = \"mpirun -np '4'\"\n", "'4'' holds a character");
  invalid("[lammps]\nslurm_launcher = \"srun -n {tasks}\"\n", "lammps.slurm_launcher");

  CHECK(launcherWords("mpirun  --oversubscribe -np {ranks}", 3, "k") ==
        std::vector<std::string>{"mpirun", "--oversubscribe", "-np", "3"});
  CHECK(launcherWords("srun -n{ranks}", 128, "k") == std::vector<std::string>{"srun", "-n128"});
  fs::remove_all(dir);
}

TEST_CASE("granagg-lammps runs: the command lines of a fresh start and of a restart",
          "[study][lammps]") {
  RunJob j;
  j.dir = "/s/runs/K5/run1";
  j.config = "/s/config/md_K5.toml";
  j.seed = 12;
  MdLaunch l;
  l.engine = "lammps";
  l.granagg = "/opt/bin/granagg";
  l.granagg_lammps = "/opt/bin/granagg-lammps";
  l.launcher = {"mpirun", "-np", "4"};
  using V = std::vector<std::string>;
  CHECK(mdCommand(l, j, 8) == V{"mpirun", "-np", "4", "/opt/bin/granagg-lammps", "--config",
                                "/s/config/md_K5.toml", "--set", "system.seed=12", "--out",
                                "/s/runs/K5/run1", "--force", "-q"});
  CHECK(checkpointFile(l) == "checkpoint.toml");
  j.restart = true;
  CHECK(mdCommand(l, j, 8) == V{"mpirun", "-np", "4", "/opt/bin/granagg-lammps", "--restart",
                                "/s/runs/K5/run1", "--force", "-q"});
  // granagg's own engine: unchanged
  l.engine = "granagg";
  CHECK(mdCommand(l, j, 8) == V{"/opt/bin/granagg", "md", "--restart", "/s/runs/K5/run1", "--force",
                                "--threads", "8", "-q"});
  j.restart = false;
  CHECK(mdCommand(l, j, 8) == V{"/opt/bin/granagg", "md", "--config", "/s/config/md_K5.toml",
                                "--seed", "12", "--out", "/s/runs/K5/run1", "--force", "--threads",
                                "8", "-q"});
  CHECK(checkpointFile(l) == "checkpoint.h5");
}

TEST_CASE(
    "Slurm script of a study on LAMMPS: each task holds its nodes and starts its run with "
    "srun",
    "[study][lammps]") {
  const fs::path dir = tempDir("study_lammps_slurm");
  const fs::path exe = standIns(dir, true);
  PairConfig c = onLammps("mpirun -np {ranks}");
  c.lammps_nodes = 2;
  c.lammps_tasks_per_node = 4;
  c.lammps_slurm_launcher = "srun --mpi=pmix";
  StudyRequest req = quietRequest(dir / "out");
  req.emit_batch = "slurm";
  PairStudy(c, req, services(exe)).run();
  const std::string s = slurp(dir / "out" / "batch.slurm");
  INFO(s);
  CHECK_THAT(s, Catch::Contains("#SBATCH --array=0-3\n"));
  CHECK_THAT(s, Catch::Contains("#SBATCH --nodes=2\n"));
  CHECK_THAT(s, Catch::Contains("#SBATCH --ntasks-per-node=4\n"));
  CHECK_THAT(s, Catch::Contains("#SBATCH --cpus-per-task=1\n"));
  CHECK_THAT(s, Catch::Contains("--run-index \"$SLURM_ARRAY_TASK_ID\" --launcher "
                                "'srun --mpi=pmix --nodes=2 --ntasks-per-node=4'"));
  // the follow-up job (analysis and the rest) starts the study with the same launcher, which it
  // checks as it starts: within --wrap='...', its quotes are escaped
  CHECK_THAT(
      s, Catch::Contains("--wrap=") && Catch::Contains(" --launcher '\\''srun --mpi=pmix --nodes=2 "
                                                       "--ntasks-per-node=4'\\'''\n"));
  CHECK(std::system(("bash -n " + (dir / "out" / "batch.slurm").string()).c_str()) == 0);
  CHECK(!fs::exists(dir / "out" / "runs"));  // nothing run
  CHECK(!fs::exists(dir / "launch_calls.txt"));
  // the array task's command: the study with that launcher, a run on srun
  const PairConfig resolved = parsePairConfig((dir / "out" / "config" / "pair.toml").string());
  CHECK(resolved.md_engine == "lammps");
  CHECK(resolved.lammps_nodes == 2);

  // granagg's own engine: a task of `threads` CPUs, no nodes, no launcher
  SlurmJob j;
  j.name = "plain";
  j.tasks = 2;
  j.runs_per_K = 1;
  j.K = {0.0, 5.0};
  j.threads = 8;
  j.out = "/scratch/plain";
  j.study_command = "granagg pair";
  const std::string plain = slurmScript(j);
  CHECK_THAT(plain, Catch::Contains("#SBATCH --cpus-per-task=8\n"));
  CHECK_THAT(plain, !Catch::Contains("--nodes") && !Catch::Contains("--launcher"));
  fs::remove_all(dir);
}

TEST_CASE("PairStudy on LAMMPS: granagg-lammps beside granagg and a launcher found, or exit 2",
          "[study][lammps]") {
  const fs::path dir = tempDir("study_lammps_missing");
  const StudyRequest req = quietRequest(dir / "out");
  {  // a build without granagg-lammps
    const fs::path exe = standIns(dir / "nolammps", false);
    CHECK_THROWS_WITH(PairStudy(onLammps("mpirun -np {ranks}"), req, services(exe)),
                      Catch::Contains("md.engine = \"lammps\"") &&
                          Catch::Contains((dir / "nolammps" / "bin" / "granagg-lammps").string()) &&
                          Catch::Contains("built when liblammps-dev"));
    // granagg's own engine needs none of it
    PairConfig own = onLammps("mpirun -np {ranks}");
    own.md_engine = "granagg";
    CHECK_NOTHROW(PairStudy(own, req, services(exe)));
  }
  const fs::path exe = standIns(dir / "lammps", true);
  CHECK_THROWS_WITH(PairStudy(onLammps("/nonexistent/mpirun -np {ranks}"), req, services(exe)),
                    Catch::Contains("lammps.launcher: '/nonexistent/mpirun' is not a program"));
  StudyRequest given = req;
  given.launcher = "no-such-mpirun-here -n 2";
  CHECK_THROWS_WITH(PairStudy(onLammps("mpirun -np {ranks}"), given, services(exe)),
                    Catch::StartsWith("--launcher: 'no-such-mpirun-here'"));
  // a cluster's launcher is not looked for here when the study is only written out for it
  given.emit_batch = "slurm";
  CHECK_NOTHROW(PairStudy(onLammps("mpirun -np {ranks}"), given, services(exe)));
  CHECK(!fs::exists(dir / "out"));
  fs::remove_all(dir);
}

TEST_CASE(
    "PairStudy on LAMMPS: runs launched, records kept, restarts from checkpoint.toml, a "
    "stop reaches the ranks and not the launcher",
    "[study][lammps]") {
  const fs::path dir = tempDir("study_lammps_pool");
  const fs::path exe = standIns(dir, true);
  const fs::path out = dir / "out";
  const std::string launcher = (dir / "launch.sh").string() + " -np {ranks}";
  StudyRequest req = quietRequest(out);
  req.jobs = 2;
  {
    PairStudy study(onLammps(launcher), req, services(exe));
    study.run();
    const std::string calls = slurp(dir / "launch_calls.txt");
    INFO(calls);
    for (const RunJob& j : study.runs()) {
      CHECK_THAT(j.spec, Catch::EndsWith(" engine=lammps"));
      const auto done = nlohmann::json::parse(slurp(j.dir / "done.json"));
      CHECK(done.at("spec") == j.spec);
      CHECK(done.at("launcher") == launcher.substr(0, launcher.size() - 7) + "2");
      CHECK_THAT(calls, Catch::Contains("-np 2 " + (dir / "bin" / "granagg-lammps").string() +
                                        " --config " + j.config.string() +
                                        " --set system.seed=" + std::to_string(j.seed) + " --out " +
                                        j.dir.string() + " --force -q\n"));
    }
    CHECK_THAT(slurp(out / "pair.log"), Catch::Contains("; MD by " + (dir / "launch.sh").string() +
                                                        " -np 2 granagg-lammps"));
    CHECK_THAT(slurp(out / "summary.json"), Catch::Contains("LAMMPS through granagg-lammps"));
  }
  {  // an interrupted run with a checkpoint continues; a lost run starts afresh
    const fs::path k0 = out / "runs" / "K0" / "run0";
    fs::remove(k0 / "done.json");
    spit(k0 / "checkpoint.toml", "");
    spit(k0 / "traj.h5", "");
    fs::remove_all(out / "runs" / "K5" / "run1");
    fs::remove(dir / "lammps_calls.txt");
    PairStudy study(onLammps(launcher), req, services(exe));
    study.run();
    const std::string calls = slurp(dir / "lammps_calls.txt");
    INFO(calls);
    CHECK_THAT(calls, Catch::Contains("--restart " + k0.string() + " --force -q\n"));
    CHECK_THAT(calls, Catch::Contains("--out " + (out / "runs" / "K5" / "run1").string()));
    CHECK(std::count(calls.begin(), calls.end(), '\n') == 2);
    CHECK(nlohmann::json::parse(slurp(k0 / "done.json")).at("restarted") == true);
  }
  {  // the same study on granagg's own engine: these runs are not its runs
    PairConfig own = onLammps(launcher);
    own.md_engine = "granagg";
    PairStudy study(own, req, services(exe));
    CHECK_THROWS_WITH(study.run(), Catch::Contains("holds a run made with another configuration"));
  }
  {  // a stop signal: SIGTERM to the ranks (granagg-lammps), which stop; the launcher gets none
    fs::remove(out / "runs" / "K0" / "run1" / "done.json");
    fs::remove(dir / "lammps_calls.txt");
    spit(dir / "slow", "");
    static volatile std::sig_atomic_t stop = 0;
    StudyServices s = services(exe);
    s.stop = &stop;
    PairStudy study(onLammps(launcher), req, s);
    std::thread signal([&] {
      for (int i = 0;
           i < 200 && slurp(dir / "lammps_calls.txt").find("run1 --force") == std::string::npos;
           ++i)
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
      std::this_thread::sleep_for(std::chrono::milliseconds(300));  // the trap is set
      stop = SIGTERM;  // what the signal handler of catchStopSignals() does
    });
    const auto t0 = std::chrono::steady_clock::now();
    try {
      study.run();
      FAIL("no interruption");
    } catch (const granagg::common::Interrupted& e) {
      CHECK(e.status() == 128 + SIGTERM);
    }
    signal.join();
    CHECK(std::chrono::steady_clock::now() - t0 < std::chrono::seconds(10));
    CHECK(slurp(dir / "terms.txt") == "rank\n");
    CHECK_THAT(slurp(out / "pair.log"), Catch::Contains("md K0 run 1: stopped"));
  }
  fs::remove_all(dir);
}

TEST_CASE("descendantsNamed finds a launcher's ranks by name, below any depth", "[study]") {
  const fs::path dir = tempDir("study_descendants");
  // each rank has a child of its own name (a subshell: forked, never exec'd), which is not a rank
  executable(dir / "granagg-lammps",
             "#!/bin/sh\n(while :; do sleep 0.05; done) &\nwhile :; do sleep 0.05; done\n");
  executable(dir / "outer.sh", "#!/bin/sh\n" + (dir / "granagg-lammps").string() + " &\n" +
                                   "/bin/sh -c '" + (dir / "granagg-lammps").string() +
                                   "; true' &\nwait\n");
  const pid_t pid = spawn({(dir / "outer.sh").string()}, dir / "log");
  std::vector<pid_t> ranks;
  for (int i = 0; i < 100 && ranks.size() < 2; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    ranks = descendantsNamed(pid, "granagg-lammps");
  }
  CHECK(ranks.size() == 2);                          // a child and a grandchild, not their forks
  CHECK(descendantsNamed(pid, "outer.sh").empty());  // the root itself is not its descendant
  CHECK(::getpgid(pid) == pid);  // spawn's child leads a process group of its own
  for (pid_t r : ranks) ::kill(r, SIGTERM);
  int st = 0;
  REQUIRE(::waitpid(pid, &st, 0) == pid);
  CHECK(descendantsNamed(pid, "granagg-lammps").empty());
  ::kill(-pid, SIGKILL);  // the ranks' subshells, orphaned, are still in the launcher's group
  fs::remove_all(dir);
}

TEST_CASE("a launched run's last word is its own line, not the launcher's report after it",
          "[study]") {
  const fs::path dir = tempDir("study_lastline");
  spit(dir / "run.log",
       "# mpirun -np 2 granagg-lammps ...\nlammps: run 0\n"
       "granagg-lammps: stopped: SIGTERM at step 700; checkpoint written\n"
       "-----------\nmpirun detected that one or more processes exited with non-zero status\n"
       "  Exit code:    143\n-----------\n");
  CHECK(lastLine(dir / "run.log", "granagg-lammps: ") ==
        "granagg-lammps: stopped: SIGTERM at step 700; checkpoint written");
  CHECK(lastLine(dir / "run.log") == "-----------");
  spit(dir / "plain.log", "md: step 10\rmd: step 20\n");  // no such line: the last line
  CHECK(lastLine(dir / "plain.log", "granagg-lammps: ") == "md: step 20");
  fs::remove_all(dir);
}
