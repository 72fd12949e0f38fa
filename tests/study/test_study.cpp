// The study library (study/): the pair configuration read back from its own resolved TOML, errors
// with file positions, the Slurm script, command lines a shell runs unchanged, whole-file writes,
// and PairStudy's job pool with stand-in programs for granagg (so that resume records, failures
// and stop signals are tested without MD). The real chain is tests/cli/test_pair_cli.cpp.
#include <catch2/catch.hpp>

#include <sys/wait.h>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "TestUtil.h"
#include "common/Interrupted.h"
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

/// Services with a stand-in for the granagg binary (`exe`) and a fixed MD plan: no md/ needed.
StudyServices fakeServices(const std::string& exe) {
  StudyServices s;
  s.exe = exe;
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

PairConfig twoByTwo() {
  PairConfig c = parsePairConfig(TINY);
  c.K = {0.0, 5.0};
  c.runs = 2;
  return c;
}

}  // namespace

TEST_CASE("pair configuration: the resolved TOML reads back as the same configuration", "[study]") {
  PairConfig c = parsePairConfig(TINY);
  CHECK(c.name == "tiny");
  CHECK(c.md_preset == "quick");
  CHECK(c.charged_Q == 0.05);
  c.K = {0.0, 2.5, 5.0};
  c.fit_window = {10.0, 1000.0};
  c.fit_column = "S_particle_mean";
  c.md_set.push_back("note=\"quoted\" and 'single'");
  c.mf_t_end = 1.0 / 3.0;  // a value that needs all 17 digits
  const fs::path dir = tempDir("study_toml");
  spit(dir / "pair.toml", toToml(c));
  const PairConfig b = parsePairConfig((dir / "pair.toml").string());
  CHECK(b.name == c.name);
  CHECK(b.K == c.K);
  CHECK(b.runs == c.runs);
  CHECK(b.seed == c.seed);
  CHECK(b.md_preset == c.md_preset);
  CHECK(b.md_config.empty());
  CHECK(b.md_set == c.md_set);
  CHECK(b.charged_Q == c.charged_Q);
  CHECK(b.charged_set == c.charged_set);
  CHECK(b.analysis_args == c.analysis_args);
  CHECK(b.betas == c.betas);
  CHECK(b.mf_t_end == c.mf_t_end);  // exact: toml++ writes round-trip digits
  CHECK(b.mf_s_end == c.mf_s_end);
  CHECK(b.zbeta_min == c.zbeta_min);
  CHECK(b.zbeta_max == c.zbeta_max);
  CHECK(b.zbeta_count == c.zbeta_count);
  CHECK(b.fit_window == c.fit_window);
  CHECK(b.fit_column == c.fit_column);
  CHECK(toToml(b).substr(toToml(b).find('\n')) == toToml(c).substr(toToml(c).find('\n')));
  fs::remove_all(dir);
}

TEST_CASE("pair configuration: errors name the file position, the key and the allowed values",
          "[study]") {
  const fs::path dir = tempDir("study_errors");
  const auto fails = [&](const std::string& text, const std::string& expected) {
    spit(dir / "bad.toml", text);
    INFO(text);
    CHECK_THROWS_WITH(parsePairConfig((dir / "bad.toml").string()), Catch::Contains(expected));
  };
  fails("[pair]\nruns = 2\nrusn = 3\n", "bad.toml:3:8: unknown key 'pair.rusn'");
  fails("[pairs]\n", "unknown section 'pairs'");
  fails("[pair]\nruns = \"two\"\n[md]\npreset = \"quick\"\n", "pair.runs must be an integer");
  fails("[pair]\nK = [0, \"5\"]\n", "pair.K must hold numbers only");
  fails("[md]\npreset = \"quick\"\nconfig = \"x.toml\"\n", "[md] needs exactly one of");
  fails("[input]\nversion = 2\n[md]\npreset = \"q\"\n", "version = 2 is not supported");
  fails("[pair\n", "invalid TOML");
  CHECK_THROWS_WITH(parsePairConfig((dir / "missing.toml").string()),
                    Catch::Contains("no such file"));
  PairConfig c = parsePairConfig(TINY);
  c.runs = MAX_RUNS + 1;
  CHECK_THROWS_WITH(validate(c), Catch::Contains("pair.runs must lie in 1..10000"));
  c = parsePairConfig(TINY);
  c.K = {5.0, 5.0};
  CHECK_THROWS_WITH(validate(c), Catch::Contains("K = 5 is listed twice"));
  c = parsePairConfig(TINY);
  c.fit_window = {10.0, 1.0};
  CHECK_THROWS_WITH(validate(c), Catch::Contains("fit.window"));
  CHECK(parseKList("0,2.5,5") == std::vector<double>{0.0, 2.5, 5.0});
  for (const char* bad : {"", "0,,5", "-1", "5x", "nan"})
    CHECK_THROWS_WITH(parseKList(bad), Catch::Contains("--K takes"));
  CHECK(kName(0.0) == "K0");
  CHECK(kName(2.5) == "K2.5");
  fs::remove_all(dir);
}

TEST_CASE("command lines: what joinCommand writes, a shell runs with the same arguments",
          "[study]") {
  const std::vector<std::string> argv{"printf", "[%s]\\n", "plain", "two words", "it's",
                                      "$HOME",  "a\"b",    "",      "*"};
  const fs::path dir = tempDir("study_shell");
  const fs::path log = dir / "out.log";
  const pid_t pid = spawn({"/bin/sh", "-c", joinCommand(argv)}, log);
  int st = 0;
  REQUIRE(::waitpid(pid, &st, 0) == pid);
  CHECK(WEXITSTATUS(st) == 0);
  CHECK(slurp(log) == "[plain]\n[two words]\n[it's]\n[$HOME]\n[a\"b]\n[]\n[*]\n");
  CHECK(shellQuote("run.t_end=5") == "run.t_end=5");  // nothing to quote: left as is
  // a program that does not exist: status 127 and the reason in the log
  const pid_t none = spawn({"/nonexistent/granagg"}, dir / "none.log");
  REQUIRE(::waitpid(none, &st, 0) == none);
  CHECK(WEXITSTATUS(st) == 127);
  CHECK_THAT(slurp(dir / "none.log"), Catch::Contains("cannot run /nonexistent/granagg"));
  // the last line of a log is what a progress line left after its last carriage return
  spit(dir / "p.log", "first\nstep 10\rstep 20\rdone: 3 s\n\n");
  CHECK(lastLine(dir / "p.log") == "done: 3 s");
  // whole-file writes leave no temporary file behind
  writeText(dir / "rec.json", "{}\n");
  CHECK(slurp(dir / "rec.json") == "{}\n");
  CHECK(!fs::exists(dir / "rec.json.tmp"));
  CHECK(fnv1a("") == "cbf29ce484222325");   // the FNV-1a 64-bit offset basis
  CHECK(fnv1a("a") == "af63dc4c8601ec8c");  // published test vector
  fs::remove_all(dir);
}

TEST_CASE("Slurm script: one array task per run, the stop signal and the follow-up job",
          "[study]") {
  SlurmJob j;
  j.name = "demo";
  j.tasks = 6;
  j.runs_per_K = 3;
  j.K = {0.0, 5.0};
  j.threads = 8;
  j.out = "/scratch/study";
  j.study_command =
      "/opt/granagg pair --config /scratch/study/config/pair.toml --out "
      "/scratch/study";
  j.written_by = "granagg pair --preset demo --emit-batch slurm";
  const std::string s = slurmScript(j);
  CHECK_THAT(s, Catch::StartsWith("#!/bin/bash\n"));
  CHECK_THAT(s, Catch::Contains("#SBATCH --array=0-5\n"));
  CHECK_THAT(s, Catch::Contains("#SBATCH --cpus-per-task=8\n"));
  CHECK_THAT(s, Catch::Contains("#SBATCH --signal=B:TERM@300\n"));
  CHECK_THAT(s, Catch::Contains("#SBATCH --output=/scratch/study/logs/slurm-%A_%a.out"));
  CHECK_THAT(s, Catch::Contains("task index = k * 3 + r for K index k (K = 0, 5)"));
  CHECK_THAT(s, Catch::Contains("--dependency=afterok:"));
  CHECK_THAT(s,
             Catch::Contains("exec " + j.study_command + " --run-index \"$SLURM_ARRAY_TASK_ID\""));
  // the script is valid shell
  const fs::path dir = tempDir("study_slurm");
  spit(dir / "batch.slurm", s);
  CHECK(std::system(("bash -n " + (dir / "batch.slurm").string()).c_str()) == 0);
  fs::remove_all(dir);
}

TEST_CASE("PairStudy: runs, seeds and records, bad requests refused before anything is written",
          "[study]") {
  const fs::path dir = tempDir("study_plan");
  StudyRequest req;
  req.out = (dir / "out").string();
  req.quiet = true;
  req.no_figures = true;
  const PairStudy plan(twoByTwo(), req, fakeServices("/bin/true"));
  REQUIRE(plan.runs().size() == 4);
  for (const RunJob& j : plan.runs()) {
    CHECK(j.seed == 1 + j.r);  // the same seeds for every K
    CHECK(j.index == (j.K == 0.0 ? 0 : 2) + j.r);
    CHECK_THAT(j.spec, Catch::StartsWith("md_config_fnv1a="));
  }
  CHECK(plan.runs()[0].spec != plan.runs()[2].spec);  // K differs: another configuration
  CHECK(plan.runs()[0].cost < plan.runs()[2].cost);   // charged runs first
  StudyRequest bad = req;
  bad.run_index = 4;
  CHECK_THROWS_WITH(PairStudy(twoByTwo(), bad, fakeServices("/bin/true")),
                    Catch::Contains("--run-index 4 is out of range"));
  bad = req;
  bad.emit_batch = "pbs";
  CHECK_THROWS_AS(PairStudy(twoByTwo(), bad, fakeServices("/bin/true")), std::invalid_argument);
  PairConfig c = twoByTwo();
  c.runs = 0;
  CHECK_THROWS_AS(PairStudy(c, req, fakeServices("/bin/true")), std::invalid_argument);
  CHECK(!fs::exists(dir / "out"));
  fs::remove_all(dir);
}

TEST_CASE("PairStudy: finished runs are kept, failed runs named, a stop signal interrupts",
          "[study]") {
  const fs::path dir = tempDir("study_pool");
  StudyRequest req;
  req.out = (dir / "out").string();
  req.quiet = true;
  req.no_figures = true;
  req.jobs = 2;
  {  // every step "succeeds": each run gets its done.json, with the spec it was run with
    PairStudy study(twoByTwo(), req, fakeServices("/bin/true"));
    study.run();
    for (const RunJob& j : study.runs()) {
      const auto done = nlohmann::json::parse(slurp(j.dir / "done.json"));
      CHECK(done.at("spec") == j.spec);
      CHECK(done.at("seed") == j.seed);
      CHECK(done.at("restarted") == false);
    }
    const auto summary = nlohmann::json::parse(slurp(dir / "out" / "summary.json"));
    CHECK(summary.at("ensembles").size() == 2);
    CHECK(summary.at("ensembles")[1].at("K") == 5.0);
    CHECK(summary.at("ensembles")[1].at("z_analyze").at("value").is_null());  // no tables
  }
  {  // a record made before the hash was corrected (Process.h, LEGACY_HASH_BASIS) still counts
    const PairStudy study(twoByTwo(), req, fakeServices("/bin/true"));
    const RunJob& j = study.runs()[0];
    CHECK(j.legacy_spec != j.spec);
    auto done = nlohmann::json::parse(slurp(j.dir / "done.json"));
    done["spec"] = j.legacy_spec;
    spit(j.dir / "done.json", done.dump(2));
  }
  const std::string log_before = slurp(dir / "out" / "pair.log");
  {  // again, with a program that fails: no run is redone; the analysis fails (no tables)
    PairStudy study(twoByTwo(), req, fakeServices("/bin/false"));
    CHECK_THROWS_WITH(study.run(), Catch::Contains("post-processing step(s) failed"));
    const std::string log = slurp(dir / "out" / "pair.log").substr(log_before.size());
    CHECK_THAT(log, Catch::Contains("md: all 4 runs finished already"));
  }
  {  // one run's record lost: that run alone is redone, and its failure is reported by name
    fs::remove(dir / "out" / "runs" / "K5" / "run1" / "done.json");
    PairStudy study(twoByTwo(), req, fakeServices("/bin/false"));
    CHECK_THROWS_WITH(study.run(), Catch::Contains("1 MD run(s) failed (K5 run 1;"));
    CHECK(!fs::exists(dir / "out" / "runs" / "K5" / "run1" / "done.json"));
    CHECK(fs::exists(dir / "out" / "runs" / "K0" / "run1" / "done.json"));
  }
  {  // a stop signal: the running runs are stopped and the study says how to resume
    fs::remove(dir / "out" / "runs" / "K0" / "run0" / "done.json");
    const fs::path slow = dir / "slow.sh";
    spit(slow, "#!/bin/sh\nexec sleep 30\n");
    fs::permissions(slow, fs::perms::owner_all);
    static volatile std::sig_atomic_t stop = 0;
    StudyServices s = fakeServices(slow.string());
    s.stop = &stop;
    PairStudy study(twoByTwo(), req, s);
    std::thread signal([] {
      std::this_thread::sleep_for(std::chrono::milliseconds(500));
      stop = SIGTERM;  // what the signal handler of catchStopSignals() does
    });
    const auto t0 = std::chrono::steady_clock::now();
    try {
      study.run();
      FAIL("no interruption");
    } catch (const granagg::common::Interrupted& e) {
      CHECK(e.status() == 128 + SIGTERM);
      CHECK_THAT(e.what(), Catch::Contains("run the same command again to resume"));
    }
    signal.join();
    CHECK(std::chrono::steady_clock::now() - t0 < std::chrono::seconds(10));  // not 30 s
    const std::string log = slurp(dir / "out" / "pair.log");
    CHECK_THAT(log, Catch::Contains("md K0 run 0: stopped"));
    CHECK(!fs::exists(dir / "out" / "runs" / "K0" / "run0" / "done.json"));
  }
  fs::remove_all(dir);
}
