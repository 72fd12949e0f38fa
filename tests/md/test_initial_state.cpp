// User-given initial states: CSV (columns, comments, wrapping into the caller's box, errors
// naming the line and particle), H5MD (last frame of a trajectory) and LAMMPS data files (the
// same state as a CSV to the bit; styles, ids, image flags, errors), plus coordinate wrapping;
// what a new run takes from them (prepareInitialState): the contacts of a frame of granagg's own
// run are accepted up to system.initial_max_overlap, deeper overlaps refused; N and the box come
// from the file, and a given system.N or system.phi that contradicts it is refused.
#include <catch2/catch.hpp>

#include <unistd.h>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "common/Csv.h"
#include "common/H5mdReader.h"
#include "md/config/ConfigParser.h"
#include "md/io/H5mdWriter.h"
#include "md/io/InitialState.h"
#include "md/run/RunLog.h"
#include "md/run/Simulation.h"

#include "TestUtil.h"

using granagg::test::tempPath;

using namespace granagg::md;

namespace {

std::string writeText(const std::string& name, const std::string& text) {
  const std::string p = tempPath(name);
  std::ofstream(p) << text;
  return p;
}

/// The deepest overlap by comparing every pair (the reference for deepestOverlap's cell grid).
double deepestOverlapAllPairs(const Frame& f) {
  double worst = 0.0;
  for (std::size_t i = 0; i < f.size(); ++i)
    for (std::size_t j = i + 1; j < f.size(); ++j) {
      double r2 = 0.0;
      for (const auto* c : {&f.x, &f.y, &f.z}) {
        double d = std::fabs((*c)[i] - (*c)[j]);
        d = std::min(d, f.box - d);
        r2 += d * d;
      }
      worst = std::max(worst, 1.0 - std::sqrt(r2));
    }
  return worst;
}

/// Four atoms in a LAMMPS data file's box of edge 10 (atom style atomic): phi = 4 pi / 6000.
const char* FOUR_ATOMS =
    "LAMMPS data file: 4 atoms\n\n4 atoms\n1 atom types\n\n"
    "0 10 xlo xhi\n0 10 ylo yhi\n0 10 zlo zhi\n\nMasses\n\n1 1.0\n\nAtoms # atomic\n\n"
    "1 1 1.0 1.0 1.0\n2 1 3.0 1.0 1.0\n3 1 5.0 5.0 5.0\n4 1 8.0 2.0 7.0\n\n"
    "Velocities\n\n1 0.5 0 0\n2 -0.5 0 0\n3 0 0.3 0\n4 0 0 -0.3\n";

/// The message of the std::invalid_argument that f throws ("" if none).
template <class F>
std::string messageOf(F f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

/// A neutral Hertz gas of 500 particles at phi = 0.2: by t = 10 it has cooled to T_g ~ 0.03 and
/// ~0.3 contacts per particle, so every frame from then on holds overlapping pairs.
MdConfig denseGas(double t_end) {
  MdConfig c;
  c.system.N = 500;
  c.system.phi = 0.2;
  c.run.t_end = t_end;
  c.output.checkpoint_wall_seconds = 0.0;
  return c;
}

}  // namespace

TEST_CASE("wrapCoordinate maps into the box and counts the crossings", "[md][io]") {
  const double L = 10.0;
  double x = 3.25;
  std::int32_t im = 4;
  REQUIRE(wrapCoordinate(x, im, L));
  CHECK(x == 3.25);
  CHECK(im == 4);
  x = L;  // exactly L belongs to the next image
  im = 0;
  REQUIRE(wrapCoordinate(x, im, L));
  CHECK(x == 0.0);
  CHECK(im == 1);
  x = -35.0;
  im = 0;
  REQUIRE(wrapCoordinate(x, im, L));
  CHECK(x == 5.0);
  CHECK(im == -4);
  x = -1e-300;  // rounds to L after adding L: must still end inside [0, L)
  im = 0;
  REQUIRE(wrapCoordinate(x, im, L));
  CHECK(x >= 0.0);
  CHECK(x < L);
  CHECK(x + im * L == Approx(0.0).margin(1e-12));
  x = std::nan("");
  CHECK_FALSE(wrapCoordinate(x, im, L));
  x = 1e300;
  CHECK_FALSE(wrapCoordinate(x, im, L));  // image count would overflow int32
}

TEST_CASE("CSV initial state: columns in any order, comments, wrapping", "[md][io]") {
  const std::string p = writeText("good.csv",
                                  "# initial state for a test\n"
                                  "# made by hand\n"
                                  "q,x,y,z,vx,vy,vz\n"
                                  "0.5,1.0,2.0,3.0,0.1,0.2,0.3\n"
                                  "\n"
                                  "-0.5,11.0,-1.0,4.0,-0.1,-0.2,-0.3\n"
                                  "0,9.5,9.5,25.0,0,0,1e-3\n");
  const Frame f = readInitialState(p, 10.0);
  REQUIRE(f.size() == 3);
  CHECK(f.box == 10.0);
  CHECK(f.step == 0);
  CHECK(f.time == 0.0);
  CHECK(f.x[0] == 1.0);
  CHECK(f.vz[0] == 0.3);
  CHECK(f.charge[1] == -0.5);
  CHECK(f.x[1] == 1.0);  // 11 -> 1, one box crossed
  CHECK(f.ix[1] == 1);
  CHECK(f.y[1] == 9.0);  // -1 -> 9
  CHECK(f.iy[1] == -1);
  CHECK(f.z[2] == 5.0);  // 25 -> 5
  CHECK(f.iz[2] == 2);
  CHECK(f.ix[0] == 0);
  CHECK(f.vz[2] == 1e-3);
  std::remove(p.c_str());

  const std::string noq = writeText("noq.csv", "x,y,z,vx,vy,vz\n1,1,1,0,0,0\n2,2,2,0,0,0\n");
  const Frame g = readInitialStateCsv(noq, 5.0);
  CHECK(g.charge == std::vector<double>{0.0, 0.0});
  std::remove(noq.c_str());
}

TEST_CASE("CSV initial state errors name the file, line and particle", "[md][io]") {
  SECTION("non-finite value") {
    const std::string p =
        writeText("nan.csv", "# comment\nx,y,z,vx,vy,vz\n1,1,1,0,0,0\n\n2,2,2,nan,0,0\n");
    CHECK_THROWS_AS(readInitialState(p, 10.0), std::invalid_argument);
    CHECK_THROWS_WITH(readInitialState(p, 10.0), Catch::Contains(p + ":5") &&
                                                     Catch::Contains("particle 1") &&
                                                     Catch::Contains("vx"));
    std::remove(p.c_str());
  }
  SECTION("infinite position") {
    const std::string p =
        writeText("inf.csv", "x,y,z,vx,vy,vz,q\n1,1,1,0,0,0,0\n2,inf,2,0,0,0,0\n");
    CHECK_THROWS_WITH(readInitialState(p, 10.0),
                      Catch::Contains(p + ":3") && Catch::Contains("y = inf"));
    std::remove(p.c_str());
  }
  SECTION("not a number") {
    const std::string p = writeText("abc.csv", "x,y,z,vx,vy,vz\n1,1,1,0,0,0\n2,2,abc,0,0,0\n");
    CHECK_THROWS_WITH(readInitialState(p, 10.0),
                      Catch::Contains(p + ":3") && Catch::Contains("'abc'"));
    std::remove(p.c_str());
  }
  SECTION("too few particles") {
    const std::string p = writeText("one.csv", "x,y,z,vx,vy,vz\n1,1,1,0,0,0\n");
    CHECK_THROWS_WITH(readInitialState(p, 10.0), Catch::Contains("at least 2"));
    std::remove(p.c_str());
  }
  SECTION("missing, unknown and duplicated columns") {
    const std::string a = writeText("missing.csv", "x,y,z,vx,vy\n1,1,1,0,0\n2,2,2,0,0\n");
    CHECK_THROWS_WITH(readInitialState(a, 10.0), Catch::Contains("vz"));
    const std::string b =
        writeText("unknown.csv", "x,y,z,vx,vy,vz,mass\n1,1,1,0,0,0,1\n2,2,2,0,0,0,1\n");
    CHECK_THROWS_WITH(readInitialState(b, 10.0), Catch::Contains("unknown column 'mass'"));
    const std::string c =
        writeText("twice.csv", "x,y,z,vx,vy,vz,x\n1,1,1,0,0,0,1\n2,2,2,0,0,0,1\n");
    CHECK_THROWS_WITH(readInitialState(c, 10.0), Catch::Contains("column 'x' appears twice"));
    for (const auto& p : {a, b, c}) std::remove(p.c_str());
  }
  SECTION("bad box and missing file") {
    const std::string p = writeText("box.csv", "x,y,z,vx,vy,vz\n1,1,1,0,0,0\n2,2,2,0,0,0\n");
    CHECK_THROWS_WITH(readInitialState(p, 0.0), Catch::Contains("box edge must be positive"));
    std::remove(p.c_str());
    CHECK_THROWS_WITH(readInitialState(tempPath("none.csv"), 10.0),
                      Catch::Contains("does not exist"));
  }
}

TEST_CASE("H5MD initial state: the last frame of a trajectory, exactly", "[md][io]") {
  const std::string path = tempPath("traj.h5");
  std::remove(path.c_str());
  Frame last;
  {
    H5mdWriter w(path, 3, {}, "", true);
    for (int k = 0; k < 3; ++k) {
      Frame f;
      f.step = 10 * k;
      f.time = 0.1 * k;
      f.box = 6.0;
      f.x = {0.1 + k, 1.0 / 3.0, 5.999999};
      f.y = {1, 2, 3};
      f.z = {4, 5, 0};
      f.vx = {0.5, -0.25, 1.0 / 7.0};
      f.vy = {0, 0, 0};
      f.vz = {1, 2, 3};
      f.charge = {0.01, -0.02, 0.0};
      f.ix = {k, 0, -k};
      f.iy = {0, 0, 0};
      f.iz = {1, 1, 1};
      w.writeFrame(f);
      last = f;
    }
  }
  const Frame g = readInitialState(path, /*ignored*/ 1.0);
  CHECK(g.step == 20);
  CHECK(g.box == 6.0);
  CHECK(g.x == last.x);
  CHECK(g.vx == last.vx);
  CHECK(g.charge == last.charge);
  CHECK(g.ix == last.ix);
  const Frame first = readInitialStateH5md(path, 0);
  CHECK(first.step == 0);
  CHECK_THROWS_WITH(readInitialStateH5md(path, 3), Catch::Contains("frame 3 requested"));
  std::remove(path.c_str());
  std::remove(H5mdWriter::xdmfPathFor(path).c_str());

  // without velocities it is not an initial state
  {
    H5mdWriter w(path, 2, {}, "", true, /*write_velocities=*/false);
    Frame f;
    f.box = 3.0;
    f.x = {0, 1};
    f.y = {0, 1};
    f.z = {0, 1};
    f.ix = f.iy = f.iz = {0, 0};
    w.writeFrame(f);
  }
  CHECK_THROWS_WITH(readInitialState(path, 1.0), Catch::Contains("no velocities"));
  std::remove(path.c_str());
  std::remove(H5mdWriter::xdmfPathFor(path).c_str());
}

TEST_CASE("LAMMPS data initial state: the same state as the CSV written beside it, to the bit",
          "[md][io]") {
  // scripts/lammps/make_state.py writes one random state both ways (the LAMMPS benchmarks' input,
  // repr floats in both): atom_style sphere for a neutral gas, hybrid sphere charge for +-1
  const std::string dir = tempPath("lmpstate");
  std::filesystem::create_directories(dir);
  for (const bool charged : {false, true}) {
    const std::string cmd = "/usr/bin/python3 " + std::string(GRANAGG_SOURCE_DIR) +
                            "/scripts/lammps/make_state.py 200 0.076 " + dir +
                            (charged ? " --charged" : "");
    REQUIRE(std::system(cmd.c_str()) == 0);
    const Frame a = readInitialState(dir + "/state_200.data", 1.0);  // box: the file's
    const double L = std::cbrt(200 * M_PI / (6 * 0.076));
    const Frame b = readInitialState(dir + "/state_200.csv", L);
    REQUIRE(a.size() == 200);
    CHECK(a.box == Approx(L).epsilon(1e-15));
    bool same = true;
    for (std::size_t i = 0; i < 200; ++i)
      same = same && a.x[i] == b.x[i] && a.y[i] == b.y[i] && a.z[i] == b.z[i] &&
             a.vx[i] == b.vx[i] && a.vy[i] == b.vy[i] && a.vz[i] == b.vz[i] &&
             a.charge[i] == b.charge[i] && a.ix[i] == 0 && a.iz[i] == 0;
    CHECK(same);
    double q2 = 0.0;
    for (double q : a.charge) q2 += q * q;
    CHECK(q2 == (charged ? 200.0 : 0.0));
  }
  std::filesystem::remove_all(dir);
}

TEST_CASE("LAMMPS data initial state: styles, ids out of order, image flags, shifted box",
          "[md][io]") {
  // atom_style charge as write_data writes it: ids out of order, velocities in another order,
  // image flags, a box from -5 to 5
  const std::string p = writeText("charge.data",
                                  "LAMMPS data file via write_data\n\n3 atoms\n1 atom types\n\n"
                                  "-5 5 xlo xhi\n-5 5 ylo yhi\n-5 5 zlo zhi\n\nMasses\n\n1 1\n\n"
                                  "Atoms # charge\n\n"
                                  "7 1 -0.5 1 2 3 0 0 1\n"
                                  "2 1 0.5 -4 -4 -4 -1 0 0\n"
                                  "5 1 0 0 0 6 0 0 0\n\n"
                                  "Velocities\n\n5 0.5 0.6 0.7\n2 0.2 0.3 0.4\n7 0.7 0.8 0.9\n");
  const Frame f = readInitialState(p, 1.0);
  REQUIRE(f.size() == 3);
  CHECK(f.box == 10.0);
  // particle order: ids 2, 5, 7
  CHECK(f.x[0] == 1.0);  // -4 - (-5)
  CHECK(f.ix[0] == -1);
  CHECK(f.charge[0] == 0.5);
  CHECK(f.vx[0] == 0.2);
  CHECK(f.z[1] == 1.0);  // 6 + 5 = 11 wrapped to 1, one more image
  CHECK(f.iz[1] == 1);
  CHECK(f.vz[1] == 0.7);
  CHECK(f.x[2] == 6.0);
  CHECK(f.iz[2] == 1);
  CHECK(f.charge[2] == -0.5);
  CHECK(f.vy[2] == 0.8);
  std::remove(p.c_str());
  // no style comment: atomic told by its 5 columns
  const std::string q = writeText("atomic.data",
                                  "title\n2 atoms\n0 4 xlo xhi\n0 4 ylo yhi\n0 4 zlo zhi\n"
                                  "Atoms\n\n1 1 1 1 1\n2 1 2.5 2.5 2.5\n"
                                  "Velocities\n\n1 1 0 0 0 0 0\n2 -1 0 0 0 0 0\n");
  const Frame g = readInitialState(q, 1.0);
  CHECK(g.size() == 2);
  CHECK(g.x[1] == 2.5);
  CHECK(g.vx[1] == -1.0);
  CHECK(g.charge[1] == 0.0);
  std::remove(q.c_str());
}

TEST_CASE("LAMMPS data initial state errors name the file, line and atom", "[md][io]") {
  const std::string box = "title\n\n2 atoms\n\n0 4 xlo xhi\n0 4 ylo yhi\n0 4 zlo zhi\n\n";
  const std::string vel = "\nVelocities\n\n1 0 0 0\n2 0 0 0\n";
  struct Case {
    std::string text, expected;
  };
  const Case cases[] = {
      {box + "Atoms # sphere\n\n1 1 2.0 0.2387 1 1 1\n2 1 1 1.909859 2 2 2\n" + vel,
       ":11: atom 1: diameter 2 (granagg's particles have diameter 1)"},
      {box + "Atoms # sphere\n\n1 1 1 1.909859 1 1 1\n2 1 1 1 2 2 2\n" + vel,
       ":12: atom 2: density 1"},
      {box + "Masses\n\n1 2.0\n\nAtoms # charge\n\n1 1 0 1 1 1\n2 1 0 2 2 2\n" + vel,
       "type 1 has mass 2"},
      {box + "Atoms # full\n\n1 1 1 0 1 1 1\n2 1 1 0 2 2 2\n" + vel, "atom style 'full'"},
      {box + "Atoms # charge\n\n1 1 0 1 1 1\n1 1 0 2 2 2\n" + vel, "atom id 1 appears twice"},
      {box + "Atoms # charge\n\n1 1 0 1 1 1\n2 1 0 2 2 2\n", "no Velocities section"},
      {box + "Atoms # charge\n\n1 1 0 1 1 1\n2 1 0 2 2 2\n\nVelocities\n\n1 0 0 0\n",
       "atom 2 has no velocity line"},
      {box + "Atoms # charge\n\n1 1 0 1 1 1\n2 1 0 2 2 nan\n" + vel,
       ":12: z 'nan' is not a finite number"},
      {box + "Atoms # charge\n\n1 1 0 1 1 1\n" + vel, "the Atoms section has 1 lines"},
      {"title\n2 atoms\n0 4 xlo xhi\n0 4 ylo yhi\n0 5 zlo zhi\nAtoms\n\n1 1 1 1 1\n2 1 2 2 2\n" +
           vel,
       "the box must be cubic"},
      {"title\n2 atoms\n0 4 xlo xhi\n0 4 ylo yhi\n0 4 zlo zhi\n0 0.5 0 xy xz yz\n", "triclinic"},
  };
  for (const Case& c : cases) {
    const std::string p = writeText("bad.data", c.text);
    INFO(c.text);
    CHECK_THROWS_WITH(readInitialState(p, 1.0), Catch::Contains(c.expected));
    std::remove(p.c_str());
  }
}

TEST_CASE("deepestOverlap finds the deepest pair, across periodic faces, as all pairs do",
          "[md][io]") {
  Frame f;
  f.box = 12.0;
  f.x = {0.1, 11.9, 5.0, 6.0, 3.0};
  f.y = {6.0, 6.0, 5.0, 5.0, 9.0};
  f.z = {6.0, 6.0, 5.0, 5.0, 0.0};
  const OverlapPair p = deepestOverlap(f);  // 0 and 1 at distance 0.2 through the x face
  CHECK(p.i == 0);
  CHECK(p.j == 1);
  CHECK(p.overlap == Approx(0.8).epsilon(1e-12));
  f.x[1] = 4.0;  // now only 2 and 3 touch (distance 1: no overlap)
  CHECK(deepestOverlap(f).overlap <= 0.0);
  // a random dense state, against every pair
  MdConfig c;
  c.system.N = 400;
  c.system.phi = 0.3;
  Frame g = randomInitialState(c);
  for (std::size_t k = 0; k < g.size(); k += 7) g.x[k] = std::fmod(g.x[k] + 0.37, g.box);
  const double all = deepestOverlapAllPairs(g);
  REQUIRE(all > 0.0);
  CHECK(deepestOverlap(g).overlap == all);
}

TEST_CASE("a frame of granagg's own run starts a new run: its contacts are accepted",
          "[md][io][run]") {
  const std::filesystem::path dir = granagg::test::tempDir("start_from_frame");
  RunOptions opt;
  Simulation::start(denseGas(10.0), dir / "cooled", opt).run();
  const std::string traj = (dir / "cooled" / "traj.h5").string();
  const Frame last = readInitialState(traj, 1.0);
  // the frame a user would start from holds contacts: real overlaps, as a cooled gas has
  const double deepest = deepestOverlapAllPairs(last);
  INFO("deepest overlap of the last frame " << deepest);
  REQUIRE(deepest > 0.0);
  REQUIRE(deepest < 0.6);
  CHECK(last.step > 0);

  MdConfig next = denseGas(1.0);
  next.system.initial = traj;
  Simulation sim = Simulation::start(next, dir / "next", opt);
  sim.run();
  const granagg::common::H5mdReader r((dir / "next" / "traj.h5").string());
  REQUIRE(r.frames() > 2);
  // the new run's clock starts at the state: frame 0 is the file's last frame at t = 0, and the
  // run reaches its own run.t_end
  const Frame first = engineFrame(r.readFrame(0));
  CHECK(first.step == 0);
  CHECK(first.time == 0.0);
  CHECK(first.x == last.x);
  CHECK(first.vz == last.vz);
  CHECK(r.readFrame(r.frames() - 1).time == Approx(1.0).margin(0.004));
  if (std::getenv("GRANAGG_KEEP_TEST_FILES") == nullptr) std::filesystem::remove_all(dir);
}

TEST_CASE("an initial state deeper than system.initial_max_overlap is refused, naming the pair",
          "[md][io]") {
  // 4 particles in the box of N = 4, phi = 0.01 (L = 5.9); 1 and 2 at distance 0.3
  const std::string p = writeText("deep.csv",
                                  "x,y,z,vx,vy,vz\n"
                                  "1,1,1,0,0,0\n"
                                  "3,3,3,0,0,0\n"
                                  "3.3,3,3,0,0,0\n"
                                  "5,1,4.5,0,0,0\n");
  MdConfig c;
  c.system.N = 4;
  c.system.phi = 0.01;
  c.system.initial = p;
  try {
    MdConfig copy = c;
    prepareInitialState(copy);
    FAIL("a deep overlap was accepted");
  } catch (const std::invalid_argument& e) {
    const std::string m = e.what();
    CHECK_THAT(m, Catch::Contains("particles 1 and 2 overlap by 0.7"));
    CHECK_THAT(m, Catch::Contains("system.initial_max_overlap = 0.6 (auto: run.max_overlap)"));
    CHECK_THAT(m, Catch::Contains("granagg md --restart"));
  }
  // the tolerance is the key's: above the overlap the state is taken as it is
  c.system.initial_max_overlap = 0.75;
  MdConfig accepted = c;
  const Frame f = prepareInitialState(accepted);
  CHECK(f.x[2] == 3.3);
  // and a small contact beyond a tight tolerance is refused naming that tolerance
  c.system.initial_max_overlap = 0.005;
  std::ofstream(p) << "x,y,z,vx,vy,vz\n1,1,1,0,0,0\n1.99,1,1,0,0,0\n";
  c.system.N = 2;
  CHECK_THROWS_WITH(prepareInitialState(c),
                    Catch::Contains("particles 0 and 1 overlap by 0.01") &&
                        Catch::Contains("system.initial_max_overlap = 0.005;"));
  std::remove(p.c_str());
}

TEST_CASE("a LAMMPS data state sets N and phi, and the run records the phi it has",
          "[md][io][run]") {
  const std::string p = writeText("four.data", FOUR_ATOMS);
  const double phi = 4.0 * M_PI / (6.0 * 1000.0);  // N pi / (6 L^3), L = 10
  const std::string config = "[system]\ninitial = \"" + p + "\"\n[run]\nt_end = 0.05\n";
  MdConfig c = parseConfigString(config, "run.toml");
  CHECK(c.system.N == 1000);  // the defaults, until the file is read
  const Frame f = prepareInitialState(c);
  CHECK(f.box == 10.0);
  CHECK(c.system.N == 4);
  CHECK(c.system.phi == Approx(phi).epsilon(1e-15));
  // the run logs and stores the phi it has
  const std::filesystem::path dir = granagg::test::tempDir("lammps_phi");
  Simulation sim = Simulation::start(parseConfigString(config, "run.toml"), dir / "run", {});
  CHECK(sim.config().system.phi == Approx(phi).epsilon(1e-15));
  std::string log;
  for (const auto& line : runStartLines(sim)) log += line + "\n";
  CHECK_THAT(log, Catch::Contains("N = 4, phi = 0.0020944, box L = 10,"));
  sim.run();
  const granagg::common::H5mdReader r((dir / "run" / "traj.h5").string());
  std::map<std::string, std::string> params;
  for (const auto& [k, v] : r.parameters()) params[k] = v;
  CHECK(std::stod(params.at("system.phi")) == Approx(phi).epsilon(1e-15));
  CHECK(params.at("system.N") == "4");
  CHECK_THAT(r.configToml(), Catch::Contains("N = 4\n"));
  std::filesystem::remove_all(dir);
  std::remove(p.c_str());
}

TEST_CASE("a system.N or system.phi that contradicts the initial file is refused, naming both",
          "[md][io]") {
  const std::string p = writeText("four_given.data", FOUR_ATOMS);
  const std::string config = "[system]\ninitial = \"" + p + "\"\n";
  auto prepared = [&](const std::string& extra, const std::vector<std::string>& set) {
    MdConfig c = parseConfigString(config + extra, "run.toml", set);
    prepareInitialState(c);
    return c;
  };
  const std::string n = messageOf([&] { prepared("N = 1000\n", {}); });
  CHECK_THAT(n, Catch::Contains("system.N = 1000 (run.toml:3:5)") &&
                    Catch::Contains("holds 4 particles"));
  const std::string phi = messageOf([&] { prepared("", {"system.phi=0.076"}); });
  CHECK_THAT(phi, Catch::Contains("system.phi = 0.076 (--set system.phi=0.076)") &&
                      Catch::Contains("phi = 0.0020943951"));
  // values that agree (phi to a relative 1e-3: a box written to a few digits) are taken, and the
  // run has the file's phi
  const MdConfig agreed = prepared("N = 4\nphi = 0.002094\n", {});
  CHECK(agreed.system.N == 4);
  CHECK(agreed.system.phi == Approx(4.0 * M_PI / 6000.0).epsilon(1e-15));
  std::remove(p.c_str());
}

TEST_CASE("an H5MD state sets N and phi from its frame, a CSV takes its box from N and phi",
          "[md][io]") {
  const std::string h5 = tempPath("three.h5");
  std::remove(h5.c_str());
  {
    H5mdWriter w(h5, 3, {}, "", true);
    Frame f;
    f.box = 6.0;
    f.x = {0.5, 2.5, 4.5};
    f.y = f.z = {1.0, 3.0, 5.0};
    f.vx = f.vy = f.vz = {0.1, -0.2, 0.1};
    f.charge = {0, 0, 0};
    f.ix = f.iy = f.iz = {0, 0, 0};
    w.writeFrame(f);
  }
  MdConfig c = parseConfigString("[system]\ninitial = \"" + h5 + "\"\n", "run.toml");
  CHECK(prepareInitialState(c).box == 6.0);
  CHECK(c.system.N == 3);
  CHECK(c.system.phi == Approx(3.0 * M_PI / (6.0 * 216.0)).epsilon(1e-15));
  std::remove(h5.c_str());
  std::remove(H5mdWriter::xdmfPathFor(h5).c_str());

  // CSV: N is the number of rows, the box that of N and system.phi
  const std::string csv = writeText(
      "three.csv", "x,y,z,vx,vy,vz\n0.5,1,1,0,0,0\n2.5,3,3,0,0,0\n4.5,5,5,0,0,0\n");
  MdConfig d = parseConfigString("[system]\nphi = 0.01\ninitial = \"" + csv + "\"\n", "r.toml");
  CHECK(prepareInitialState(d).box == Approx(std::cbrt(3.0 * M_PI / 0.06)).epsilon(1e-15));
  CHECK(d.system.N == 3);
  CHECK(d.system.phi == 0.01);
  MdConfig e = parseConfigString("[system]\ninitial = \"" + csv + "\"\n", "r.toml",
                                 {"system.N=1000"});
  CHECK_THAT(messageOf([&] { prepareInitialState(e); }),
             Catch::Contains("system.N = 1000 (--set system.N=1000)") &&
                 Catch::Contains("holds 3 particles"));
  std::remove(csv.c_str());
}
