// What a study's summary says (study/Summary.h), on hand-made tables and results: a z only where
// S(t) is a power law, "no power law (local slope rising)" where the local slope rises, "not
// resolved with N runs" where an interval includes 0, a full-curve beta at a bound of its search
// range (as a number or as null) never reported as a value, and summary.txt in the results folder.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "TestUtil.h"
#include "study/PairConfig.h"
#include "study/PairStudy.h"
#include "study/Summary.h"

namespace fs = std::filesystem;
using namespace granagg::study;
using granagg::test::slurp;
using granagg::test::spit;
using granagg::test::tempDir;

namespace {

/// Log-spaced times 1..t_end, 10 per decade.
std::vector<double> logTimes(double t_end) {
  std::vector<double> t;
  for (int k = 0; k <= static_cast<int>(std::round(10 * std::log10(t_end))); ++k)
    t.push_back(std::pow(10.0, k / 10.0));
  return t;
}

/// Services whose regime classifier answers `regime` (the real one is analysis/'s).
StudyServices servicesWithRegime(const std::string& regime) {
  StudyServices s;
  s.flat_slope_tolerance = 0.25;
  s.classify_growth = [regime](const std::vector<double>&, const std::vector<double>&,
                               const std::vector<double>&) {
    GrowthSummary g;
    g.regime = regime;
    g.growth_factor = 50;
    return g;
  };
  return s;
}

/// An ensemble in a scaling regime with fit-beta's z over [30, 100].
EnsembleFindings scalingEnsemble(double z, double low, double high, int runs) {
  EnsembleFindings e;
  e.r.K = 5;
  e.r.regime.regime = "scaling";
  e.r.regime.growth_factor = 12;
  e.r.onset = 33;
  e.r.t_last = 100;
  e.r.fz = z, e.r.fz_low = low, e.r.fz_high = high, e.r.w0 = 30, e.r.w1 = 100;
  e.r.z = 9.9, e.r.z_low = 9.8, e.r.z_high = 10.0, e.r.fit_t_min = 10, e.r.fit_t_max = 100;
  e.runs = runs;
  e.N = 2000;
  e.t_end = 100;
  e.fit_status = "done";
  e.paper_z = 1.49;
  e.paper_z_pm = 0.012;
  return e;
}

std::string joined(const std::vector<std::string>& lines) {
  std::string s;
  for (const auto& l : lines) s += l + "\n";
  return s;
}

}  // namespace

TEST_CASE("summary: the local slope over the last half decade, rising, flat or falling",
          "[study][summary]") {
  const std::vector<double> t = logTimes(1000);  // last half decade: t = 316..1000, 6 samples
  std::vector<double> S(t.size(), 2.0), rising, flat, falling;
  for (double x : t) {
    rising.push_back(std::log10(x));           // 2.5 .. 3.0 over the last half decade
    flat.push_back(1.5 + 0.01 * std::sin(x));  // within 1 % of 1.5
    falling.push_back(4.0 - std::log10(x));
  }
  const SlopeTrend r = slopeTrend(t, S, rising, 0.25 * 0.1);  // spread 0.5 > 0.025 x mean
  CHECK(r.n == 6);
  CHECK(r.t0 == Approx(std::pow(10.0, 2.5)));
  CHECK(r.t1 == Approx(1000));
  CHECK(r.first == Approx(2.5));
  CHECK(r.last == Approx(3.0));
  CHECK(r.min == Approx(2.5));
  CHECK(r.max == Approx(3.0));
  CHECK(r.direction == "rising");
  CHECK(slopeTrend(t, S, flat, 0.25).direction == "flat");
  CHECK(slopeTrend(t, S, falling, 0.25 * 0.1).direction == "falling");
  // up and down by the same amount: neither
  std::vector<double> zigzag;
  for (std::size_t k = 0; k < t.size(); ++k) zigzag.push_back(k % 2 ? 2.0 : 1.0);
  CHECK(slopeTrend(t, S, zigzag, 0.25).direction == "varying");
  // the stretch ends at the last finite S, not at the last row
  std::vector<double> S_cut = S;
  S_cut.back() = NAN;
  CHECK(slopeTrend(t, S_cut, rising, 0.25).t1 == Approx(t[t.size() - 2]));
  // fewer than 3 slopes: no direction claimed
  std::vector<double> sparse(t.size(), NAN);
  sparse.back() = 1.0;
  CHECK(slopeTrend(t, S, sparse, 0.25).direction.empty());
}

TEST_CASE("summary: a rising local slope gives no z, whatever the fits say", "[study][summary]") {
  EnsembleFindings e = scalingEnsemble(1.354, 1.1, 1.6, 3);
  e.r.regime.regime = "onset";
  e.r.slope.n = 6, e.r.slope.direction = "rising";
  e.r.slope.first = 1.16, e.r.slope.last = 2.01, e.r.slope.t0 = 31.6, e.r.slope.t1 = 100;
  const ReportedZ z = reportedZ(e.r, 3);
  CHECK(z.status == "no power law");
  CHECK(z.text == "no power law (local slope rising)");
  CHECK(std::isnan(z.value));
  const std::string lines = joined(ensembleLines(e));
  CHECK_THAT(lines, Catch::Contains("  z: no power law (local slope rising)\n"));
  CHECK_THAT(lines, Catch::Contains("local slope: 1.16 at t = 31.6 -> 2.01 at t = 100"));
  CHECK_THAT(lines, Catch::Contains("beta: none"));
  CHECK_THAT(lines, !Catch::Contains("1.35"));  // neither fit's z is printed
  CHECK_THAT(lines, !Catch::Contains("9.9"));
  StudyFindings f;
  f.ensembles = {e};
  CHECK_THAT(joined(verdictLines(f)), Catch::Contains("not a power law yet (local slope rising"));
}

TEST_CASE("summary: an interval over few runs that includes zero is not resolved",
          "[study][summary]") {
  const EnsembleFindings e = scalingEnsemble(1.354, -0.264, 2.972, 3);
  const ReportedZ z = reportedZ(e.r, 3);
  CHECK(z.status == "not resolved");
  CHECK_THAT(z.text, Catch::StartsWith("not resolved with 3 runs"));
  const std::string lines = joined(ensembleLines(e));
  CHECK_THAT(lines, Catch::Contains("  z: not resolved with 3 runs"));
  CHECK_THAT(lines, !Catch::Contains("-0.26"));
  CHECK_THAT(lines, !Catch::Contains("1.35"));
  // a resolved one: one z, with its window and interval, from fit-beta (not analyze's 9.9)
  const EnsembleFindings good = scalingEnsemble(1.5, 1.4, 1.6, 3);
  const ReportedZ zg = reportedZ(good.r, 3);
  CHECK(zg.status == "power law");
  CHECK(zg.source == "fit-beta");
  CHECK_THAT(zg.text, Catch::StartsWith("z = 1.50 [1.40, 1.60] over t = 30..100"));
  CHECK_THAT(joined(ensembleLines(good)), !Catch::Contains("9.9"));
  // no fit-beta z: analyze's, with analyze's window
  EnsembleFindings nofit = good;
  nofit.r.fz = NAN;
  nofit.r.z = 1.3, nofit.r.z_low = 1.2, nofit.r.z_high = 1.4;
  CHECK(reportedZ(nofit.r, 3).source == "analyze");
  CHECK_THAT(reportedZ(nofit.r, 3).text,
             Catch::StartsWith("z = 1.30 [1.20, 1.40] over t = 10..100"));
}

TEST_CASE("summary: a full-curve beta at a bound of its range is not determined, number or null",
          "[study][summary]") {
  const fs::path dir = tempDir("summary_beta");
  const StudyServices s = servicesWithRegime("scaling");
  fs::create_directories(dir / "fit" / "K5");
  const auto fitWith = [&](const nlohmann::json& extra) {
    nlohmann::json j{{"z", 1.5},
                     {"z_low", 1.4},
                     {"z_high", 1.6},
                     {"t0", 30},
                     {"t1", 100},
                     {"beta_min", 1.5},
                     {"beta_max", 6.0},
                     {"beta_fit_low", nullptr},
                     {"beta_fit_high", nullptr}};
    j.update(extra);
    spit(dir / "fit" / "K5" / "fit_beta.json", j.dump());
    return readEnsemble(dir, 5, s);
  };
  // written as the number at the bound, without the flag (older fit-beta)
  EnsembleResult r = fitWith({{"beta_fit", 5.999978946946012}});
  CHECK(r.has_fit);
  CHECK_FALSE(r.bf_determined);
  CHECK(std::isnan(r.bf));
  CHECK_FALSE(fitWith({{"beta_fit", 1.5}}).bf_determined);  // the lower bound
  // written as null
  CHECK_FALSE(fitWith({{"beta_fit", nullptr}, {"beta_fit_determined", false}}).bf_determined);
  // flagged undetermined although inside the range
  CHECK_FALSE(fitWith({{"beta_fit", 3.0}, {"beta_fit_determined", false}}).bf_determined);
  // inside the range: a result
  r = fitWith({{"beta_fit", 3.2},
               {"beta_fit_low", 2.9},
               {"beta_fit_high", 3.5},
               {"beta_fit_determined", true}});
  CHECK(r.bf_determined);
  CHECK(r.bf == 3.2);
  // the summary line says "not determined" and gives no number for it
  EnsembleFindings e = scalingEnsemble(1.5, 1.4, 1.6, 3);
  e.r.bf = NAN, e.r.bf_determined = false, e.r.ba = 3.0, e.r.ba_low = 2.5, e.r.ba_high = 3.5;
  const std::string lines = joined(ensembleLines(e));
  CHECK_THAT(lines, Catch::Contains("full-curve fit: not determined"));
  CHECK_THAT(lines, !Catch::Contains("6.00"));
  fs::remove_all(dir);
}

TEST_CASE("summary: the verdict leads, with the validation study's conclusion and the mean field",
          "[study][summary]") {
  StudyFindings f;
  f.name = "demo";
  f.out = "/tmp/results/demo x";
  f.bytes = 566ull << 20;
  EnsembleFindings neutral = scalingEnsemble(NAN, NAN, NAN, 3);
  neutral.r.K = 0, neutral.r.regime.regime = "onset", neutral.r.onset = 513;
  neutral.paper_z = 1.21, neutral.paper_z_pm = 0.04;
  neutral.r.slope.n = 6, neutral.r.slope.direction = "rising";
  neutral.validation.found = true;
  neutral.validation.runs = 20, neutral.validation.N = 50016, neutral.validation.t_end = 1000;
  neutral.validation.zloc_min = 0.38, neutral.validation.zloc_max = 4.08;
  EnsembleFindings charged = neutral;
  charged.r.K = 5, charged.r.onset = 33;
  charged.paper_z = 1.49, charged.paper_z_pm = 0.012;
  charged.validation.N = 10000, charged.validation.runs = 5;
  f.ensembles = {neutral, charged};
  f.meanfield = {{2, 250, 1.186, 1.19}, {3, 1650, 1.487, 1.49}};
  const std::string text = summaryText(f);
  INFO(text);
  CHECK_THAT(text, Catch::Contains("VERDICT\n- The neutral gas (K = 0) aggregates from t_c = 513"));
  CHECK(text.find("VERDICT") < text.find("PER ENSEMBLE"));
  CHECK_THAT(text, Catch::Contains("15.5 times earlier than the neutral gas"));
  std::string flat = text;  // the lines joined again where wrap() broke them
  for (std::size_t k; (k = flat.find("\n  ")) != std::string::npos;) flat.replace(k, 3, " ");
  CHECK_THAT(flat, Catch::Contains("the paper's growth exponents (1.21 neutral, 1.49 charged) are "
                                   "not reproduced"));
  CHECK_THAT(text, Catch::Contains("1.186 at S ~ 250 (beta = 2)"));
  CHECK_THAT(text, Catch::Contains("566 MiB"));
  CHECK_THAT(text, Catch::EndsWith("Delete them all with:\n  rm -r '/tmp/results/demo x'\n"));
  for (std::size_t a = 0, b; a < text.size(); a = b + 1) {  // no line past 100 columns
    b = text.find('\n', a);
    CHECK(b - a <= 100);
  }
}

TEST_CASE("summary: a study writes summary.txt beside summary.json", "[study][summary]") {
  const fs::path dir = tempDir("summary_txt");
  StudyServices s = servicesWithRegime("none");
  s.exe = "/bin/true";
  s.command_line = "test";
  s.find_md_preset = [](const std::string& name) { return "/presets/" + name + ".toml"; };
  s.resolve_md = [](const std::string& base, const std::vector<std::string>&) {
    MdPlan p;
    p.toml = base;
    p.N = 100;
    p.t_end = 1;
    p.steps = 10;
    return p;
  };
  PairConfig c = parsePairConfig(std::string(GRANAGG_SOURCE_DIR) + "/data/pair/tiny.toml");
  c.runs = 1;
  StudyRequest req;
  req.out = (dir / "out").string();
  req.quiet = true;
  req.no_figures = true;
  PairStudy study(c, req, s);
  try {
    study.run();
  } catch (const std::runtime_error&) {  // the stand-in analysis writes no tables
  }
  const std::string text = slurp(dir / "out" / "summary.txt");
  CHECK_THAT(text, Catch::StartsWith("granagg pair study 'tiny': summary"));
  CHECK_THAT(text, Catch::Contains("K = 0, neutral gas: 1 run of N = 100 to t = 1"));
  CHECK_THAT(text, Catch::Contains("rm -r "));
  const auto j = nlohmann::json::parse(slurp(dir / "out" / "summary.json"));
  CHECK(j.at("verdict").size() >= 2);
  CHECK(j.at("ensembles")[0].at("z_reported").at("status") == "unknown");  // no S_t.csv
  fs::remove_all(dir);
}

TEST_CASE("figures: no power law and no mean-field curve where they are not determined",
          "[study][summary]") {
  // scripts/plot_figures.py's Figs. 5 and 6 on a hand-made folder: S(t) with a rising local slope
  // and fit-beta's curve at beta = 6, the bound of its range. Neither the power-law line nor the
  // fitted mean field may be drawn: for summary.json as written now (z_reported, null beta) and
  // as written before (beta at the bound as a number, no z_reported).
  const fs::path dir = tempDir("summary_figures");
  fs::create_directories(dir / "analysis" / "K0");
  fs::create_directories(dir / "fit" / "K0");
  std::string st = "t,S_grid_mean,S_grid_se,z_local_grid_of_mean\n";
  std::string fc = "t,S_md,S_mf_fitted\n";
  for (int k = 0; k <= 30; ++k) {
    const double t = std::pow(10.0, k / 10.0), S = std::exp(0.02 * t / 10);  // z rising
    st += std::to_string(t) + "," + std::to_string(S) + ",0.01," + std::to_string(0.002 * t) + "\n";
    fc += std::to_string(t) + "," + std::to_string(S) + "," + std::to_string(S * 1.01) + "\n";
  }
  spit(dir / "analysis" / "K0" / "S_t.csv", st);
  spit(dir / "fit" / "K0" / "fit_curve.csv", fc);
  const nlohmann::json older{{"name", "K0"},
                             {"K", 0.0},
                             {"regime", "onset"},
                             {"z_analyze", {{"value", 1.354}, {"low", -0.264}, {"high", 2.972}}},
                             {"z_analyze_window", {100.0, 1000.0}},
                             {"beta_fit", {{"value", 6.0}, {"low", nullptr}, {"high", nullptr}}},
                             {"beta_fit_determined", false}};
  nlohmann::json now = older;
  now["beta_fit"]["value"] = nullptr;
  now["z_reported"] = {{"status", "no power law"},
                       {"text", "no power law (local slope rising)"},
                       {"window", {nullptr, nullptr}}};
  const std::string check =
      "import sys; sys.path.insert(0, '" + std::string(GRANAGG_SOURCE_DIR) +
      "/scripts')\n"
      "import matplotlib.pyplot as plt, plot_figures as pf\n"
      "st = pf.Study('" +
      dir.string() +
      "')\n"
      "for f in (pf.fig5, pf.fig6):\n"
      "    fig = plt.figure(); f(st, fig)\n"
      "    labels = [l.get_label() for ax in fig.axes for l in ax.lines]\n"
      "    bad = [l for l in labels if 'power law' in l and 'no power law' not in l or\n"
      "           'beta =' in l and 'mean field beta =' not in l]\n"
      "    print(f.__name__, labels)\n"
      "    assert not bad, bad\n"
      "print('no undetermined curve')\n";
  spit(dir / "check.py", check);
  for (const nlohmann::json& e : {older, now}) {
    INFO(e.dump());
    spit(dir / "summary.json", nlohmann::json{{"ensembles", {e}}}.dump());
    const std::string cmd = "/usr/bin/python3 " + (dir / "check.py").string() + " > " +
                            (dir / "out.txt").string() + " 2>&1";
    const int status = std::system(cmd.c_str());
    INFO(slurp(dir / "out.txt"));
    CHECK(status == 0);
    CHECK_THAT(slurp(dir / "out.txt"), Catch::Contains("no undetermined curve"));
  }
  fs::remove_all(dir);
}
