// `granagg md --analyze` (study/insitu): the tables of the analysis during the run against the
// independent path, `granagg analyze` over the trajectory the same run wrote; a run without
// stored frames (output.trajectory = false); a run stopped by SIGTERM or killed by SIGKILL and
// continued with --restart; bad [analysis] input refused before the first step.
#include <catch2/catch.hpp>

#include "RunCommand.h"

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "TestUtil.h"

using granagg::test::tempDir;
namespace fs = std::filesystem;

namespace {

/// A small run of the quick preset (neutral gas with collisional charging): N = 1000 to t = 10,
/// about 0.3 s; `extra` adds options.
Run mdRun(const fs::path& out, const std::string& extra) {
  return runGranagg("md --preset quick --set system.N=1000 --set run.t_end=10 --seed 5 -q "
                    "--threads 1 --out " + out.string() + " " + extra);
}

/// The cells of a CSV table, comment lines (provenance) left out.
std::vector<std::vector<std::string>> cells(const fs::path& csv) {
  std::ifstream in(csv);
  std::vector<std::vector<std::string>> rows;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::vector<std::string> row;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, ',')) row.push_back(cell);
    rows.push_back(row);
  }
  return rows;
}

/// Every CSV of folder `a` (and its per_run/) equals the one of the same name in `b`: cells the
/// same text, or numbers within 1e-12 relative (the order of a sum may differ); counts exact.
void requireSameCsvs(const fs::path& a, const fs::path& b) {
  std::size_t files = 0;
  for (const fs::path& sub : {fs::path(), fs::path("per_run")}) {
    for (const auto& e : fs::directory_iterator(a / sub)) {
      if (e.path().extension() != ".csv") continue;
      ++files;
      const fs::path other = b / sub / e.path().filename();
      INFO("table " << (sub / e.path().filename()).string());
      REQUIRE(fs::exists(other));
      const auto ca = cells(e.path()), cb = cells(other);
      REQUIRE(ca.size() == cb.size());
      REQUIRE(ca.size() >= 2);  // a header and rows
      std::size_t differ = 0;
      for (std::size_t r = 0; r < ca.size(); ++r) {
        REQUIRE(ca[r].size() == cb[r].size());
        for (std::size_t c = 0; c < ca[r].size(); ++c) {
          if (ca[r][c] == cb[r][c]) continue;
          const double x = std::strtod(ca[r][c].c_str(), nullptr),
                       y = std::strtod(cb[r][c].c_str(), nullptr);
          if (!(std::fabs(x - y) <= 1e-12 * std::max(std::fabs(x), std::fabs(y)))) ++differ;
        }
      }
      CHECK(differ == 0);
    }
  }
  CHECK(files >= 20);  // the ensemble tables and the per-run ones
}

}  // namespace

TEST_CASE("md --analyze writes the tables that granagg analyze computes from the run's frames",
          "[cli][insitu]") {
  const fs::path dir = tempDir("insitu");
  const fs::path run = dir / "run";
  const Run r = mdRun(run, "--analyze");
  INFO(r.output);
  REQUIRE(r.status == 0);
  REQUIRE(fs::exists(run / "analysis" / "S_t.csv"));
  REQUIRE(fs::exists(run / "analysis" / "analysis.h5"));
  const Run a = runGranagg("analyze " + run.string() + " -q --out " + (dir / "offline").string());
  INFO(a.output);
  REQUIRE(a.status == 0);
  requireSameCsvs(dir / "offline", run / "analysis");
  // the frame times: those of the trajectory (10 per decade from t = 0.01, and t = 0)
  CHECK(cells(run / "analysis" / "per_run" / "S_t.csv").size() == 1 + 1 + 31);

  SECTION("with output.trajectory = false it stores no frame and gives the same tables") {
    const fs::path bare = dir / "bare";
    const Run b = mdRun(bare, "--analyze --set output.trajectory=false");
    INFO(b.output);
    REQUIRE(b.status == 0);
    requireSameCsvs(run / "analysis", bare / "analysis");
    CHECK(fs::file_size(bare / "traj.h5") * 5 < fs::file_size(run / "traj.h5"));
    // granagg analyze takes such a run from its in-situ state (the ensembles of granagg pair)
    const Run o = runGranagg("analyze " + bare.string() + " -q --out " + (dir / "o2").string());
    INFO(o.output);
    REQUIRE(o.status == 0);
    requireSameCsvs(bare / "analysis", dir / "o2");
  }
  SECTION("a run stopped by SIGTERM, or killed by SIGKILL, and continued ends with the same tables") {
    for (const std::string sig : {"TERM", "KILL"}) {
      INFO("SIG" << sig);
      const fs::path part = dir / ("part" + sig);
      // a checkpoint every 40 steps: stop once the second analysis state exists, mid-run
      const std::string cmd =
          std::string(GRANAGG_BINARY) +
          " md --preset quick --set system.N=1000 --set run.t_end=10 --seed 5 -q --threads 1 "
          "--analyze --set output.checkpoint_interval=40 --out " + part.string();
      const Run s = sh(cmd + " & p=$!; while [ ! -e " +
                       (part / "analysis-state.prev.h5").string() +
                       " ] && kill -0 $p 2>/dev/null; do sleep 0.01; done; kill -" + sig +
                       " $p; wait $p; echo rc=$?");
      INFO(s.output);
      REQUIRE_FALSE(fs::exists(part / "analysis"));  // stopped before its end
      const Run c = runGranagg("md --restart " + part.string() + " --force -q --threads 1");
      INFO(c.output);
      REQUIRE(c.status == 0);
      requireSameCsvs(run / "analysis", part / "analysis");
    }
  }
  fs::remove_all(dir);
}

TEST_CASE("bad [analysis] input is refused before the first step, with exit 2 naming the key",
          "[cli][insitu]") {
  const fs::path dir = tempDir("insitu_bad");
  struct Case {
    std::string set, says;
  };
  const std::vector<Case> cases = {
      {"analysis.grid_spacng=2", "unknown key 'analysis.grid_spacng'"},
      {"analysis.grid_spacing=-1", "analysis.grid_spacing must be > 0"},
      {"analysis.grid_assign=tsc", "analysis.grid_assign must be ngp or cic"},
      {"analysis.tolerance=abc", "analysis.tolerance must be a number"},
      {"analysis.fit_window=[1.0]", "analysis.fit_window must be two times"},
      {"analysis.msd_origins=some", "analysis.msd_origins must be auto, t0 or all"},
      {"analysis.msd_origins=all", "analysis.msd_origins = \"all\" needs evenly spaced frames"},
  };
  for (const auto& c : cases) {
    INFO(c.set);
    const fs::path out = dir / "o";
    const Run r = mdRun(out, "--analyze --set " + c.set);
    INFO(r.output);
    CHECK(r.status == 2);
    CHECK_THAT(r.output, Catch::Contains(c.says) && Catch::Contains("--set " + c.set));
    CHECK_FALSE(fs::exists(out));  // nothing written
  }
  // in a file, the message names the line
  std::ofstream(dir / "a.toml") << "[system]\nN = 500\n[output]\nanalyze = true\n"
                                   "[analysis]\nslope_ratio = 0.5\n";
  const Run r = runGranagg("md --config " + (dir / "a.toml").string() + " -q --out " +
                           (dir / "f").string());
  INFO(r.output);
  CHECK(r.status == 2);
  CHECK_THAT(r.output, Catch::Contains("a.toml:6:15: analysis.slope_ratio must be > 1"));
  CHECK_FALSE(fs::exists(dir / "f"));
  const Run restart = runGranagg("md --restart " + (dir / "f").string() + " --analyze");
  CHECK(restart.status == 2);
  CHECK_THAT(restart.output, Catch::Contains("--analyze cannot be combined with --restart"));
  fs::remove_all(dir);
}
