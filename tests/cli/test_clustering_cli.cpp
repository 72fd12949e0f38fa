// A granular gas that clusters within seconds (issue 14): the path the validation study relies on
// -- `granagg md` -> `granagg analyze` -> S_grid(t), growth factor, onset time -- at test size,
// against an elastic control that must not cluster.
//
// Set-up (measured 2026-12-01, 6 seeds each): N = 2000 spring-dashpot spheres at phi = 0.15
// (L = 19.0), stiffness 2000, to t = 40, grid clusters with the defaults (9^3 cells).
//   restitution 0.3  (strongly dissipative: the clustering instability of a cooling granular gas
//                     sets in within a few cooling times): S_grid grows 5.5-20x per run, ln of the
//                     growth 2.33 +- 0.45 (mean +- sd over runs);
//   restitution 0.99 (nearly elastic control): growth 0.88-1.29 per run, ln 0.14 +- 0.14.
// Three runs (seeds 1-3) of each: the growth of the ensemble-mean S has ln-spread about
// 0.45 / sqrt(3) = 0.26, so the dissipative ensemble stays above 3 (4 sd below its mean) and
// the control below 2 (5 sd above its mean) except with negligible probability -- and the seeds are
// fixed, so the test is deterministic; the thresholds say how far from them a change may move.
#include <catch2/catch.hpp>

#include "RunCommand.h"

#include <unistd.h>
#include <cmath>
#include <filesystem>
#include <map>
#include <string>

#include "common/Csv.h"

namespace fs = std::filesystem;

namespace {

/// Runs three seeds of the gas with restitution `eps` and analyses them; returns fits.csv's row.
std::map<std::string, double> clusteringEnsemble(const fs::path& dir, double eps) {
  std::string runs;
  for (int seed = 1; seed <= 3; ++seed) {
    const fs::path out = dir / ("eps" + std::to_string(eps) + "_seed" + std::to_string(seed));
    const Run r = runGranagg(
        "md --preset haff --set system.N=2000 --set system.phi=0.15 --set contact.stiffness=2000 "
        "--set contact.restitution=" +
        std::to_string(eps) + " --set run.t_end=40 --seed " + std::to_string(seed) +
        " --threads 2 -q --out " + out.string());
    INFO(r.output);
    REQUIRE(r.status == 0);
    runs += " " + out.string();
  }
  const fs::path ana = dir / ("ana_eps" + std::to_string(eps));
  const Run a = runGranagg(
      "analyze" + runs + " --no-particle --fit-window 10 40 --threads 2 -q --out " + ana.string());
  INFO(a.output);
  REQUIRE(a.status == 0);
  const granagg::common::CsvTable fits = granagg::common::readCsv((ana / "fits.csv").string());
  const granagg::common::CsvTable S = granagg::common::readCsv((ana / "S_t.csv").string());
  std::map<std::string, double> out;
  for (std::size_t k = 0; k < fits.columns.size(); ++k) out[fits.columns[k]] = fits.rows.front()[k];
  out["S_end"] = S.rows.back()[S.column("S_grid_mean")];
  out["t_end"] = S.rows.back()[S.column("t")];
  return out;
}

}  // namespace

TEST_CASE("a strongly dissipative gas clusters within seconds, an elastic one does not",
          "[cluster-growth][slow]") {
  const fs::path dir =
      fs::temp_directory_path() / ("granagg_clustering_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);

  const auto d = clusteringEnsemble(dir, 0.3);
  const double growth = d.at("S_end") / d.at("onset_S_base_grid");
  INFO("dissipative: S_base " << d.at("onset_S_base_grid") << ", S(t = 40) " << d.at("S_end")
                              << ", onset " << d.at("onset_time_grid") << ", z " << d.at("z_grid"));
  CHECK(d.at("t_end") == Approx(40.0));
  CHECK(growth > 3.0);
  CHECK(std::isfinite(d.at("onset_time_grid")));
  CHECK(d.at("onset_time_grid") < 40.0);
  CHECK(d.at("z_grid") > 0.0);

  const auto e = clusteringEnsemble(dir, 0.99);
  const double control = e.at("S_end") / e.at("onset_S_base_grid");
  INFO("elastic: S_base " << e.at("onset_S_base_grid") << ", S(t = 40) " << e.at("S_end"));
  CHECK(control < 2.0);
  CHECK(std::isnan(e.at("onset_time_grid")));
  fs::remove_all(dir);
}
