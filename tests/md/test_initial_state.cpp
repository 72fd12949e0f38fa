// User-given initial states: CSV (columns, comments, wrapping into the caller's box, errors
// naming the line and particle) and H5MD (last frame of a trajectory), plus coordinate wrapping.
#include <catch2/catch.hpp>

#include <unistd.h>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <string>

#include "md/io/H5mdWriter.h"
#include "md/io/InitialState.h"

#include "TestUtil.h"

using granagg::test::tempPath;

using namespace granagg::md;

namespace {

std::string writeText(const std::string& name, const std::string& text) {
  const std::string p = tempPath(name);
  std::ofstream(p) << text;
  return p;
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
