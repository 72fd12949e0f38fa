// `granagg fit-beta`: bad inputs (exit status 2 and a message naming the problem), z of an exact
// power law, beta recovered from noisy mean-field S(t) made by `granagg smol`, and the three input
// layouts (CSV with one or several S columns, an analyze folder with per-run tables, analysis.h5).
#include <catch2/catch.hpp>

#include "RunCommand.h"

#include <unistd.h>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "common/Csv.h"
#include "common/Hdf5.h"

#include "TestUtil.h"

using granagg::test::slurp;
using granagg::test::tempDir;

namespace fs = std::filesystem;

namespace {

/// Writes a CSV: header row, then rows.
void writeCsv(const fs::path& p, const std::string& header,
              const std::vector<std::vector<double>>& rows, const std::string& comment = "") {
  std::ofstream o(p);
  if (!comment.empty()) o << "# " << comment << "\n";
  o << header << "\n";
  o.precision(17);
  for (const auto& r : rows) {
    for (std::size_t j = 0; j < r.size(); ++j) o << (j ? "," : "") << r[j];
    o << "\n";
  }
}

/// Standard normal deviates by Box-Muller from std::mt19937_64 (bit-exact on every platform, unlike
/// std::normal_distribution).
struct Normal {
  std::mt19937_64 g;
  explicit Normal(std::uint64_t seed) : g(seed) {}
  double operator()() {
    const double u1 = (static_cast<double>(g() >> 11) + 0.5) / 9007199254740992.0;
    const double u2 = static_cast<double>(g() >> 11) / 9007199254740992.0;
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
  }
};

/// One row of a CSV written by fit-beta, by column name.
std::map<std::string, double> readRow(const fs::path& p) {
  const auto t = granagg::common::readCsv(p.string());
  REQUIRE(t.rows.size() == 1);
  std::map<std::string, double> m;
  for (std::size_t j = 0; j < t.columns.size(); ++j) m[t.columns[j]] = t.rows[0][j];
  return m;
}

/// Mean-field S(t) for `beta` from `granagg smol` (sectional, grid ratio 1.05 -- finer than
/// fit-beta's own curves), 20 samples per decade from t = 0.05 to S = 2000: (t, S).
std::vector<std::pair<double, double>> smolCurve(const fs::path& dir, double beta) {
  const fs::path out = dir / "smol.csv";
  const Run r = runGranagg("smol --beta " + granagg::common::formatReal(beta) +
                           " --t-min 0.05 --t-end 1e6 --per-decade 20 --s-end 2000 -q --force -o " +
                           out.string());
  INFO(r.output);
  REQUIRE(r.status == 0);
  const auto t = granagg::common::readCsv(out.string());
  std::vector<std::pair<double, double>> c;
  for (const auto& row : t.rows) c.emplace_back(row[t.column("t")], row[t.column("S")]);
  return c;
}

}  // namespace

TEST_CASE("fit-beta rejects bad input with exit status 2 and a one-line message",
          "[cli][fitbeta]") {
  const fs::path dir = tempDir("bad");
  std::vector<std::vector<double>> good;
  for (int i = 1; i <= 20; ++i) good.push_back({0.5 * i, std::pow(0.5 * i, 1.3)});
  writeCsv(dir / "good.csv", "t,S", good);
  writeCsv(dir / "no_t.csv", "time,S", good);
  writeCsv(dir / "two.csv", "t,A,B",
           {{1, 1, 1}, {2, 2, 2}, {3, 3, 3}, {4, 4, 4}, {5, 5, 5}, {6, 6, 6}});
  auto bad = good;
  bad[7][0] = bad[6][0];
  writeCsv(dir / "tie.csv", "t,S", bad);
  bad = good;
  std::swap(bad[3], bad[4]);
  writeCsv(dir / "back.csv", "t,S", bad);
  bad = good;
  bad[5][1] = 0.0;
  writeCsv(dir / "zero.csv", "t,S", bad);
  bad = good;
  bad[9][1] = -2.0;
  writeCsv(dir / "neg.csv", "t,S", bad);
  writeCsv(dir / "short.csv", "t,S", {{1, 1}, {2, 2}, {3, 3}, {4, 4}});
  fs::create_directories(dir / "emptydir");
  fs::create_directories(dir / "taken");
  std::ofstream(dir / "taken" / "fit_beta.csv") << "x\n";

  const std::string out = " -q --no-curve-fit --out " + (dir / "o").string();
  const std::string g = (dir / "good.csv").string();
  struct Case {
    std::string args, says;
  };
  for (const Case& c : {
           Case{(dir / "no_t.csv").string() + out, "no column 't'"},
           Case{(dir / "two.csv").string() + out, "--column"},
           Case{g + " --column X" + out, "no column 'X'"},
           Case{(dir / "tie.csv").string() + out, "t must increase strictly"},
           Case{(dir / "back.csv").string() + out, "t must increase strictly"},
           Case{(dir / "zero.csv").string() + out, "S must be positive"},
           Case{(dir / "neg.csv").string() + out, "S must be positive"},
           Case{(dir / "short.csv").string() + out, "too few points"},
           Case{g + " --window 1 2" + out, "too few points in the window"},
           Case{g + " --window 5 2" + out, "T0 < T1"},
           Case{g + " --window 3" + out, "--window"},
           Case{g + " --beta-min 0.5" + out, "--beta-min"},
           Case{g + " --beta-max 40" + out, "--beta-max"},
           Case{g + " --beta-min 4 --beta-max 3" + out, "--beta-max"},
           Case{(dir / "nosuch.csv").string() + out, "nosuch.csv"},
           Case{(dir / "emptydir").string() + out, "S_t.csv"},
           Case{g + " -q --no-curve-fit --out " + (dir / "taken").string(), "--force"},
       }) {
    INFO(c.args);
    const Run r = runGranagg("fit-beta " + c.args);
    INFO(r.output);
    CHECK(r.status == 2);
    CHECK_THAT(r.output, Catch::Contains(c.says));
    CHECK(std::count(r.output.begin(), r.output.end(), '\n') == 1);
    CHECK_THAT(r.output, Catch::StartsWith("granagg: error:"));
  }
  CHECK_FALSE(fs::exists(dir / "o"));  // nothing written on bad input
  fs::remove_all(dir);
}

TEST_CASE("fit-beta recovers z of an exact power law exactly", "[cli][fitbeta]") {
  // S = 2 t^1.3 with a t = 0 row (left out): z exact to 1e-10 and inside its interval; the
  // automatic window spans every sample with t > 0.
  const fs::path dir = tempDir("power");
  std::vector<std::vector<double>> rows{{0.0, 1.0}};
  for (int i = 0; i <= 40; ++i) {
    const double t = std::pow(10.0, 2.0 * i / 40.0);
    rows.push_back({t, 2.0 * std::pow(t, 1.3)});
  }
  writeCsv(dir / "S.csv", "t,S", rows);
  const Run r = runGranagg("fit-beta " + (dir / "S.csv").string() + " --no-curve-fit --out " +
                           (dir / "o").string());
  INFO(r.output);
  REQUIRE(r.status == 0);
  CHECK_THAT(r.output, Catch::Contains("paper: 1.21 +- 0.04 neutral, 1.49 +- 0.012 charged"));
  CHECK_THAT(r.output, Catch::Contains("t = 0 left out"));
  const auto row = readRow(dir / "o" / "fit_beta.csv");
  CHECK(std::fabs(row.at("z") - 1.3) < 1e-10);
  CHECK(row.at("z_low") <= 1.3);
  CHECK(1.3 <= row.at("z_high"));
  CHECK(row.at("n_points") == 41);
  CHECK(row.at("t0") == Approx(1.0));
  CHECK(row.at("beta_from_z") >
        1.5);  // S = 2..800: the mean field's z over that range is 1.3 near beta = 3.5
  CHECK(row.at("beta_from_z") < 6.0);
  CHECK(std::isnan(row.at("beta_fit")));  // --no-curve-fit
  CHECK_FALSE(fs::exists(dir / "o" / "fit_curve.csv"));
  const std::string json = slurp(dir / "o" / "fit_beta.json");
  CHECK_THAT(json, Catch::Contains("\"beta_fit\": null"));
  CHECK_THAT(json, Catch::Contains("\"z_interval_method\": \"student-t\""));
  // the same folder again: refused without --force, accepted with it
  CHECK(runGranagg("fit-beta " + (dir / "S.csv").string() + " -q --no-curve-fit --out " +
                   (dir / "o").string())
            .status == 2);
  CHECK(runGranagg("fit-beta " + (dir / "S.csv").string() + " -q --no-curve-fit --force --out " +
                   (dir / "o").string())
            .status == 0);
  fs::remove_all(dir);
}

TEST_CASE("fit-beta writes no number for a beta_fit at a bound of the search range",
          "[cli][fitbeta][slow]") {
  // S = t^2.6 grows faster than every mean-field curve in [1.5, 6] (z = 3 beta / (beta + 3) <= 2):
  // the curve fit ends at beta = 6, which is the search bound, not a result: no number for it in
  // fit_beta.csv and fit_beta.json.
  const fs::path dir = tempDir("bound");
  std::vector<std::vector<double>> rows;
  for (int i = 0; i < 30; ++i) {
    const double t = std::pow(10.0, 0.1 * i);
    rows.push_back({t, std::pow(t, 2.6)});
  }
  writeCsv(dir / "S.csv", "t,S", rows);
  const Run r = runGranagg("fit-beta " + (dir / "S.csv").string() + " --out " +
                           (dir / "o").string());
  INFO(r.output);
  REQUIRE(r.status == 0);
  CHECK_THAT(r.output, Catch::Contains("not determined (at the bound 6"));
  const auto row = readRow(dir / "o" / "fit_beta.csv");
  CHECK(std::isnan(row.at("beta_fit")));
  CHECK(std::isnan(row.at("beta_fit_low")));
  CHECK(std::isnan(row.at("beta_fit_high")));
  CHECK(row.at("beta_fit_determined") == 0.0);
  const std::string json = slurp(dir / "o" / "fit_beta.json");
  CHECK_THAT(json, Catch::Contains("\"beta_fit\": null"));
  CHECK_THAT(json, Catch::Contains("\"beta_fit_determined\": false"));
  CHECK_THAT(json, Catch::Contains("\"beta_max\": 6.0"));  // the bound is still recorded
  // no curve drawn for an undetermined beta; the data and the beta = 2, 3 curves stay
  const auto curve = granagg::common::readCsv((dir / "o" / "fit_curve.csv").string());
  REQUIRE(curve.rows.size() == rows.size());
  for (const auto& c : curve.rows) {
    CHECK(std::isnan(c[curve.column("S_mf_fitted")]));
    CHECK(std::isfinite(c[curve.column("S_md")]));
    CHECK(std::isfinite(c[curve.column("S_mf_beta3")]));
  }
}

TEST_CASE("fit-beta names the runs and times whose S is NaN when too few samples are left",
          "[cli][fitbeta]") {
  // What `pair --preset tiny` meets at K = 5: S_grid is NaN (no occupied grid cell) in run 0 at
  // most frames and in run 1 at some. The error says which rows went and why.
  const fs::path dir = tempDir("nan-runs");
  std::vector<std::vector<double>> rows;
  const double nan = std::nan("");
  for (int run = 0; run < 2; ++run)
    for (int k = 0; k <= 8; ++k) {
      const double t = 0.1 * k;
      const bool missing = run == 0 ? (k >= 1 && k <= 7) : (k == 5 || k == 6 || k == 8);
      rows.push_back({static_cast<double>(run), t, missing ? nan : 1.0 + t});
    }
  writeCsv(dir / "S.csv", "run,t,S_grid", rows);
  const Run r = runGranagg("fit-beta " + (dir / "S.csv").string() + " -q --no-curve-fit --out " +
                           (dir / "o").string());
  INFO(r.output);
  CHECK(r.status == 2);
  // rows at t = 0.1 .. 0.8 all miss S in one run or the other: none is left
  CHECK_THAT(r.output, Catch::Contains("too few points (0 usable samples, at least 5 needed"));
  CHECK_THAT(r.output, Catch::Contains("1 row(s) at t = 0 left out"));
  CHECK_THAT(r.output, Catch::Contains("8 row(s) with S_grid = NaN left out (run 0 at 7 time(s), "
                                       "t = 0.1 .. 0.7; run 1 at 3 time(s), t = 0.5 .. 0.8)"));
  CHECK_THAT(r.output, Catch::Contains("no occupied grid cell"));
  CHECK_FALSE(fs::exists(dir / "o"));
}

TEST_CASE("fit-beta reports no z, not a zero-width interval, for an S that does not grow",
          "[cli][fitbeta]") {
  // pair --preset tiny at K = 0: S_grid = 1 at every frame; a fit would say z = 0 [-1e-12, 1e-12].
  const fs::path dir = tempDir("flat");
  std::vector<std::vector<double>> rows;
  for (int k = 1; k <= 10; ++k) rows.push_back({0.5 * k, 1.0});
  writeCsv(dir / "S.csv", "t,S", rows);
  const Run r = runGranagg("fit-beta " + (dir / "S.csv").string() + " --no-curve-fit --out " +
                           (dir / "o").string());
  INFO(r.output);
  REQUIRE(r.status == 0);
  CHECK_THAT(r.output, Catch::Contains("fit-beta: z = n/a"));
  CHECK_THAT(r.output, Catch::Contains("S is 1 at every sample of the window [0.5, 5]: it does "
                                       "not grow, no growth exponent"));
  const auto row = readRow(dir / "o" / "fit_beta.csv");
  CHECK(std::isnan(row.at("z")));
  CHECK(std::isnan(row.at("z_low")));
  CHECK(std::isnan(row.at("z_high")));
  const std::string json = slurp(dir / "o" / "fit_beta.json");
  CHECK_THAT(json, Catch::Contains("\"z\": null"));
  CHECK_THAT(json, Catch::Contains("\"z_note\": \"S is 1 at every sample"));
}

TEST_CASE("fit-beta recovers beta = 2.5 from noisy mean-field S(t) given as CSV",
          "[cli][fitbeta]") {
  // S = S_c S_MF(t / tau_c; 2.5) exp(0.03 eps), S_c = 1.4, tau_c = 6: the curve fit's interval
  // contains 2.5, S_c and tau_c; fit_curve.csv holds the fitted curve beside the data.
  const fs::path dir = tempDir("recover");
  const auto c = smolCurve(dir, 2.5);
  Normal eps(42);
  std::vector<std::vector<double>> rows;
  for (const auto& [t, S] : c) rows.push_back({6.0 * t, 1.4 * S * std::exp(0.03 * eps())});
  writeCsv(dir / "S.csv", "t,S_md", rows, "made by test_fit_beta_cli from granagg smol --beta 2.5");
  const Run r =
      runGranagg("fit-beta " + (dir / "S.csv").string() + " --out " + (dir / "o").string());
  INFO(r.output);
  REQUIRE(r.status == 0);
  CHECK_THAT(r.output, Catch::Contains("beta from the curve fit"));
  CHECK_THAT(r.output, Catch::Contains("mean field z = 1.19 at beta = 2, 1.49 at beta = 3"));
  const auto row = readRow(dir / "o" / "fit_beta.csv");
  CHECK(row.at("beta_fit_low") <= 2.5);
  CHECK(2.5 <= row.at("beta_fit_high"));
  CHECK(row.at("beta_fit_high") - row.at("beta_fit_low") < 0.3);
  CHECK(row.at("S_c_low") <= 1.4);
  CHECK(1.4 <= row.at("S_c_high"));
  CHECK(row.at("tau_c_low") <= 6.0);
  CHECK(6.0 <= row.at("tau_c_high"));
  CHECK(row.at("chi2_dof") == Approx(0.03 * 0.03).epsilon(0.5));
  // beta from z at the data's S: biased low here, since S_c = 1.4 puts the mean field's S
  // range 1.4x higher than the data's; at S / S_c it is consistent.
  CHECK(row.at("beta_from_z") == Approx(2.5).margin(0.3));
  INFO("beta_from_z_scaled " << row.at("beta_from_z_scaled") << " ["
                             << row.at("beta_from_z_scaled_low") << ", "
                             << row.at("beta_from_z_scaled_high") << "]");
  CHECK(row.at("beta_from_z_scaled_low") <= 2.5);
  CHECK(2.5 <= row.at("beta_from_z_scaled_high"));
  const auto curve = granagg::common::readCsv((dir / "o" / "fit_curve.csv").string());
  CHECK(curve.columns ==
        std::vector<std::string>{"t", "S_md", "S_mf_fitted", "S_mf_beta2", "S_mf_beta3"});
  REQUIRE(curve.rows.size() == rows.size());
  for (std::size_t i = 0; i < rows.size(); ++i) {
    CHECK(curve.rows[i][1] == Approx(rows[i][1]).epsilon(1e-12));
    CHECK(std::fabs(std::log(curve.rows[i][2] / rows[i][1])) <
          0.15);  // within 5 sigma of the noise
  }
  // beta = 2 grows more slowly, beta = 3 faster, than the fitted 2.5 at late times
  CHECK(curve.rows.back()[3] < curve.rows.back()[2]);
  CHECK(curve.rows.back()[4] > curve.rows.back()[2]);
  const std::string json = slurp(dir / "o" / "fit_beta.json");
  for (const char* key : {"\"z\":", "\"beta_from_z\":", "\"beta_fit\":", "\"S_c\":", "\"tau_c\":",
                          "\"chi2_dof\":", "\"window_rule\":", "\"paper_z_charged\": 1.49"})
    CHECK_THAT(json, Catch::Contains(key));
  fs::remove_all(dir);
}

TEST_CASE("fit-beta reads run columns, analyze folders and analysis.h5", "[cli][fitbeta][slow]") {
  // Five runs of S_MF(t; 3) with 8 % noise each, as (a) one CSV with columns S_run0..S_run4
  // (--column S_run), (b) an analyze folder (S_t.csv with S_grid_mean, per_run/S_t.csv) and (c) an
  // analysis.h5: the same z and beta from z from all three; intervals by bootstrap over the runs.
  // The curve fit (on (a) only) recovers beta, S_c and tau_c within their intervals.
  const fs::path dir = tempDir("layouts");
  const auto c = smolCurve(dir, 3.0);
  const int R = 5;
  Normal eps(7);
  std::vector<double> t, mean(c.size(), 0.0);
  std::vector<std::vector<double>> runs(R);
  for (const auto& p : c) t.push_back(2.0 * p.first);
  for (int r = 0; r < R; ++r)
    for (std::size_t i = 0; i < c.size(); ++i) {
      runs[r].push_back(c[i].second * std::exp(0.08 * eps()));
      mean[i] += runs[r][i] / R;
    }
  // (a)
  std::vector<std::vector<double>> wide;
  std::string header = "t,S_other";
  for (int r = 0; r < R; ++r) header += ",S_run" + std::to_string(r);
  for (std::size_t i = 0; i < t.size(); ++i) {
    std::vector<double> row{t[i], 1.0};
    for (int r = 0; r < R; ++r) row.push_back(runs[r][i]);
    wide.push_back(row);
  }
  writeCsv(dir / "wide.csv", header, wide);
  // (b) t = 0 rows as analyze writes them; S_grid_mean is the mean of the runs' S_grid
  fs::create_directories(dir / "an" / "per_run");
  std::vector<std::vector<double>> ens{{0.0, 1.0, 0.0, R}}, per;
  for (std::size_t i = 0; i < t.size(); ++i) ens.push_back({t[i], mean[i], 0.1, R});
  writeCsv(dir / "an" / "S_t.csv", "t,S_grid_mean,S_grid_se,n_runs", ens,
           "command = granagg analyze");
  for (int r = 0; r < R; ++r) {
    per.push_back({static_cast<double>(r), 0.0, 1.0});
    for (std::size_t i = 0; i < t.size(); ++i)
      per.push_back({static_cast<double>(r), t[i], runs[r][i]});
  }
  writeCsv(dir / "an" / "per_run" / "S_t.csv", "run,t,S_grid", per);
  // (c)
  {
    namespace h5 = granagg::common::h5;
    h5::silenceErrors();
    h5::Handle f(H5Fcreate((dir / "analysis.h5").c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT));
    REQUIRE(f);
    const std::vector<hsize_t> n{t.size()};
    {
      h5::Handle g = h5::createGroup(f.get(), "/ensemble/S_t", "test");
      h5::writeDataset(g.get(), "t", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, n, t.data(), "test");
      h5::writeDataset(g.get(), "S_grid_mean", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, n, mean.data(),
                       "test");
    }
    for (int r = 0; r < R; ++r) {
      h5::Handle g = h5::createGroup(f.get(), "/runs/" + std::to_string(r) + "/S_t", "test");
      h5::writeDataset(g.get(), "t", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, n, t.data(), "test");
      h5::writeDataset(g.get(), "S_grid", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, n, runs[r].data(),
                       "test");
    }
  }

  std::map<std::string, std::map<std::string, double>> results;
  for (const auto& [name, input] :
       std::map<std::string, std::string>{{"a", (dir / "wide.csv").string() + " --column S_run"},
                                          {"b", (dir / "an").string()},
                                          {"c", (dir / "analysis.h5").string()}}) {
    const Run r = runGranagg("fit-beta " + input + (name == "a" ? "" : " --no-curve-fit") +
                             " --out " + (dir / ("o" + name)).string());
    INFO(name << ": " << r.output);
    REQUIRE(r.status == 0);
    CHECK_THAT(r.output, Catch::Contains("5 runs"));
    CHECK_THAT(r.output, Catch::Contains("bootstrap-runs"));
    results[name] = readRow(dir / ("o" + name) / "fit_beta.csv");
    CHECK(results[name].at("n_runs") == R);
  }
  for (const char* key :
       {"z", "z_low", "z_high", "t0", "t1", "beta_from_z", "beta_from_z_low", "beta_from_z_high"}) {
    INFO(key);
    CHECK(results["b"].at(key) == Approx(results["a"].at(key)).epsilon(1e-12));
    CHECK(results["c"].at(key) == Approx(results["a"].at(key)).epsilon(1e-12));
  }
  const auto& a = results["a"];
  INFO("beta_fit " << a.at("beta_fit") << " [" << a.at("beta_fit_low") << ", "
                   << a.at("beta_fit_high") << "]");
  CHECK(a.at("beta_fit_low") <= 3.0);
  CHECK(3.0 <= a.at("beta_fit_high"));
  CHECK(a.at("beta_fit_high") - a.at("beta_fit_low") < 0.3);
  CHECK(a.at("S_c_low") <= 1.0);
  CHECK(1.0 <= a.at("S_c_high"));
  CHECK(a.at("tau_c_low") <= 2.0);
  CHECK(2.0 <= a.at("tau_c_high"));
  CHECK(a.at("z_low") < a.at("z"));
  CHECK(a.at("z") < a.at("z_high"));
  fs::remove_all(dir);
}
