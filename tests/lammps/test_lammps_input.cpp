// The translation of a run configuration into LAMMPS commands (md/lammps/LammpsInput.h): the
// contact mapping, Coulomb, the fix, keys LAMMPS cannot honour, and the data file.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <stdexcept>
#include <string>

#include "common/Csv.h"
#include "md/config/ConfigParser.h"
#include "md/engine/Engine.h"
#include "md/io/InitialState.h"
#include "md/lammps/LammpsInput.h"

#include "TestUtil.h"

using namespace granagg;
using namespace granagg::md;

namespace {

bool has(const lammps::LammpsInput& in, const std::string& command) {
  return std::find(in.commands.begin(), in.commands.end(), command) != in.commands.end();
}

MdConfig config(const std::vector<std::string>& set) {
  std::vector<std::string> s = {"system.N=200", "run.t_end=1"};
  s.insert(s.end(), set.begin(), set.end());
  return parseConfigString("", "(test)", s);
}

}  // namespace

TEST_CASE("lammps input maps the Hertz contact to gran/hertz/history with kn 2E and gamma_n 4D",
          "[lammps]") {
  const MdConfig c = config({"contact.E=100", "contact.D=10"});
  const Frame s = randomInitialState(c);
  const auto in = lammps::translateConfig(c, s, "/tmp/x.data");
  // F = sqrt(xi/4) [kn xi + (1/2) gamma_n xi'] = E xi^{3/2} + D xi^{1/2} xi'
  CHECK(has(in, "pair_style gran/hertz/history 200 0.0 40 0.0 0.0 0 limit_damping"));
  CHECK(has(in, "comm_modify vel yes"));
  CHECK(has(in, "newton on"));
  CHECK(has(in, "read_data /tmp/x.data"));
  CHECK(has(in, "set group all mass 1.0"));
  CHECK(has(in, "fix integrate all nve/sphere"));
  CHECK(has(in, "neighbor 0.3 bin"));
  CHECK(in.dt == Engine::chooseTimeStep(c));
  CHECK(has(in, "timestep " + common::formatReal(in.dt)));
  CHECK(in.steps == std::llround(1.0 / in.dt));
  CHECK(has(in, "fix granagg all granagg/charging pair gran/hertz/history seed 1 Q 1 kappa 0.83 "
                "psi1 0.1 3.1623 psi2 0.0415 exchange yes max_overlap 0.6"));
  // unclamped: no limit_damping; fixed charges: the fix counts but does not exchange
  const MdConfig u = config({"contact.clamp=false", "charging.mode=fixed"});
  const auto iu = lammps::translateConfig(u, s, "/tmp/x.data", true);
  CHECK(has(iu, "pair_style gran/hertz/history 557.2 0.0 110.8 0.0 0.0 0"));
  CHECK(std::any_of(iu.commands.begin(), iu.commands.end(), [](const std::string& x) {
    return x.find("exchange no") != std::string::npos && x.find("record yes") != std::string::npos;
  }));
  CHECK(iu.text("# header").find("run " + std::to_string(iu.steps) + "\n") != std::string::npos);
}

TEST_CASE("lammps input maps the spring-dashpot contact to gran/hooke/history", "[lammps]") {
  const MdConfig c = config({"contact.model=spring_dashpot", "contact.stiffness=1000",
                             "contact.restitution=0.8", "contact.clamp=false"});
  const auto in = lammps::translateConfig(c, randomInitialState(c), "/tmp/x.data");
  // F = k xi + gamma xi' and LAMMPS's kn xi + m_eff gamma_n xi': gamma_n = 2 gamma, with gamma from
  // the restitution (SpringDashpot.h): zeta = -ln(e) omega0 / sqrt(pi^2 + ln(e)^2), gamma = zeta
  const double omega0 = std::sqrt(1000.0 / 0.5), le = std::log(0.8);
  const double gamma = 2.0 * 0.5 * (-le * omega0 / std::sqrt(M_PI * M_PI + le * le));
  const std::string expect = "pair_style gran/hooke/history 1000 0.0 ";
  const auto it = std::find_if(in.commands.begin(), in.commands.end(), [&](const std::string& x) {
    return x.rfind(expect, 0) == 0;
  });
  REQUIRE(it != in.commands.end());
  CHECK(std::stod(it->substr(expect.size())) == Approx(2.0 * gamma).epsilon(1e-15));
  CHECK(it->find("limit_damping") == std::string::npos);
}

TEST_CASE("lammps input translates coulomb.every = k to rRESPA: pair every dt, PPPM every k dt",
          "[lammps]") {
  const MdConfig c = config({"coulomb.K=5", "coulomb.every=4", "integrator.dt=0.002",
                             "run.t_end=10"});
  const auto in = lammps::translateConfig(c, randomInitialState(c), "/tmp/x.data");
  CHECK(has(in, "run_style respa 2 4 pair 1 kspace 2"));
  CHECK(in.respa_loop == 4);
  CHECK(in.dt == 4 * 0.002);  // LAMMPS's timestep: the outer step
  CHECK(has(in, "timestep " + common::formatReal(4 * 0.002)));
  CHECK(in.steps == 1250);  // outer steps to t_end
  bool respa_fix = false;
  for (const auto& cmd : in.commands)
    if (cmd.rfind("fix granagg all granagg/charging", 0) == 0)
      respa_fix = cmd.size() > 8 && cmd.compare(cmd.size() - 8, 8, " respa 4") == 0;
  CHECK(respa_fix);
  // the skin covers 4 steps between list checks at the fastest impact speed (sqrt(4 ln 1e6) at
  // T = 1): 0.3 + 2 x 7.43384 x 3 x 0.002
  const double skin = 0.3 + 2.0 * std::sqrt(4.0 * std::log(1e6)) * 3 * 0.002;
  CHECK(has(in, "neighbor " + common::formatReal(skin) + " bin"));
  CHECK_NOTHROW(lammps::checkLammpsCanRun(
      config({"coulomb.K=5", "coulomb.every=4", "integrator.dt=0.002",
              "coulomb.skin=" + common::formatReal(skin)})));
  // "auto" and 1 stay at every force at every step
  for (const char* every : {"coulomb.every=1", "coulomb.every=auto"}) {
    const auto plain = lammps::translateConfig(config({"coulomb.K=5", every}),
                                               randomInitialState(c), "/tmp/x.data");
    INFO(every);
    CHECK(plain.respa_loop == 1);
    for (const auto& cmd : plain.commands) CHECK(cmd.rfind("run_style", 0) == std::string::npos);
  }
}

TEST_CASE("lammps input puts Coulomb in coul/long and pppm at granagg's PPPM design", "[lammps]") {
  const MdConfig c = config({"coulomb.K=5", "coulomb.accuracy=1e-4"});
  const Frame s = randomInitialState(c);
  const auto in = lammps::translateConfig(c, s, "/tmp/x.data");
  const CoulombDesign d = designCoulomb(c.coulomb, s.size(), s.box, 0.3, 1, 1, 200.0);
  CHECK(has(in, "pair_style hybrid/overlay gran/hertz/history 557.2 0.0 110.8 0.0 0.0 0 "
                "limit_damping coul/long " + common::formatReal(d.pppm.r_cut)));
  CHECK(has(in, "pair_coeff * * gran/hertz/history"));
  CHECK(has(in, "pair_coeff * * coul/long"));
  CHECK(has(in, "dielectric 0.2"));  // K q_i q_j / r^2 with granagg's charges
  CHECK(has(in, "kspace_style pppm " + common::formatReal(1e-4 * 5.0)));  // a K
  const std::string m = std::to_string(d.pppm.mesh);
  CHECK(has(in, "kspace_modify gewald " + common::formatReal(d.pppm.alpha) + " mesh " + m + " " +
                    m + " " + m + " order " + std::to_string(d.pppm.order)));
  CHECK(in.coulomb);
}

TEST_CASE("lammps input rejects what LAMMPS cannot honour, naming the key", "[lammps]") {
  struct Case {
    std::vector<std::string> set;
    std::string key;
  };
  for (const Case& k :
       {Case{{"coulomb.K=5", "coulomb.every_max=4"}, "coulomb.every_max"},
        Case{{"coulomb.K=5", "coulomb.r_fast=3"}, "coulomb.r_fast"},
        Case{{"coulomb.K=5", "coulomb.every=8", "coulomb.r_fast=3"}, "coulomb.r_fast"},
        Case{{"coulomb.K=5", "coulomb.every=8", "coulomb.skin=0.3"}, "coulomb.skin"},
        Case{{"coulomb.K=5", "coulomb.skin=0.5"}, "coulomb.skin"},
        Case{{"coulomb.K=5", "coulomb.method=ewald"}, "coulomb.method"}}) {
    const MdConfig c = config(k.set);
    INFO(k.key);
    CHECK_THROWS_AS(lammps::checkLammpsCanRun(c), std::invalid_argument);
    CHECK_THROWS_WITH(lammps::checkLammpsCanRun(c), Catch::StartsWith(k.key + " = "));
    CHECK_THROWS_AS(lammps::translateConfig(c, randomInitialState(c), "/tmp/x.data"),
                    std::invalid_argument);
  }
  // what LAMMPS does anyway is accepted: every = 1, the skin LAMMPS uses, and the Coulomb keys of
  // a run without Coulomb (granagg ignores them there too)
  CHECK_NOTHROW(lammps::checkLammpsCanRun(config({"coulomb.K=5", "coulomb.every=1"})));
  CHECK_NOTHROW(lammps::checkLammpsCanRun(config({"coulomb.K=5", "coulomb.skin=0.3"})));
  CHECK_NOTHROW(lammps::checkLammpsCanRun(config({"coulomb.every=8", "coulomb.r_fast=3"})));
}

TEST_CASE("lammps data file reads back as the same state, bit for bit", "[lammps]") {
  MdConfig c = config({"charging.initial=bipolar", "charging.q0=0.3"});
  Frame s = randomInitialState(c);
  s.ix[3] = 2;
  s.iz[7] = -1;
  s.charge[5] = 0.1 + 1e-17;  // a value without a short decimal form
  const std::string path = test::tempPath("state.data");
  test::spit(path, lammps::lammpsDataText(s));
  const Frame r = readInitialStateLammps(path);
  CHECK(r.box == s.box);
  CHECK(test::sameBits(r.x, s.x));
  CHECK(test::sameBits(r.y, s.y));
  CHECK(test::sameBits(r.z, s.z));
  CHECK(test::sameBits(r.vx, s.vx));
  CHECK(test::sameBits(r.vy, s.vy));
  CHECK(test::sameBits(r.vz, s.vz));
  CHECK(test::sameBits(r.charge, s.charge));
  CHECK(r.ix == s.ix);
  CHECK(r.iz == s.iz);
  std::filesystem::remove(path);
}
