// md/run/Simulation, in process: a run resumed from a mid-run checkpoint writes the same
// trajectory to the bit as the uninterrupted run, and bad requests fail before anything is
// written. (The same paths through the command line: tests/cli/test_cli_md.cpp.)
#include <catch2/catch.hpp>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "common/H5mdReader.h"
#include "common/Hdf5.h"
#include "md/config/MdConfig.h"
#include "md/io/InitialState.h"
#include "md/run/Simulation.h"

#include "TestUtil.h"

using granagg::test::sameBits;
using granagg::test::tempDir;

using namespace granagg::md;
using granagg::common::H5mdReader;
using granagg::common::ObservableSeries;
namespace fs = std::filesystem;

namespace {

/// A small charged gas with everything a restart must carry: exchange charging, PPPM with the
/// slow interval following the gas (every 2, up to 8), frames on both schedules, checkpoints by
/// steps only (a wall-clock checkpoint would make the file sequence depend on the machine).
MdConfig chargedGas(double t_end) {
  MdConfig c;
  c.system.N = 300;
  c.system.seed = 11;
  c.charging.mode = "exchange";
  c.charging.Q = 0.1;
  c.coulomb.K = 1.0;
  c.coulomb.every = 2;
  c.coulomb.every_max = 8;
  c.run.t_end = t_end;
  c.output.frames_per_decade = 5;
  c.output.frame_interval = 0.25;
  c.output.observable_interval = 37;  // not a divisor of the checkpoint step
  c.output.checkpoint_interval = 101;
  c.output.checkpoint_wall_seconds = 0.0;
  return c;
}

/// Trajectory b (interrupted after step `stop`, resumed) against a (uninterrupted): the same
/// frames and observable samples to the bit, plus the ones b wrote when it stopped at `stop`.
void requireSameTrajectory(const fs::path& a, const fs::path& b, std::int64_t stop) {
  const H5mdReader ra((a / "traj.h5").string()), rb((b / "traj.h5").string());
  std::size_t j = 0;
  for (std::size_t i = 0; i < ra.frames(); ++i, ++j) {
    INFO("frame " << i);
    Frame fa = engineFrame(ra.readFrame(i));
    REQUIRE(j < rb.frames());
    Frame fb = engineFrame(rb.readFrame(j));
    if (fb.step == stop && fa.step != stop) {  // the frame b wrote when it stopped
      REQUIRE(++j < rb.frames());
      fb = engineFrame(rb.readFrame(j));
    }
    CHECK(fa.step == fb.step);
    CHECK(sameBits(fa.x, fb.x));
    CHECK(sameBits(fa.y, fb.y));
    CHECK(sameBits(fa.z, fb.z));
    CHECK(sameBits(fa.vx, fb.vx));
    CHECK(sameBits(fa.vy, fb.vy));
    CHECK(sameBits(fa.vz, fb.vz));
    CHECK(sameBits(fa.charge, fb.charge));
    CHECK(fa.ix == fb.ix);
  }
  CHECK(j == rb.frames());
  const auto names = ra.observableNames();
  REQUIRE(names == rb.observableNames());
  for (const auto& n : names) {
    INFO("observable " << n);
    const ObservableSeries sa = ra.readObservable(n);
    ObservableSeries sb = rb.readObservable(n);
    for (std::size_t k = 0; k < sb.step.size(); ++k)  // the sample b took when it stopped
      if (sb.step[k] == stop && std::find(sa.step.begin(), sa.step.end(), stop) == sa.step.end()) {
        sb.step.erase(sb.step.begin() + static_cast<long>(k));
        sb.value.erase(sb.value.begin() + static_cast<long>(k));
        break;
      }
    CHECK(sa.step == sb.step);
    CHECK(sameBits(sa.value, sb.value));
  }
}

}  // namespace

TEST_CASE("a resumed Simulation writes the uninterrupted trajectory to the bit", "[md][run]") {
  const fs::path dir = tempDir("simulation_resume");
  const double t_end = 1.5;
  RunOptions opt;
  opt.command_line = "test";
  {
    Simulation a = Simulation::start(chargedGas(t_end), dir / "a", opt);
    const RunSummary s = a.run();
    CHECK(s.steps == a.lastStep());
    CHECK(s.slow_evaluations > 0);
  }
  std::int64_t stop = 0;
  {
    Simulation b = Simulation::start(chargedGas(0.6), dir / "b", opt);
    b.run();
    stop = b.engine().step();
  }
  // a run.t_end before the checkpoint is refused before anything is written
  const std::string before = granagg::test::slurp(dir / "b" / "traj.h5");
  CHECK_THROWS_WITH(Simulation::resume(dir / "b", {"run.t_end=0.3"}, opt),
                    Catch::Contains("before the checkpoint") && Catch::Contains("t = 0.6"));
  CHECK(granagg::test::slurp(dir / "b" / "traj.h5") == before);
  RunOptions again = opt;
  again.command_line = "test --restart";
  Simulation resumed = Simulation::resume(dir / "b", {"run.t_end=1.5"}, again);
  CHECK(resumed.resumed());
  CHECK(resumed.engine().step() == stop);
  resumed.run();
  CHECK(resumed.engine().step() == resumed.lastStep());
  requireSameTrajectory(dir / "a", dir / "b", stop);
  // the trajectory records its continuation; /parameters still describes the start
  {
    namespace h5 = granagg::common::h5;
    h5::silenceErrors();
    const h5::Handle f =
        h5::check(H5Fopen((dir / "b" / "traj.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), "open");
    REQUIRE(h5::exists(f.get(), "/granagg/restarts/0"));
    CHECK_FALSE(h5::exists(f.get(), "/granagg/restarts/1"));
    const h5::Handle g = h5::check(H5Gopen2(f.get(), "/granagg/restarts/0", H5P_DEFAULT), "g");
    const h5::Handle cmd = h5::openAttribute(g.get(), "command");
    CHECK(h5::readString(cmd.get(), true, "command") == "test --restart");
    const h5::Handle st = h5::openAttribute(g.get(), "step");
    CHECK(h5::readNumericAttribute<std::int64_t>(st.get(), H5T_NATIVE_INT64, "step").at(0) == stop);
  }
  if (std::getenv("GRANAGG_KEEP_TEST_FILES") == nullptr) fs::remove_all(dir);
}

TEST_CASE("Simulation refuses bad requests before writing anything", "[md][run]") {
  const fs::path dir = tempDir("simulation_refuse");
  RunOptions opt;
  // no checkpoint to resume from
  CHECK_THROWS_AS(Simulation::resume(dir / "none", {}, opt), std::invalid_argument);
  CHECK_FALSE(fs::exists(dir / "none"));
  // an initial state that cannot be read: the folder is not even created
  MdConfig bad = chargedGas(0.1);
  bad.system.initial = (dir / "missing.csv").string();
  CHECK_THROWS(Simulation::start(bad, dir / "bad", opt));
  CHECK_FALSE(fs::exists(dir / "bad"));
  // an invalid configuration
  MdConfig invalid = chargedGas(0.1);
  invalid.system.phi = 0.9;
  CHECK_THROWS_AS(Simulation::start(invalid, dir / "invalid", opt), std::invalid_argument);
  CHECK_FALSE(fs::exists(dir / "invalid"));
  // a finished run is neither overwritten without permission nor resumed with other settings
  Simulation::start(chargedGas(0.05), dir / "run", opt).run();
  const std::string before = granagg::test::slurp(dir / "run" / "traj.h5");
  CHECK_THROWS_AS(Simulation::start(chargedGas(0.05), dir / "run", opt), std::invalid_argument);
  CHECK_THROWS_AS(Simulation::resume(dir / "run", {"system.N=5"}, opt), std::invalid_argument);
  CHECK(granagg::test::slurp(dir / "run" / "traj.h5") == before);
  // with overwrite, a new run replaces the old one's files, its checkpoint included
  RunOptions overwrite = opt;
  overwrite.overwrite = true;
  MdConfig other = chargedGas(0.05);
  other.system.seed = 12;
  Simulation replaced = Simulation::start(other, dir / "run", overwrite);
  CHECK_FALSE(fs::exists(dir / "run" / "checkpoint.h5"));
  replaced.run();
  CHECK(fs::exists(dir / "run" / "checkpoint.h5"));
  fs::remove_all(dir);
}
