// RunAnalysis, the frame-by-frame analysis behind `granagg analyze` and the in-situ analysis:
// frames added one by one give analyzeRun's tables, and a state saved between two frames and
// restored into a new analysis continues to the same tables, bit for bit, as the analysis that
// never stopped (what a restarted MD run relies on).
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <string>

#include "TestTrajectories.h"
#include "analysis/pipeline/RunAnalysis.h"
#include "analysis/pipeline/RunAnalyzer.h"

#include "TestUtil.h"

using granagg::test::tempDir;

using namespace granagg::analysis;
namespace fs = std::filesystem;

namespace {

bool sameValue(double a, double b) {
  return (std::isnan(a) && std::isnan(b)) || granagg::test::sameBits(a, b);
}

void requireSameTables(const RunResult& a, const RunResult& b) {
  REQUIRE(a.tables.size() == b.tables.size());
  CHECK(a.frames == b.frames);
  CHECK(a.particles == b.particles);
  CHECK(a.notes == b.notes);
  CHECK(a.grid_cells == b.grid_cells);
  for (std::size_t k = 0; k < a.tables.size(); ++k) {
    const Table &ta = a.tables[k], &tb = b.tables[k];
    INFO("table " << ta.name);
    REQUIRE(ta.name == tb.name);
    REQUIRE(ta.columns == tb.columns);
    REQUIRE(ta.rows.size() == tb.rows.size());
    std::size_t differ = 0;
    for (std::size_t r = 0; r < ta.rows.size(); ++r)
      for (std::size_t c = 0; c < ta.rows[r].size(); ++c)
        differ += !sameValue(ta.rows[r][c], tb.rows[r][c]);
    CHECK(differ == 0);
  }
}

/// Evenly spaced frames (so that the all-origins MSD, the largest piece of state, is kept).
std::vector<Frame> frames() {
  std::vector<double> t;
  for (int k = 0; k < 9; ++k) t.push_back(0.1 * k);
  auto fr = testtraj::ballisticGas(400, 8.0, t, 17);  // phi = 0.41: clusters exist
  for (Frame& f : fr)  // the ids an H5MD file gives back (its index order)
    for (std::size_t i = 0; i < f.size(); ++i) f.id[i] = static_cast<std::int64_t>(i);
  return fr;
}

AnalysisOptions options() {
  AnalysisOptions o;
  o.bootstrap_replicates = 50;
  return o;
}

}  // namespace

TEST_CASE("frames added one by one give the tables of analyzeRun on the same trajectory",
          "[analysis][pipeline]") {
  const fs::path dir = tempDir("run_analysis");
  const auto fr = frames();
  const std::string h5 = (dir / "t.h5").string();
  testtraj::writeH5md(h5, fr);
  const RunResult offline = analyzeRun(h5, options());
  RunAnalysis a(options(), h5, "h5md", {});
  for (const Frame& f : fr) a.add(f);
  CHECK(a.frames() == fr.size());
  CHECK(a.lastStep() == fr.back().step);
  const RunResult online = a.finish();
  requireSameTables(offline, online);
  CHECK(online.hasTable("msd_all_origins"));
  fs::remove_all(dir);
}

TEST_CASE("a state saved between frames and restored continues to the uninterrupted tables",
          "[analysis][pipeline]") {
  const fs::path dir = tempDir("run_analysis_state");
  const auto fr = frames();
  RunAnalysis whole(options(), "run", "in-situ", {{"charging.kappa", "0.5"}});
  for (const Frame& f : fr) whole.add(f);
  const RunResult expected = whole.finish();
  CHECK(expected.kappa == 0.5);

  for (std::size_t split : {std::size_t(1), std::size_t(4), fr.size() - 1}) {
    INFO("state saved after " << split << " frames");
    const std::string state = (dir / ("state" + std::to_string(split) + ".h5")).string();
    {
      RunAnalysis first(options(), "run", "in-situ", {{"charging.kappa", "0.5"}});
      for (std::size_t k = 0; k < split; ++k) first.add(fr[k]);
      first.saveState(state, 1000 + static_cast<std::int64_t>(split));
    }
    CHECK(RunAnalysis::stateTag(state) == 1000 + static_cast<std::int64_t>(split));
    CHECK_FALSE(fs::exists(state + ".tmp"));
    RunAnalysis second(options(), "run", "in-situ", {{"charging.kappa", "0.5"}});
    second.restoreState(state);
    CHECK(second.frames() == split);
    for (std::size_t k = split; k < fr.size(); ++k) second.add(fr[k]);
    requireSameTables(expected, second.finish());
  }

  SECTION("a frame whose time does not increase is refused and leaves the state as it was") {
    RunAnalysis a(options(), "run", "in-situ", {{"charging.kappa", "0.5"}});
    a.add(fr[0]);
    a.add(fr[1]);
    CHECK_THROWS_AS(a.add(fr[1]), TrajectoryError);
    for (std::size_t k = 2; k < fr.size(); ++k) a.add(fr[k]);
    requireSameTables(expected, a.finish());
  }
  SECTION("a file that is no state is refused, naming it") {
    const std::string h5 = (dir / "t.h5").string();
    testtraj::writeH5md(h5, fr);
    RunAnalysis c(options(), "run", "in-situ", {});
    CHECK_THROWS_WITH(c.restoreState(h5), Catch::Contains("not a granagg run-analysis state"));
    CHECK_THROWS_AS(RunAnalysis::stateTag(h5), std::runtime_error);
  }
  fs::remove_all(dir);
}
