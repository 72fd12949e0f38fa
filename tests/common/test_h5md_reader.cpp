/// The one H5MD reader's own rules (common/H5mdReader.h), where md's and analysis's former
/// readers differed: the default particle group, an element sampled on another grid, a missing
/// time dataset, image counts of a file without an image element. The readers' other behaviour
/// is tested through md (tests/md/test_h5md.cpp) and analysis (tests/analysis/test_readers.cpp).
#include <catch2/catch.hpp>

#include <cstdio>
#include <string>
#include <vector>

#include "common/H5mdReader.h"
#include "common/Hdf5.h"

#include "TestUtil.h"

using granagg::test::tempPath;
using namespace granagg::common;

namespace {

/// A file by hand: groups "aaa" (1 particle) and "all" (2 particles, 3 frames at steps 0, 10, 20,
/// positions unwrapped in a box of 4, no time dataset), velocity at steps 0 and 20 only, charge
/// on position's grid.
void writeFile(const std::string& path) {
  h5::silenceErrors();
  h5::Handle file(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT));
  REQUIRE(file.valid());
  const hid_t f = file.get();
  for (const char* g : {"aaa", "all"}) {
    const hsize_t n = std::string(g) == "all" ? 2 : 1;
    const std::string base = std::string("particles/") + g;
    h5::Handle pos = h5::createGroup(f, base + "/position", "t");
    std::vector<double> xyz(3 * n * 3, 1.0);
    xyz[3 * n] = 5.0;  // frame 1, particle 0, x: one box length beyond
    h5::writeDataset(pos.get(), "value", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, {3, n, 3}, xyz.data(),
                     "t");
    const long long steps[3] = {0, 10, 20};
    h5::writeDataset(pos.get(), "step", H5T_STD_I64LE, H5T_NATIVE_LLONG, {3}, steps, "t");
    h5::Handle box = h5::createGroup(f, base + "/box", "t");
    const double edges[3] = {4.0, 4.0, 4.0};
    h5::writeDataset(box.get(), "edges", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, {3}, edges, "t");
    if (n != 2) continue;
    h5::Handle vel = h5::createGroup(f, base + "/velocity", "t");
    const std::vector<double> v(2 * n * 3, 0.5);
    h5::writeDataset(vel.get(), "value", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, {2, n, 3}, v.data(),
                     "t");
    const long long vsteps[2] = {0, 20};
    h5::writeDataset(vel.get(), "step", H5T_STD_I64LE, H5T_NATIVE_LLONG, {2}, vsteps, "t");
    h5::Handle chg = h5::createGroup(f, base + "/charge", "t");
    const double q[6] = {1, -1, 2, -2, 3, -3};
    h5::writeDataset(chg.get(), "value", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, {3, n}, q, "t");
    h5::writeDataset(chg.get(), "step", H5T_STD_I64LE, H5T_NATIVE_LLONG, {3}, steps, "t");
  }
}

}  // namespace

TEST_CASE("H5MD reader: the default group, other grids, missing time, crossings", "[common][io]") {
  const std::string path = tempPath("reader_rules.h5");
  writeFile(path);
  H5mdReader r(path);
  CHECK(r.particleGroup() == "all");  // "all" wins over the first name in order ("aaa")
  REQUIRE(r.size() == 2);
  REQUIRE(r.frames() == 3);
  CHECK(r.time(2) == 20.0);  // no time dataset: the steps stand in
  CHECK(H5mdReader(path, "aaa").size() == 1);

  // velocity sampled at steps 0 and 20: frame 1 (step 10) has none, frames 0 and 2 have theirs
  CHECK(r.readFrame(0).velocity.size() == 6);
  CHECK(r.readFrame(1).velocity.empty());
  CHECK(r.readFrame(2).velocity == std::vector<double>(6, 0.5));
  CHECK(r.readFrame(2).charge == std::vector<double>{3, -3});

  // no image element: no image counts, unless asked for the crossings of the wrap
  TrajectoryFrame f = r.readFrame(1);
  CHECK(f.position[0] == 1.0);
  CHECK(f.image.empty());
  r.keepWrapCrossings(true);
  r.readFrame(1, f);
  REQUIRE(f.image.size() == 6);
  CHECK(f.image[0] == 1);
  CHECK(f.unwrapped(0, 0) == 5.0);

  try {
    (void)r.readFrame(3);
    FAIL("no error");
  } catch (const TrajectoryError& e) {
    CHECK(e.frame() == 3);
    CHECK_THAT(e.what(), Catch::Contains(path) && Catch::Contains("3 complete frames"));
  }
  std::remove(path.c_str());
}
