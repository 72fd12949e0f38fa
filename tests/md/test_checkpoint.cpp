// Checkpoints: bit-exact round trip, atomic replacement (a failed write keeps the previous
// checkpoint), and clear errors for truncated, corrupted and foreign files.
#include <catch2/catch.hpp>

#include <sys/stat.h>
#include <unistd.h>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>
#include <string>

#include <hdf5.h>

#include "md/io/Checkpoint.h"
#include "md/io/H5mdWriter.h"

#include "TestUtil.h"

using granagg::test::sameBits;
using granagg::test::slurp;
using granagg::test::spit;
using granagg::test::tempPath;

using namespace granagg::md;

namespace {

/// A state with awkward doubles (signed zero, subnormal, huge) so that any rounding shows.
Checkpoint makeCheckpoint(std::size_t n, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 12.0), v(-5.0, 5.0);
  std::uniform_int_distribution<std::int32_t> im(-50, 50);
  Checkpoint c;
  Frame& s = c.state;
  s.step = 123456789012LL;
  s.time = 98.76543210987654;
  s.box = 12.0;
  Checkpoint& e = c;
  for (std::size_t i = 0; i < n; ++i) {
    s.x.push_back(u(rng));
    s.y.push_back(u(rng));
    s.z.push_back(u(rng));
    s.vx.push_back(v(rng));
    s.vy.push_back(v(rng));
    s.vz.push_back(v(rng));
    s.charge.push_back(v(rng) * 1e-3);
    s.ix.push_back(im(rng));
    s.iy.push_back(im(rng));
    s.iz.push_back(im(rng));
    e.forces.x.push_back(v(rng) * 1e4);
    e.forces.y.push_back(v(rng) * 1e4);
    e.forces.z.push_back(v(rng) * 1e4);
  }
  s.vx[0] = -0.0;
  s.vy[0] = std::numeric_limits<double>::denorm_min();
  e.forces.z[0] = 1.7976931348623157e308;
  e.dt = 1.0 / 3000.0;
  e.run.config_toml = "[input]\nversion = 1\n[system]\nN = " + std::to_string(n) + "\n";
  e.run.seed = 0xFFFFFFFFFFFFFFF1ULL;  // needs all 64 unsigned bits
  e.run.frames_written = 17;
  e.engine.ints = {{"neighbor_rebuilds", 4242}, {"min_step", -7}};
  e.engine.reals = {{"wall_seconds", 1234.5}, {"max_displacement", 0.1 + 0.2}};
  return c;
}

bool sameCheckpoint(const Checkpoint& a, const Checkpoint& b) {
  const Frame &s = a.state, &t = b.state;
  const Checkpoint &e = a, &f = b;
  return s.step == t.step && sameBits(s.time, t.time) && sameBits(s.box, t.box) &&
         sameBits(s.x, t.x) && sameBits(s.y, t.y) && sameBits(s.z, t.z) && sameBits(s.vx, t.vx) &&
         sameBits(s.vy, t.vy) && sameBits(s.vz, t.vz) && sameBits(s.charge, t.charge) &&
         sameBits(s.ix, t.ix) && sameBits(s.iy, t.iy) && sameBits(s.iz, t.iz) &&
         sameBits(e.forces.x, f.forces.x) && sameBits(e.forces.y, f.forces.y) &&
         sameBits(e.forces.z, f.forces.z) && sameBits(e.dt, f.dt) &&
         e.run.config_toml == f.run.config_toml && e.run.seed == f.run.seed &&
         e.run.frames_written == f.run.frames_written && e.engine.ints == f.engine.ints &&
         e.engine.reals.size() == f.engine.reals.size() &&
         std::equal(e.engine.reals.begin(), e.engine.reals.end(), f.engine.reals.begin(),
                    [](const auto& p, const auto& q) {
                      return p.first == q.first && sameBits(p.second, q.second);
                    });
}

bool fileExists(const std::string& p) {
  struct stat st;
  return ::stat(p.c_str(), &st) == 0;
}

}  // namespace

TEST_CASE("checkpoint round trip is bit-exact", "[md][io]") {
  const std::string path = tempPath("rt.h5");
  const Checkpoint c = makeCheckpoint(1000, 7);
  writeCheckpoint(path, c);
  CHECK_FALSE(fileExists(path + ".tmp"));  // renamed into place
  const Checkpoint r = readCheckpoint(path);
  CHECK(sameCheckpoint(c, r));
  CHECK(r.run.seed == 0xFFFFFFFFFFFFFFF1ULL);
  CHECK(r.engine.ints.at("min_step") == -7);

  // replacing it with a newer checkpoint
  const Checkpoint c2 = makeCheckpoint(1000, 8);
  writeCheckpoint(path, c2);
  CHECK(sameCheckpoint(readCheckpoint(path), c2));
  std::remove(path.c_str());
}

TEST_CASE("a checkpoint with an older build's /run/next_frame_index reads", "[md][io]") {
  // Older builds also stored the index of the next scheduled frame, which a restart recomputes
  // from the step; such files must still resume, with the attribute ignored.
  const std::string path = tempPath("older.h5");
  const Checkpoint c = makeCheckpoint(10, 3);
  writeCheckpoint(path, c);
  {
    const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    REQUIRE(f >= 0);
    const hid_t g = H5Gopen2(f, "run", H5P_DEFAULT);
    const hid_t s = H5Screate(H5S_SCALAR);
    const hid_t a = H5Acreate2(g, "next_frame_index", H5T_STD_U64LE, s, H5P_DEFAULT, H5P_DEFAULT);
    const std::uint64_t v = 19;
    REQUIRE(H5Awrite(a, H5T_NATIVE_UINT64, &v) >= 0);
    H5Aclose(a);
    H5Sclose(s);
    H5Gclose(g);
    H5Fclose(f);
  }
  CHECK(sameCheckpoint(readCheckpoint(path), c));
  std::remove(path.c_str());
}

TEST_CASE("a failed checkpoint write keeps the previous checkpoint", "[md][io]") {
  const std::string path = tempPath("atomic.h5");
  const Checkpoint good = makeCheckpoint(50, 1);
  writeCheckpoint(path, good);
  // Simulate a failure while writing: the temporary file cannot be created because a directory
  // of that name is in the way.
  const std::string tmp = path + ".tmp";
  REQUIRE(::mkdir(tmp.c_str(), 0700) == 0);
  const Checkpoint next = makeCheckpoint(50, 2);
  CHECK_THROWS_AS(writeCheckpoint(path, next), std::runtime_error);
  CHECK_THROWS_WITH(writeCheckpoint(path, next), Catch::Contains(tmp));
  CHECK(sameCheckpoint(readCheckpoint(path), good));  // the old one survives intact
  ::rmdir(tmp.c_str());
  // and once the obstacle is gone, writing works again
  writeCheckpoint(path, next);
  CHECK(sameCheckpoint(readCheckpoint(path), next));
  std::remove(path.c_str());
}

TEST_CASE("checkpoint arguments are validated", "[md][io]") {
  const std::string path = tempPath("invalid.h5");
  Checkpoint c = makeCheckpoint(10, 3);
  Checkpoint bad = c;
  bad.forces.y.pop_back();
  CHECK_THROWS_WITH(writeCheckpoint(path, bad),
                    Catch::Contains("fy has 9 entries, expected N = 10"));
  bad = c;
  bad.dt = 0.0;
  CHECK_THROWS_WITH(writeCheckpoint(path, bad),
                    Catch::Contains("dt must be positive"));
  bad = c;
  bad.state.charge.clear();
  CHECK_THROWS_AS(writeCheckpoint(path, bad), std::invalid_argument);
  CHECK_FALSE(fileExists(path));
}

TEST_CASE("corrupt or foreign checkpoints give clear errors", "[md][io]") {
  const std::string path = tempPath("corrupt.h5");
  Checkpoint c = makeCheckpoint(4096, 4);
  // a recognisable pattern in x to locate its bytes in the file
  for (std::size_t i = 0; i < c.state.x.size(); ++i)
    c.state.x[i] = 1.0 + 1e-9 * static_cast<double>(i);
  writeCheckpoint(path, c);
  const std::string bytes = slurp(path);

  SECTION("truncated") {
    const std::string half = tempPath("half.h5");
    spit(half, bytes.substr(0, bytes.size() / 2));
    CHECK_THROWS_AS(readCheckpoint(half), std::runtime_error);
    CHECK_THROWS_WITH(readCheckpoint(half), Catch::Contains(half));
    std::remove(half.c_str());
  }
  SECTION("a flipped byte in the particle data fails the checksum") {
    double probe = c.state.x[100];
    const std::string needle(reinterpret_cast<const char*>(&probe), sizeof probe);
    const std::size_t at = bytes.find(needle);
    REQUIRE(at != std::string::npos);
    std::string broken = bytes;
    broken[at + 3] = static_cast<char>(broken[at + 3] ^ 0x10);
    const std::string bad = tempPath("flipped.h5");
    spit(bad, broken);
    CHECK_THROWS_WITH(readCheckpoint(bad), Catch::Contains(bad) && Catch::Contains("/state/x"));
    std::remove(bad.c_str());
  }
  SECTION("not HDF5, missing, not a checkpoint") {
    const std::string text = tempPath("text.h5");
    spit(text, "not a checkpoint\n");
    CHECK_THROWS_WITH(readCheckpoint(text),
                      Catch::Contains(text) && Catch::Contains("not an HDF5 file"));
    std::remove(text.c_str());
    CHECK_THROWS_WITH(readCheckpoint(tempPath("missing.h5")), Catch::Contains("does not exist"));
    const std::string traj = tempPath("traj.h5");
    { H5mdWriter w(traj, 3, {}, "", true); }
    CHECK_THROWS_WITH(readCheckpoint(traj), Catch::Contains("not a granagg checkpoint"));
    std::remove(traj.c_str());
    std::remove(H5mdWriter::xdmfPathFor(traj).c_str());
  }
  std::remove(path.c_str());
}
