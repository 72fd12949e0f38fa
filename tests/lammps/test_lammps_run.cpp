// granagg-lammps under mpirun: the charge exchanged at a collision (to the bit), the restitution
// of a collision against granagg's engine, a charged gas on 2 ranks (charge conservation, every
// collision charging exactly once, the same collisions as on 1 rank; its H5MD trajectory read by
// granagg analyze and scripts/check_h5md.py), SIGTERM and --restart, a folder in use, bad input.
#include <catch2/catch.hpp>

#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <map>
#include <regex>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "cli/RunCommand.h"
#include "common/Csv.h"
#include "common/H5mdReader.h"
#include "md/config/ConfigParser.h"
#include "md/engine/Engine.h"
#include "md/io/InitialState.h"
#include "md/potentials/ChargeExchange.h"

#include "TestUtil.h"

using namespace granagg;
namespace fs = std::filesystem;

namespace {

/// granagg-lammps on `ranks` MPI ranks (Open MPI's mpirun; everything may run as root here, and
/// a machine may have fewer cores than ranks).
Run lammpsRun(int ranks, const std::string& args) {
  std::string launch = std::string(GRANAGG_MPIEXEC) + " --oversubscribe -np " +
                       std::to_string(ranks);
  if (::geteuid() == 0) launch += " --allow-run-as-root";
  return sh("OMP_NUM_THREADS=1 " + launch + " " + GRANAGG_LAMMPS_BINARY + " " + args);
}

std::string writeFile(const fs::path& p, const std::string& text) {
  std::ofstream(p) << text;
  return p.string();
}

/// The last frame of a run's traj.h5, as the engine's Frame (id order).
md::Frame lastFrame(const fs::path& run) {
  const common::H5mdReader r((run / "traj.h5").string());
  return md::engineFrame(r.readFrame(r.frames() - 1));
}

/// One of a run's /granagg/observables.
common::ObservableSeries observable(const fs::path& run, const std::string& name) {
  return common::H5mdReader((run / "traj.h5").string()).readObservable(name);
}

/// Two particles on the x axis at y = z = 2.5 in a box of edge 5, approaching head-on at
/// relative speed v, 0.002 apart; on 2 ranks the box is cut at x = 2.5, between them.
const double TWO_BODY_L = 5.0;
const char* TWO_BODY_PHI = "0.008377580409572781";  // 2 pi / (6 * 125): L = 5
std::string twoBodyState(const fs::path& dir, double v) {
  const std::string h = common::formatReal(0.5 * v);
  return writeFile(dir / "two.csv", "x,y,z,vx,vy,vz,q\n1.999,2.5,2.5," + h + ",0,0,0\n" +
                                        "3.001,2.5,2.5,-" + h + ",0,0,0\n");
}

std::string twoBodyConfig(const fs::path& dir, const std::string& state, const std::string& mode,
                          double dt, double t_end) {
  return writeFile(dir / "two.toml",
                   std::string("[system]\nN = 2\nphi = ") + TWO_BODY_PHI + "\nseed = 987654321\n" +
                       "initial = \"" + state + "\"\n[charging]\nmode = \"" + mode +
                       "\"\n[integrator]\ndt = " + common::formatReal(dt) +
                       "\n[run]\nt_end = " + common::formatReal(t_end) +
                       "\n[output]\nobservable_interval = 1000000000\nframes_per_decade = 0\n" +
                       "checkpoint_wall_seconds = 0.0\n");
}

}  // namespace

TEST_CASE("granagg-lammps exchanges at a collision exactly the charge of ChargeExchange",
          "[lammps][mpi]") {
  const fs::path dir = test::tempDir("lammps_charge");
  const double v = 0.5, dt = 1e-3;
  const std::string state = twoBodyState(dir, v);
  const std::string cfg = twoBodyConfig(dir, state, "exchange", dt, 0.05);
  // 2 ranks: the pair meets across the rank boundary (each rank owns one particle)
  const Run r = lammpsRun(2, "--config " + cfg + " --out " + (dir / "o").string() +
                                 " --collisions -q");
  INFO(r.output);
  REQUIRE(r.status == 0);

  // the step of the collision, independently: the free drift x += dt u of both particles (fix
  // nve/sphere's arithmetic; no force acts before the contact) until their distance is below 1
  double x0 = 1.999, x1 = 3.001;
  std::int64_t step = 0;
  double rx = 0.0;
  do {
    x0 += dt * (0.5 * v);
    x1 += dt * -(0.5 * v);
    ++step;
    rx = x0 - x1;
  } while (!(rx * rx < 1.0));
  // the approach speed as the engine computes it (md/compute/ContactForce.cpp) from the velocities,
  // which before the contact are the initial ones: xi' = -(v_0 - v_1).(r/|r|)
  const double r_len = std::sqrt(rx * rx);
  const double xi_dot = -((0.5 * v - -(0.5 * v)) * (rx * (1.0 / r_len)));
  md::ChargeExchange::Params p;
  p.seed = 987654321;
  const double dq0 = md::ChargeExchange::transferTo(p, step, 0, 1, xi_dot);

  const common::CsvTable coll = common::readCsv((dir / "o" / "collisions.csv").string());
  REQUIRE(coll.rows.size() == 1);
  const auto& c = coll.rows[0];
  CHECK(c[coll.column("step")] == step);
  CHECK(c[coll.column("id_lo")] == 0);
  CHECK(c[coll.column("id_hi")] == 1);
  CHECK(test::sameBits(c[coll.column("xi_dot")], xi_dot));
  CHECK(test::sameBits(c[coll.column("dq_lo")], dq0));
  CHECK(dq0 != 0.0);
  // the charges at the end (the trajectory's last frame): the exchange and nothing else, to the bit
  const md::Frame fin = lastFrame(dir / "o");
  REQUIRE(fin.size() == 2);
  CHECK(fin.step == std::llround(0.05 / dt));
  CHECK(test::sameBits(fin.charge[0], dq0));
  CHECK(test::sameBits(fin.charge[1], -dq0));

  // granagg's engine from the same state gives the same charges at the same step
  const md::MdConfig mc = md::parseConfigFile(cfg);
  md::Engine engine(mc, md::readInitialState(state, TWO_BODY_L));
  engine.run(step - 1);
  CHECK(engine.observables().collisions == 0);
  engine.run(1);
  CHECK(engine.observables().collisions == 1);
  const md::Frame f = engine.frame();
  CHECK(test::sameBits(f.charge[0], dq0));
  CHECK(test::sameBits(f.charge[1], -dq0));
}

TEST_CASE("granagg-lammps gives a two-body collision the restitution of granagg's engine",
          "[lammps][mpi]") {
  const fs::path dir = test::tempDir("lammps_restitution");
  // dt = 1e-6: LAMMPS's fix nve/sphere evaluates the damping with the half-step velocity, an
  // error first order in dt in the restitution (3.9e-7 here, 4e-6 at dt = 1e-5;
  // docs/benchmarks.md); the engine predicts the full-step velocity
  const double v = 0.5, dt = 1e-6, t_end = 0.45;  // the contact ends by t = 0.4
  const std::string state = twoBodyState(dir, v);
  const std::string cfg = twoBodyConfig(dir, state, "fixed", dt, t_end);
  const Run r = lammpsRun(1, "--config " + cfg + " --out " + (dir / "o").string() + " -q");
  INFO(r.output);
  REQUIRE(r.status == 0);
  const md::Frame fin = lastFrame(dir / "o");
  REQUIRE(fin.size() == 2);
  const double e_lammps = (fin.vx[1] - fin.vx[0]) / v;

  const md::MdConfig mc = md::parseConfigFile(cfg);  // the same configuration, dt included
  md::Engine::setThreads(1);  // two particles: threads would only add their synchronisation
  md::Engine engine(mc, md::readInitialState(state, TWO_BODY_L));
  engine.run(std::llround(t_end / dt));
  const md::Frame f = engine.frame();
  const double e_engine = (f.vx[1] - f.vx[0]) / v;
  INFO("e LAMMPS " << std::setprecision(12) << e_lammps << ", engine " << e_engine);
  CHECK(e_engine == Approx(0.370093).margin(1e-6));  // `granagg kinetic restitution --v 0.5`
  CHECK(std::fabs(e_lammps - e_engine) < 1e-6);
  CHECK(engine.observables().elastic_energy == 0.0);  // the contact is over in both
}

TEST_CASE("granagg-lammps charges a K = 5 gas on 2 ranks exactly once per collision, and granagg "
          "analyze reads its trajectory",
          "[lammps][mpi]") {
  const fs::path dir = test::tempDir("lammps_gas");
  const int N = 1000;
  const double dt = 0.003;
  auto config = [&](const std::string& name, int steps) {
    return writeFile(dir / name,
                     "[system]\nN = " + std::to_string(N) +
                         "\nseed = 42\n[charging]\ninitial = \"bipolar\"\nq0 = 0.05\nQ = 0.05\n"
                         "[coulomb]\nK = 5\n[integrator]\ndt = 0.003\n[run]\nt_end = " +
                         common::formatReal(steps * dt) +
                         "\n[output]\nobservable_interval = 25\nframes_per_decade = 10\n"
                         "checkpoint_wall_seconds = 0.0\n");
  };
  const Run two = lammpsRun(2, "--config " + config("long.toml", 500) + " --out " +
                                   (dir / "two").string() + " --collisions");
  INFO(two.output);
  REQUIRE(two.status == 0);
  const Run one = lammpsRun(1, "--config " + config("short.toml", 50) + " --out " +
                                   (dir / "one").string() + " --collisions -q");
  INFO(one.output);
  REQUIRE(one.status == 0);

  // particles crossed the boundaries between the ranks' domains
  std::smatch m;
  REQUIRE(std::regex_search(two.output, m, std::regex("([0-9]+) migrations between ranks")));
  CHECK(std::stol(m[1]) > 100);

  // the total charge at every sample, to 1e-12 N max|q| (the exchange rule conserves it exactly;
  // what remains is the rounding of the per-particle sums)
  const auto total_q = observable(dir / "two", "total_charge"),
             max_q_obs = observable(dir / "two", "max_abs_charge"),
             mean_q_obs = observable(dir / "two", "mean_abs_charge"),
             collisions = observable(dir / "two", "collisions");
  REQUIRE(total_q.value.size() == 21);  // steps 0, 25, ..., 500
  CHECK(total_q.step.back() == 500);
  const md::Frame init = md::readInitialStateLammps((dir / "two" / "initial.data").string());
  double q_init = 0.0;
  for (double q : init.charge) q_init += q;
  for (std::size_t k = 0; k < total_q.value.size(); ++k)
    CHECK(std::fabs(total_q.value[k] - q_init) <= 1e-12 * N * max_q_obs.value[k]);
  CHECK(mean_q_obs.value.back() > 0.06);  // charges grew

  // every collision charged each partner exactly once: the final charges are the initial ones plus
  // the sum of the logged exchanges, within the rounding of the per-step sums
  const common::CsvTable coll = common::readCsv((dir / "two" / "collisions.csv").string());
  const std::size_t cs = coll.column("step"), clo = coll.column("id_lo"),
                    chi = coll.column("id_hi"), cdq = coll.column("dq_lo");
  std::vector<double> q = init.charge;
  double max_q = 0.0;
  std::set<std::tuple<long, long, long>> seen;
  for (const auto& row : coll.rows) {
    CHECK(seen.insert({std::lround(row[cs]), std::lround(row[clo]), std::lround(row[chi])}).second);
    q[static_cast<std::size_t>(row[clo])] += row[cdq];
    q[static_cast<std::size_t>(row[chi])] -= row[cdq];
  }
  const md::Frame fin = lastFrame(dir / "two");
  REQUIRE(fin.size() == static_cast<std::size_t>(N));
  CHECK(fin.step == 500);
  for (double x : q) max_q = std::max(max_q, std::fabs(x));
  int wrong = 0;
  for (int i = 0; i < N; ++i) wrong += !(std::fabs(fin.charge[i] - q[i]) <= 1e-12 * max_q);
  CHECK(wrong == 0);
  CHECK(coll.rows.back()[cs] > 400);
  CHECK(static_cast<double>(coll.rows.size()) == collisions.value.back());

  // the trajectory is granagg's H5MD (scripts/check_h5md.py), and granagg analyze reads it: the
  // run's N, frames and box, and its charges (<|q|> of the last frame, against the frame itself)
  const common::H5mdReader traj((dir / "two" / "traj.h5").string());
  const std::size_t frames = traj.frames();
  CHECK(frames >= 10);
  CHECK(traj.box(0) == init.box);
  CHECK(traj.configToml().find("K = 5") != std::string::npos);
  const Run check = sh("/usr/bin/python3 " + std::string(GRANAGG_SOURCE_DIR) +
                       "/scripts/check_h5md.py " + (dir / "two" / "traj.h5").string());
  INFO(check.output);
  CHECK(check.status == 0);
  CHECK_THAT(check.output, Catch::Contains("layout OK"));
  const Run ana = sh(std::string(GRANAGG_BINARY) + " analyze " + (dir / "two").string() +
                     " --out " + (dir / "ana").string());
  INFO(ana.output);
  REQUIRE(ana.status == 0);
  REQUIRE(fs::exists(dir / "ana" / "S_t.csv"));
  const common::CsvTable thermo = common::readCsv((dir / "ana" / "thermo.csv").string());
  std::string run0;
  for (const auto& [k, v] : thermo.meta)
    if (k == "run.0") run0 = v;
  INFO(run0);
  CHECK_THAT(run0, Catch::Contains(std::to_string(frames) + " frames, N = " + std::to_string(N)));
  std::smatch grid;
  REQUIRE(std::regex_search(run0, grid, std::regex("grid ([0-9]+)\\^3 cells of h = ([0-9.e+-]+)")));
  CHECK(std::stod(grid[1]) * std::stod(grid[2]) == Approx(init.box).epsilon(1e-12));
  REQUIRE(thermo.rows.size() == frames);
  double mean_abs_q = 0.0;
  for (double x : fin.charge) mean_abs_q += std::fabs(x) / N;
  CHECK(thermo.rows.back()[thermo.column("mean_abs_q_mean")] == Approx(mean_abs_q).epsilon(1e-12));
  CHECK(thermo.rows.back()[thermo.column("t")] == Approx(500 * dt).epsilon(1e-12));

  // the same collisions as on 1 rank over the first 50 steps (the trajectories agree to rounding
  // there), with the same exchanges up to that rounding
  const common::CsvTable ref = common::readCsv((dir / "one" / "collisions.csv").string());
  std::vector<std::vector<double>> first;
  for (const auto& row : coll.rows)
    if (row[cs] <= 50) first.push_back(row);
  CHECK(ref.rows.size() >= 20);
  REQUIRE(first.size() == ref.rows.size());
  for (std::size_t k = 0; k < first.size(); ++k) {
    INFO("collision " << k);
    CHECK(first[k][cs] == ref.rows[k][cs]);
    CHECK(first[k][clo] == ref.rows[k][clo]);
    CHECK(first[k][chi] == ref.rows[k][chi]);
    CHECK(first[k][cdq] == Approx(ref.rows[k][cdq]).epsilon(1e-9));
  }
}

TEST_CASE("granagg-lammps rejects a key LAMMPS cannot honour: exit 2, the key named, nothing "
          "written",
          "[lammps][mpi]") {
  const fs::path dir = test::tempDir("lammps_bad");
  for (const std::string& set : {std::string("--set coulomb.K=5 --set coulomb.every=8"),
                                 std::string("--set coulomb.K=5 --set coulomb.r_fast=3"),
                                 std::string("--set system.bogus=1")}) {
    INFO(set);
    const Run r = lammpsRun(2, "--preset quick " + set + " --out " + (dir / "o").string());
    CHECK(r.status == 2);
    const std::size_t from = set.rfind("--set ") + 6;
    const std::string key = set.substr(from, set.rfind('=') - from);
    CHECK_THAT(r.output, Catch::Contains(key));
    CHECK(!fs::exists(dir / "o"));
  }
  // an output folder in the way
  fs::create_directories(dir / "full");
  writeFile(dir / "full" / "x", "x");
  const Run r = lammpsRun(1, "--preset quick --out " + (dir / "full").string());
  CHECK(r.status == 2);
  CHECK_THAT(r.output, Catch::Contains("--force"));
}

TEST_CASE("granagg-lammps stops at an overlap beyond run.max_overlap, naming the particles",
          "[lammps][mpi]") {
  const fs::path dir = test::tempDir("lammps_overlap");
  const Run r = lammpsRun(2, "--preset quick --set system.N=500 --set run.t_end=1 "
                             "--set run.max_overlap=0.01 -q --out " + (dir / "o").string());
  CHECK(r.status == 1);
  CHECK(std::regex_search(r.output, std::regex("step [0-9]+: overlap 0\\.01[0-9]* of particles "
                                               "[0-9]+ and [0-9]+ beyond run.max_overlap = 0.01")));
}

TEST_CASE("granagg-lammps samples the contacts of its initial state as the engine does",
          "[lammps][mpi]") {
  const fs::path dir = test::tempDir("lammps_initial_contacts");
  // a pair overlapping by 0.1 at rest, and a free particle
  const std::string state =
      writeFile(dir / "s.csv", "x,y,z,vx,vy,vz,q\n1,1,1,0,0,0,0\n1.9,1,1,0,0,0,0\n"
                               "3.5,3.5,3.5,0.1,0,0,0\n");
  const std::string cfg = writeFile(
      dir / "c.toml", "[system]\nN = 3\nphi = 0.02\ninitial = \"" + state +
                          "\"\n[integrator]\ndt = 0.001\n[run]\nt_end = 0.002\n"
                          "[output]\nframes_per_decade = 0\ncheckpoint_wall_seconds = 0.0\n");
  const Run r = lammpsRun(1, "--config " + cfg + " --out " + (dir / "o").string() + " -q");
  INFO(r.output);
  REQUIRE(r.status == 0);
  auto at0 = [&](const std::string& name) {
    const auto series = observable(dir / "o", name);
    REQUIRE(!series.value.empty());
    CHECK(series.step[0] == 0);
    return series.value[0];
  };
  const md::MdConfig mc = md::parseConfigFile(cfg);
  md::Engine::setThreads(1);
  const md::Engine engine(mc, md::readInitialState(state, md::boxLength(mc.system)), true);
  const md::Observables o = engine.observables();
  CHECK(o.contacts_per_particle == Approx(2.0 / 3.0));
  CHECK(at0("contacts_per_particle") == Approx(o.contacts_per_particle));
  CHECK(at0("max_overlap") == Approx(o.max_overlap).epsilon(1e-12));
  CHECK(at0("elastic_energy") == Approx(o.elastic_energy).epsilon(1e-12));
  CHECK(at0("collisions") == 0);
}
