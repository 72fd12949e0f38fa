// fix granagg/charging driven through the LAMMPS C++ API in this process: a run continued from a
// LAMMPS restart file follows the uninterrupted run, under run_style verlet and respa; under
// respa a run in chunks (each with LAMMPS's full setup) does too.
#include <catch2/catch.hpp>

#include <sys/wait.h>
#include <unistd.h>

#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "md/config/ConfigParser.h"
#include "md/io/InitialState.h"
#include "md/lammps/FixCharging.h"
#include "md/lammps/LammpsInput.h"

#include "TestUtil.h"

using namespace granagg;

namespace {

/// Runs `body` in a forked child with its own MPI (a singleton rank): the test process itself
/// stays without MPI, so that the other tests can launch mpirun. Returns the child's exit status
/// (LAMMPS ends the process with 1 on its errors).
int inChildProcess(const std::function<int()>& body) {
  std::fflush(nullptr);
  const pid_t pid = ::fork();
  if (pid == 0) {
    int rc = 3;
    try {
      rc = body();
    } catch (...) {
      rc = 4;
    }
    std::fflush(nullptr);
    ::_exit(rc);
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::unique_ptr<LAMMPS_NS::LAMMPS> newLammps() {
  std::vector<std::string> args = {"test", "-log", "none", "-screen", "none", "-nocite"};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  auto lmp = std::make_unique<LAMMPS_NS::LAMMPS>(static_cast<int>(argv.size()), argv.data(),
                                                 MPI_COMM_WORLD);
  md::lammps::FixCharging::registerStyle(lmp.get());
  return lmp;
}

/// x, v, q of every atom by id, and the collision count.
std::vector<double> state(LAMMPS_NS::LAMMPS* lmp) {
  const auto* atom = lmp->atom;
  std::vector<double> s(7 * static_cast<std::size_t>(atom->natoms) + 1);
  for (int i = 0; i < atom->nlocal; ++i) {
    double* row = &s[7 * static_cast<std::size_t>(atom->tag[i] - 1)];
    for (int k = 0; k < 3; ++k) row[k] = atom->x[i][k];
    for (int k = 0; k < 3; ++k) row[3 + k] = atom->v[i][k];
    row[6] = atom->q[i];
  }
  const int ifix = lmp->modify->find_fix(md::lammps::CHARGING_FIX_ID);
  s.back() = static_cast<double>(
      dynamic_cast<md::lammps::FixCharging*>(lmp->modify->fix[ifix])->stats().collisions);
  return s;
}

/// x, v, q and the collision count after `commands`, then each of `runs` (LAMMPS commands).
std::vector<double> stateAfter(const std::vector<std::string>& commands,
                               const std::vector<std::string>& runs) {
  auto lmp = newLammps();
  for (const auto& cmd : commands) lmp->input->one(cmd);
  for (const auto& r : runs) lmp->input->one(r);
  return state(lmp.get());
}

/// The commands of a run continued from the restart file `file`: the same commands with
/// read_restart for read_data, less what the restart file sets (units, atom style, box).
std::vector<std::string> fromRestart(const std::vector<std::string>& commands,
                                     const std::string& file) {
  std::vector<std::string> out;
  for (const auto& cmd : commands) {
    if (cmd.rfind("units", 0) == 0 || cmd.rfind("atom_style", 0) == 0 ||
        cmd.rfind("boundary", 0) == 0)
      continue;
    out.push_back(cmd.rfind("read_data", 0) == 0 ? "read_restart " + file : cmd);
  }
  return out;
}

/// "max|dx| max|dv| max|dq| max|q| collisions_a collisions_b" of two state() results, the
/// positions compared by minimum image in a box of edge L (a setup wraps them into the box).
std::string difference(const std::vector<double>& a, const std::vector<double>& b, double L) {
  double dx = 0.0, dv = 0.0, dq = 0.0, qmax = 0.0;
  for (std::size_t i = 0; i + 1 < a.size(); i += 7) {
    for (int k = 0; k < 3; ++k) {
      const double d = a[i + k] - b[i + k];
      dx = std::max(dx, std::fabs(d - L * std::round(d / L)));
      dv = std::max(dv, std::fabs(a[i + 3 + k] - b[i + 3 + k]));
    }
    dq = std::max(dq, std::fabs(a[i + 6] - b[i + 6]));
    qmax = std::max(qmax, std::fabs(a[i + 6]));
  }
  std::ostringstream o;
  o << dx << ' ' << dv << ' ' << dq << ' ' << qmax << ' ' << a.back() << ' ' << b.back() << '\n';
  return o.str();
}

}  // namespace

TEST_CASE("fix granagg/charging continues a run from a LAMMPS restart file as if uninterrupted",
          "[lammps]") {
  const std::string dir = test::tempDir("lammps_restart").string();
  const std::string out = dir + "/result.txt";
  const int rc = inChildProcess([&] {
    MPI_Init(nullptr, nullptr);
    // a charged gas with exchange and Coulomb forces, dense enough for many contacts
    md::MdConfig c = md::parseConfigString(
        "", "(test)",
        {"system.N=300", "system.phi=0.2", "system.seed=7", "charging.initial=bipolar",
         "charging.q0=0.3", "charging.Q=0.1", "coulomb.K=1", "integrator.dt=0.003"});
    const md::Frame s = md::prepareInitialState(c);
    test::spit(dir + "/state.data", md::lammps::lammpsDataText(s));
    const auto in = md::lammps::translateConfig(c, s, dir + "/state.data");
    const std::vector<double> whole = stateAfter(in.commands, {"run 200"});
    stateAfter(in.commands, {"run 100", "write_restart " + dir + "/at100.restart"});
    const std::vector<double> continued =
        stateAfter(fromRestart(in.commands, dir + "/at100.restart"), {"run 100"});
    std::ofstream(out) << difference(whole, continued, s.box);
    MPI_Finalize();
    return 0;
  });
  REQUIRE(rc == 0);
  std::ifstream in(out);
  double dx = -1, dv = -1, dq = -1, qmax = 0, coll_whole = 0, coll_continued = 0;
  in >> dx >> dv >> dq >> qmax >> coll_whole >> coll_continued;
  INFO("max |dx| " << dx << ", |dv| " << dv << ", |dq| " << dq << ", collisions " << coll_whole
                   << " and " << coll_continued);
  // LAMMPS's own restart recomputes the first forces with full-step velocities in the granular
  // damping (differences of order 1e-4 in v after 100 steps); with the fix's stored forces only
  // the rounding of reordered sums remains
  CHECK(coll_whole > 100);
  CHECK(coll_continued == coll_whole);
  CHECK(dx < 1e-10);
  CHECK(dv < 1e-10);
  CHECK(dq <= 1e-12 * qmax);
}

TEST_CASE("fix granagg/charging under rRESPA: chunks and a restart continue the run as if "
          "uninterrupted",
          "[lammps]") {
  // Under run_style respa every `run` starts with LAMMPS's setup, which recomputes the forces of
  // each level from the full-step velocities; the fix puts the kept forces of the state back
  // (FixCharging.h). Without that the chunked run differs at contacts in progress (the granular
  // damping with v(t_n) in place of the drift velocity); with it only the rounding of sums
  // reordered by the setup's sort remains.
  const std::string dir = test::tempDir("lammps_respa").string();
  const std::string out = dir + "/result.txt";
  const int rc = inChildProcess([&] {
    MPI_Init(nullptr, nullptr);
    md::MdConfig c = md::parseConfigString(
        "", "(test)",
        {"system.N=300", "system.phi=0.2", "system.seed=7", "charging.initial=bipolar",
         "charging.q0=0.3", "charging.Q=0.1", "coulomb.K=1", "integrator.dt=0.003",
         "coulomb.every=4"});
    const md::Frame s = md::prepareInitialState(c);
    test::spit(dir + "/state.data", md::lammps::lammpsDataText(s));
    const auto in = md::lammps::translateConfig(c, s, dir + "/state.data");
    const std::vector<double> whole = stateAfter(in.commands, {"run 60"});
    const std::vector<double> chunked =
        stateAfter(in.commands, std::vector<std::string>(6, "run 10 post no"));
    stateAfter(in.commands, {"run 30", "write_restart " + dir + "/at30.restart"});
    const std::vector<double> continued =
        stateAfter(fromRestart(in.commands, dir + "/at30.restart"), {"run 30"});
    std::ofstream(out) << difference(whole, chunked, s.box) << difference(whole, continued, s.box);
    MPI_Finalize();
    return 0;
  });
  REQUIRE(rc == 0);
  std::ifstream in(out);
  for (const char* how : {"in 6 chunks", "from a restart file at outer step 30"}) {
    double dx = -1, dv = -1, dq = -1, qmax = 0, coll_whole = 0, coll_other = 0;
    in >> dx >> dv >> dq >> qmax >> coll_whole >> coll_other;
    INFO(how << ": max |dx| " << dx << ", |dv| " << dv << ", |dq| " << dq << ", collisions "
              << coll_whole << " and " << coll_other);
    CHECK(coll_whole > 100);  // 240 inner steps of a dense gas: contacts at every boundary
    CHECK(coll_other == coll_whole);
    CHECK(dx < 1e-10);
    CHECK(dv < 1e-10);
    CHECK(dq <= 1e-12 * qmax);
  }
}
