// Trajectory readers: a LAMMPS dump and an H5MD file of the same frames give identical results;
// truncated and malformed inputs give errors naming the file and the frame; --allow-partial.
#include <catch2/catch.hpp>

#include <unistd.h>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "TestTrajectories.h"
#include "analysis/io/H5mdTrajectory.h"
#include "analysis/io/LammpsDump.h"
#include "analysis/io/TrajectoryReader.h"
#include "analysis/pipeline/RunAnalyzer.h"

#include "TestUtil.h"

using granagg::test::tempDir;

using namespace granagg::analysis;
namespace fs = std::filesystem;

namespace {

/// A small dense gas (so that clusters exist) at log-spaced times.
std::vector<Frame> sampleFrames(std::size_t count = 8) {
  std::vector<double> times{0.0};
  for (std::size_t k = 1; k < count; ++k)
    times.push_back(0.05 * std::pow(1.6, static_cast<double>(k)));
  return testtraj::ballisticGas(400, 8.0, times, 9);  // phi = 0.41: many contacts
}

bool sameValue(double a, double b) { return (std::isnan(a) && std::isnan(b)) || a == b; }

void requireSameTables(const RunResult& a, const RunResult& b) {
  REQUIRE(a.tables.size() == b.tables.size());
  for (std::size_t k = 0; k < a.tables.size(); ++k) {
    const Table &ta = a.tables[k], &tb = b.tables[k];
    INFO("table " << ta.name);
    REQUIRE(ta.name == tb.name);
    REQUIRE(ta.rows.size() == tb.rows.size());
    for (std::size_t r = 0; r < ta.rows.size(); ++r)
      for (std::size_t c = 0; c < ta.rows[r].size(); ++c) {
        INFO("row " << r << ", column " << ta.columns[c]);
        // charge_speed lists particle ids: LAMMPS ids start at 1, H5MD indices at 0
        if (ta.name == "charge_speed" && ta.columns[c] == "id")
          CHECK(tb.rows[r][c] == ta.rows[r][c] + 1);
        else
          CHECK(sameValue(ta.rows[r][c], tb.rows[r][c]));
      }
  }
}

AnalysisOptions fastOptions() {
  AnalysisOptions o;
  o.bootstrap_replicates = 50;
  return o;
}

}  // namespace

TEST_CASE("H5MD and LAMMPS dump of the same frames give identical frames and results",
          "[analysis][io]") {
  const fs::path dir = tempDir("same");
  const auto frames = sampleFrames();
  const std::string h5 = (dir / "t.h5").string(), dump = (dir / "t.dump").string();
  testtraj::writeH5md(h5, frames);
  testtraj::writeLammps(dump, frames);

  auto r1 = openTrajectory(h5);
  auto r2 = openTrajectory(dump);
  CHECK(r1->format() == "h5md");
  CHECK(r2->format() == "lammps-dump");
  CHECK(r1->frameCountHint() == frames.size());
  Frame a, b;
  std::size_t n = 0;
  while (r1->next(a)) {
    REQUIRE(r2->next(b));
    CHECK(a.time == b.time);
    CHECK(a.step == b.step);
    CHECK(a.box == b.box);
    CHECK(a.position == b.position);
    CHECK(a.image == b.image);
    CHECK(a.velocity == b.velocity);
    CHECK(a.charge == b.charge);
    CHECK(a.position == frames[n].position);
    ++n;
  }
  CHECK_FALSE(r2->next(b));
  CHECK(n == frames.size());

  const RunResult ra = analyzeRun(h5, fastOptions()), rb = analyzeRun(dump, fastOptions());
  CHECK(ra.frames == frames.size());
  CHECK(ra.particles == 400);
  requireSameTables(ra, rb);
  // the gas is dense: clusters exist and S > 1
  CHECK(ra.table("S_t").rows.back()[ra.table("S_t").column("S_particle")] > 1.0);

  SECTION(
      "a dump with unwrapped xu yu zu and a shifted box origin gives the same frames to "
      "round-off") {
    const std::string dump2 = (dir / "t2.dump").string();
    testtraj::writeLammps(dump2, frames, -4.0, -1, true);
    auto r3 = openTrajectory(dump2);
    Frame c;
    std::size_t k = 0;
    while (r3->next(c)) {
      for (std::size_t i = 0; i < c.size(); ++i)
        for (int d = 0; d < 3; ++d)
          CHECK(c.unwrapped(i, d) == Approx(frames[k].unwrapped(i, d)).margin(1e-9));
      ++k;
    }
    CHECK(k == frames.size());
  }
  SECTION("H5MD fixed-increment step and time (scalar datasets) are expanded") {
    std::vector<Frame> even;
    for (std::size_t k = 0; k < 4; ++k) {
      even.push_back(frames[0]);
      even.back().time = 0.5 * k;
      even.back().step = 10 * static_cast<std::int64_t>(k);
    }
    const std::string h5b = (dir / "fixed.h5").string();
    testtraj::H5mdLayout lay;
    lay.fixed_step_time = true;
    testtraj::writeH5md(h5b, even, lay);
    H5mdTrajectory r(h5b);
    Frame c;
    std::vector<double> t;
    while (r.next(c)) t.push_back(c.time);
    CHECK(t == std::vector<double>{0.0, 0.5, 1.0, 1.5});
    const RunResult rr = analyzeRun(h5b, fastOptions());
    CHECK(rr.hasTable("msd_all_origins"));  // evenly spaced: the FFT MSD is there
  }
  fs::remove_all(dir);
}

TEST_CASE(
    "a LAMMPS dump cut mid-frame names the file and frame, --allow-partial keeps the frames before",
    "[analysis][io]") {
  const fs::path dir = tempDir("cut");
  const auto frames = sampleFrames(5);
  const std::string dump = (dir / "cut.dump").string();
  testtraj::writeLammps(dump, frames, 0.0, 123);
  try {
    analyzeRun(dump, fastOptions());
    FAIL("no error for a truncated dump");
  } catch (const TrajectoryError& e) {
    CHECK(e.frame() == 4);
    CHECK_THAT(e.what(), Catch::Contains("cut.dump") && Catch::Contains("frame 4") &&
                             Catch::Contains("123 of 400"));
  }
  AnalysisOptions o = fastOptions();
  o.allow_partial = true;
  const RunResult r = analyzeRun(dump, o);
  CHECK(r.partial);
  CHECK(r.frames == 4);
  CHECK(r.table("S_t").rows.size() == 4);
  CHECK_THAT(r.partial_reason, Catch::Contains("frame 4"));

  SECTION("other malformed dumps") {
    auto expectError = [&](const std::string& text, const std::string& says) {
      const std::string p = (dir / "bad.dump").string();
      std::ofstream(p) << text;
      INFO(text);
      CHECK_THROWS_WITH(analyzeRun(p, fastOptions()),
                        Catch::Contains("bad.dump") && Catch::Contains(says));
    };
    const std::string head =
        "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n2\nITEM: BOX BOUNDS pp pp pp\n0 5\n0 5\n0 5\n";
    expectError(head + "ITEM: ATOMS id x y z\n1 1 1 1\n2 2 2 x\n", "values");
    expectError(head + "ITEM: ATOMS id vx vy vz\n1 1 1 1\n2 2 2 2\n", "no positions");
    expectError(
        "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n2\nITEM: BOX BOUNDS ff pp pp\n0 5\n0 5\n0 "
        "5\nITEM: ATOMS id x y z\n",
        "not periodic");
    expectError(
        "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n2\nITEM: BOX BOUNDS pp pp pp\n0 5\n0 6\n0 "
        "5\nITEM: ATOMS id x y z\n",
        "not cubic");
    // errors found after the frame is read name the atom's own line, not the frame's last
    expectError(head + "ITEM: ATOMS id x y z\n1 1 1 1\n1 2 2 2\n",
                "atom id 1 appears twice (also on line 10) (line 11)");
    expectError(head + "ITEM: ATOMS id x y z\n1 1 1 1\n2 nan 2 2\n",
                "non-finite position (line 11)");
    expectError("ITEM: TIMESTEP\n0\nITEM: NUMBER OF", "frame 0");
    // a binary file: said so, its bytes not echoed
    std::string bytes = "\x01\x02\xff\xfe\x89 garbage\n\x7f\x80";
    expectError(bytes, "binary data (not a text dump)");
    const std::string p = (dir / "bad.dump").string();
    try {
      analyzeRun(p, fastOptions());
    } catch (const std::exception& e) {
      CHECK(std::string(e.what()).find('\x89') == std::string::npos);
    }
  }
  fs::remove_all(dir);
}

TEST_CASE("truncated and malformed H5MD files give errors naming the file and the frame",
          "[analysis][io]") {
  const fs::path dir = tempDir("h5bad");
  const auto frames = sampleFrames(4);
  SECTION("a file cut short cannot be opened: the error says so") {
    const std::string full = (dir / "full.h5").string(), cut = (dir / "cut.h5").string();
    testtraj::writeH5md(full, frames);
    const auto size = fs::file_size(full);
    fs::copy_file(full, cut);
    fs::resize_file(cut, size / 2);
    CHECK_THROWS_WITH(analyzeRun(cut, fastOptions()), Catch::Contains("cut.h5") &&
                                                          Catch::Contains("frame 0") &&
                                                          Catch::Contains("cannot open"));
    AnalysisOptions o = fastOptions();
    o.allow_partial = true;  // nothing before frame 0: still an error
    CHECK_THROWS_AS(analyzeRun(cut, o), TrajectoryError);
  }
  SECTION("missing box") {
    testtraj::H5mdLayout lay;
    lay.box = false;
    const std::string p = (dir / "nobox.h5").string();
    testtraj::writeH5md(p, frames, lay);
    CHECK_THROWS_WITH(analyzeRun(p, fastOptions()),
                      Catch::Contains("nobox.h5") && Catch::Contains("box"));
  }
  SECTION("missing position") {
    const std::string p = (dir / "nopos.h5").string();
    {
      granagg::common::h5::Handle f(
          H5Fcreate(p.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT));
      granagg::common::h5::createGroup(f.get(), "particles/all/box", "test");
    }
    CHECK_THROWS_WITH(analyzeRun(p, fastOptions()),
                      Catch::Contains("nopos.h5") && Catch::Contains("position"));
  }
  SECTION(
      "an element with fewer rows than frames fails at the first missing frame; --allow-partial "
      "stops there") {
    testtraj::H5mdLayout lay;
    lay.velocity_rows = 2;
    const std::string p = (dir / "short.h5").string();
    testtraj::writeH5md(p, frames, lay);
    try {
      analyzeRun(p, fastOptions());
      FAIL("no error");
    } catch (const TrajectoryError& e) {
      CHECK(e.frame() == 2);
      CHECK_THAT(e.what(), Catch::Contains("short.h5") && Catch::Contains("frame 2") &&
                               Catch::Contains("velocity"));
    }
    AnalysisOptions o = fastOptions();
    o.allow_partial = true;
    const RunResult r = analyzeRun(p, o);
    CHECK(r.partial);
    CHECK(r.frames == 2);
  }
  SECTION("a non-finite position names the frame") {
    auto bad = frames;
    bad[3].position[7] = std::nan("");
    const std::string p = (dir / "nan.h5").string();
    testtraj::writeH5md(p, bad);
    CHECK_THROWS_WITH(analyzeRun(p, fastOptions()),
                      Catch::Contains("nan.h5") && Catch::Contains("frame 3"));
  }
  SECTION("no velocities or charges: those observables are skipped with a note") {
    testtraj::H5mdLayout lay;
    lay.velocities = false;
    lay.charges = false;
    const std::string p = (dir / "bare.h5").string();
    testtraj::writeH5md(p, frames, lay);
    const RunResult r = analyzeRun(p, fastOptions());
    CHECK_FALSE(r.hasTable("speed_dist"));
    CHECK_FALSE(r.hasTable("charge_speed"));
    CHECK(r.notes.size() >= 2);
  }
  CHECK_THROWS_AS(openTrajectory((dir / "nosuch.h5").string()), std::invalid_argument);
  fs::remove_all(dir);
}

TEST_CASE("ensemble tables average runs with standard errors", "[analysis][ensemble]") {
  Table a("x", "d", {"t", "v"}), b("x", "d", {"t", "v"});
  a.add({0.0, 1.0});
  a.add({1.0, 2.0});
  b.add({0.0, 3.0});
  b.add({1.0000000000001, 6.0});  // matches t = 1 after rounding to 9 digits
  b.add({2.0, 5.0});
  const Table e = ensembleAverage({&a, &b});
  REQUIRE(e.rows.size() == 3);
  CHECK(e.columns == std::vector<std::string>{"t", "v_mean", "v_se", "n_runs"});
  CHECK(e.rows[0][1] == 2.0);
  CHECK(e.rows[0][2] == Approx(1.0));  // sd sqrt(2) / sqrt(2)
  CHECK(e.rows[1][1] == 4.0);
  CHECK(e.rows[2][3] == 1.0);
  CHECK(std::isnan(e.rows[2][2]));
  Table c("N_s", "d", {"t", "s", "N_s"}, 2), d2("N_s", "d", {"t", "s", "N_s"}, 2);
  c.missing_is_zero = d2.missing_is_zero = true;
  c.add({0, 1, 4});
  d2.add({0, 2, 2});
  const Table n = ensembleAverage({&c, &d2});
  CHECK(n.rows[0][2] == 2.0);  // (4 + 0) / 2
  CHECK(n.rows[1][2] == 1.0);  // (0 + 2) / 2
  const Table s = stackRuns({&a, &b});
  CHECK(s.rows.size() == 5);
  CHECK(s.rows[4][0] == 1.0);
}

TEST_CASE("ensemble of runs: per-run tables, means and a bootstrap growth exponent",
          "[analysis][ensemble]") {
  const fs::path dir = tempDir("ens");
  std::vector<RunResult> runs;
  for (unsigned seed : {1u, 2u, 3u}) {
    std::vector<double> times{0.0, 0.1, 0.2, 0.4, 0.8};
    const auto frames = testtraj::ballisticGas(300, 8.0, times, seed);
    const std::string p = (dir / ("r" + std::to_string(seed) + ".h5")).string();
    testtraj::writeH5md(p, frames);
    runs.push_back(analyzeRun(p, fastOptions()));
  }
  const auto ens = analyzeEnsemble(runs, fastOptions());
  bool have_S = false, have_fits = false;
  for (const auto& t : ens) {
    if (t.name == "S_t") {
      have_S = true;
      CHECK(t.rows.size() == 5);
      CHECK(t.rows[0][t.column("n_runs")] == 3.0);
      double mean = 0;
      for (const auto& r : runs)
        mean += r.table("S_t").rows[2][r.table("S_t").column("S_particle")];
      CHECK(t.rows[2][t.column("S_particle_mean")] == Approx(mean / 3));
    }
    if (t.name == "fits") {
      have_fits = true;
      CHECK(t.rows.size() == 1);
      CHECK(t.rows[0][t.column("runs")] == 3.0);
    }
  }
  CHECK(have_S);
  CHECK(have_fits);
  fs::remove_all(dir);
}

TEST_CASE("the charging-rate fit recovers the exponent of d<|q|>/dt, kappa comes from /parameters",
          "[analysis][charge]") {
  // <|q|>(t) = 2 - t^-1.2 exactly: d<|q|>/dt = 1.2 t^-2.2. Frames 20 per decade on [1, 100]; the
  // finite-difference rate at the geometric mid-time carries a relative error O((ln 10 / 20)^2)
  // that is nearly constant in t, so the fitted exponent is -2.2 to ~1e-4.
  const fs::path dir = tempDir("charge");
  std::vector<double> times;
  for (int k = 0; k <= 40; ++k) times.push_back(std::pow(10.0, k / 20.0));
  auto frames = testtraj::ballisticGas(100, 10.0, times, 4);
  for (auto& f : frames)
    for (std::size_t i = 0; i < f.size(); ++i)
      f.charge[i] = (i % 2 ? 1.0 : -1.0) * (2.0 - std::pow(f.time, -1.2));
  testtraj::H5mdLayout lay;
  lay.parameters = {{"charging.kappa", "0.8"}};
  const std::string p = (dir / "q.h5").string();
  testtraj::writeH5md(p, frames, lay);
  AnalysisOptions o = fastOptions();
  const RunResult r = analyzeRun(p, o);
  CHECK(r.kappa == 0.8);
  CHECK(r.kappa_source == "file (charging.kappa)");
  const Table& fits = r.table("fits");
  CHECK(fits.rows[0][fits.column("charging_rate_exponent")] == Approx(-2.2).margin(1e-3));
  CHECK(fits.rows[0][fits.column("charging_rate_expected")] == Approx(-13.0 / 6.0));
  CHECK(fits.rows[0][fits.column("charge_fit_points")] == 40.0);
  const Table& th = r.table("thermo");
  CHECK(th.rows[10][th.column("mean_abs_q")] == Approx(2.0 - std::pow(times[10], -1.2)));
  o.kappa = 0.5;  // an explicit option wins over the file
  CHECK(analyzeRun(p, o).kappa == 0.5);
  fs::remove_all(dir);
}

TEST_CASE("a dump header's counts are checked before anything is allocated", "[analysis][io]") {
  const fs::path dir = tempDir("dumpsize");
  auto dump = [&](const std::string& name, const std::string& count, const std::string& atom) {
    const std::string p = (dir / name).string();
    std::ofstream(p) << "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n"
                     << count << "\nITEM: BOX BOUNDS pp pp pp\n0 10\n0 10\n0 10\n"
                     << "ITEM: ATOMS id x y z ix iy iz\n"
                     << atom << "\n";
    return p;
  };
  Frame f;
  // 1e12 atoms in a file of ~150 bytes: refused from the file size, not by std::bad_alloc
  LammpsDump big(dump("big.dump", "1000000000000", "1 1 1 1 0 0 0"));
  CHECK_THROWS_AS(big.next(f), std::invalid_argument);
  LammpsDump big2(dump("big.dump", "1000000000000", "1 1 1 1 0 0 0"));
  CHECK_THROWS_WITH(big2.next(f), Catch::Contains("big.dump") &&
                                      Catch::Contains("NUMBER OF ATOMS = 1000000000000") &&
                                      Catch::Contains("room for at most 1 atom lines"));
  for (const char* count : {"-5", "99999999999999999999999", "many"}) {
    LammpsDump bad(dump("count.dump", count, "1 1 1 1 0 0 0"));
    CHECK_THROWS_WITH(bad.next(f), Catch::Contains("count.dump") &&
                                       Catch::Contains("NUMBER OF ATOMS") &&
                                       Catch::Contains("line 4"));
  }
  // values whose conversion to an integer would be undefined behaviour
  LammpsDump id(dump("id.dump", "1", "1e300 1 1 1 0 0 0"));
  CHECK_THROWS_WITH(id.next(f), Catch::Contains("atom id 1e+300 is not an integer"));
  LammpsDump img(dump("img.dump", "1", "1 1 1 1 0 5e9 0"));
  CHECK_THROWS_WITH(img.next(f), Catch::Contains("image flag 5e+09"));
  LammpsDump far(dump("far.dump", "1", "1 1e300 1 1 0 0 0"));
  CHECK_THROWS_WITH(far.next(f), Catch::Contains("box lengths from the box"));
  // the same file with a true count reads
  LammpsDump ok(dump("ok.dump", "1", "7 1 2 3 0 0 0"));
  REQUIRE(ok.next(f));
  CHECK(f.id.at(0) == 7);
  fs::remove_all(dir);
}
