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

TEST_CASE("a dataset's extent is checked against the bytes the file stores before allocation",
          "[common][io]") {
  // A chunked position/value of 1 x 1e9 x 3 doubles (24 GB) with no chunk written: HDF5 accepts
  // the file (unwritten chunks read as fill values), granagg refuses it before sizing a frame.
  const std::string path = tempPath("reader_claims.h5");
  writeFile(path);
  {
    h5::Handle file(H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT));
    REQUIRE(file.valid());
    REQUIRE(H5Ldelete(file.get(), "particles/all/position/value", H5P_DEFAULT) >= 0);
    const hsize_t dims[3] = {1, 1000000000, 3}, chunk[3] = {1, 1024, 3};
    h5::Handle space(H5Screate_simple(3, dims, nullptr));
    h5::Handle dcpl(H5Pcreate(H5P_DATASET_CREATE));
    H5Pset_chunk(dcpl.get(), 3, chunk);
    h5::Handle d(H5Dcreate2(file.get(), "particles/all/position/value", H5T_IEEE_F64LE,
                            space.get(), H5P_DEFAULT, dcpl.get(), H5P_DEFAULT));
    REQUIRE(d.valid());
  }
  try {
    H5mdReader r(path, "all");
    FAIL("the reader accepted a dataset of 24 GB that stores nothing");
  } catch (const std::invalid_argument& e) {
    CHECK_THAT(e.what(), Catch::Contains("reader_claims.h5") &&
                             Catch::Contains("position/value") &&
                             Catch::Contains("1 x 1000000000 x 3") &&
                             Catch::Contains("24.0 GB") && Catch::Contains("stores 0 bytes"));
  }
  std::remove(path.c_str());
}

TEST_CASE("byteText writes byte counts in decimal units", "[common][io]") {
  CHECK(h5::byteText(0) == "0 bytes");
  CHECK(h5::byteText(999) == "999 bytes");
  CHECK(h5::byteText(13400) == "13.4 kB");
  CHECK(h5::byteText(24e9) == "24.0 GB");
}
