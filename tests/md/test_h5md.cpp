// H5MD trajectories: exact round trip, layout against the H5MD 1.1 specification (and the
// MDAnalysis reader quirks of docs/ARCHITECTURE.md), refusal to overwrite, clear errors for
// truncated / foreign / malformed files, restart truncation, the XDMF sidecar, and the
// scripts/check_h5md.py checker.
#include <catch2/catch.hpp>

#include <sys/wait.h>
#include <unistd.h>
#include <algorithm>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>
#include <sstream>
#include <string>

#include "common/H5mdReader.h"
#include "common/Hdf5.h"
#include "md/io/H5mdWriter.h"
#include "md/io/InitialState.h"

#include "TestUtil.h"

using granagg::test::sameBits;
using granagg::test::slurp;
using granagg::test::tempPath;

using namespace granagg::md;
using granagg::common::H5mdReader;
using granagg::common::ObservableSeries;
namespace h5 = granagg::common::h5;

namespace {

void removeTrajectory(const std::string& path) {
  std::remove(path.c_str());
  std::remove(H5mdWriter::xdmfPathFor(path).c_str());
}

/// A random but reproducible frame with wrapped positions, including the edge values 0 and the
/// largest double below L, a subnormal velocity and large image counts.
Frame makeFrame(std::size_t n, std::int64_t step, unsigned seed, double L = 7.5) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, L), v(-3.0, 3.0), q(-1.0, 1.0);
  std::uniform_int_distribution<std::int32_t> im(-1000, 1000);
  Frame f;
  f.step = step;
  f.time = 1e-3 * static_cast<double>(step) + 1.0 / 3.0;
  f.box = L;
  for (std::size_t i = 0; i < n; ++i) {
    f.x.push_back(u(rng));
    f.y.push_back(u(rng));
    f.z.push_back(u(rng));
    f.vx.push_back(v(rng));
    f.vy.push_back(v(rng));
    f.vz.push_back(v(rng));
    f.charge.push_back(q(rng));
    f.ix.push_back(im(rng));
    f.iy.push_back(im(rng));
    f.iz.push_back(im(rng));
  }
  f.x[0] = 0.0;
  f.y[0] = std::nextafter(L, 0.0);
  f.vx[0] = 4.9e-324;  // subnormal
  f.iz[0] = std::numeric_limits<std::int32_t>::min() + 5;
  return f;
}

bool sameFrame(const Frame& a, const Frame& b) {
  return a.step == b.step && std::memcmp(&a.time, &b.time, sizeof(double)) == 0 && a.box == b.box &&
         sameBits(a.x, b.x) && sameBits(a.y, b.y) && sameBits(a.z, b.z) && sameBits(a.vx, b.vx) &&
         sameBits(a.vy, b.vy) && sameBits(a.vz, b.vz) && sameBits(a.charge, b.charge) &&
         sameBits(a.ix, b.ix) && sameBits(a.iy, b.iy) && sameBits(a.iz, b.iz);
}

const std::vector<std::pair<std::string, std::string>> PARAMS = {
    {"command", "granagg md --config run.toml"},
    {"seed", "42"},
    {"version", "granagg test"},
    {"system.N", "16"}};
const std::string TOML = "[input]\nversion = 1\n\n[system]\nN = 16\nseed = 42\n";

/// Writes `frames` frames of n particles (steps 0, 100, 200, ...) plus observables every 25 steps.
std::vector<Frame> writeTrajectory(const std::string& path, std::size_t n, int frames,
                                   bool velocities = true) {
  removeTrajectory(path);
  std::vector<Frame> written;
  H5mdWriter w(path, n, PARAMS, TOML, /*overwrite=*/false, velocities);
  for (int k = 0; k < frames; ++k) {
    for (int s = 0; s < 4; ++s) {
      const std::int64_t step = 100 * k + 25 * s;
      w.writeObservables(step, 1e-3 * step,
                         {{"kinetic_energy", 1.5 + step}, {"temperature", 1.0 / (1 + step)}});
    }
    written.push_back(makeFrame(n, 100 * k, 1000u + static_cast<unsigned>(k)));
    w.writeFrame(written.back());
  }
  w.close();
  return written;
}

/// Number of hard links to the object at `path` (H5O reference count).
unsigned linkCount(hid_t file, const std::string& path) {
#if H5_VERSION_GE(1, 12, 0)
  H5O_info2_t info;
  REQUIRE(H5Oget_info_by_name3(file, path.c_str(), &info, H5O_INFO_BASIC, H5P_DEFAULT) >= 0);
#else
  H5O_info_t info;
  REQUIRE(H5Oget_info_by_name2(file, path.c_str(), &info, H5O_INFO_BASIC, H5P_DEFAULT) >= 0);
#endif
  return info.rc;
}

std::vector<hsize_t> dimsOf(hid_t file, const std::string& path,
                            std::vector<hsize_t>* maxdims = nullptr) {
  h5::Handle d(H5Dopen2(file, path.c_str(), H5P_DEFAULT));
  REQUIRE(d.valid());
  h5::Handle s(H5Dget_space(d.get()));
  const int rank = H5Sget_simple_extent_ndims(s.get());
  std::vector<hsize_t> dims(static_cast<std::size_t>(rank)), maxd(static_cast<std::size_t>(rank));
  H5Sget_simple_extent_dims(s.get(), dims.data(), maxd.data());
  if (maxdims) *maxdims = maxd;
  return dims;
}

/// Class and size of a dataset's stored type.
std::pair<H5T_class_t, std::size_t> typeOf(hid_t file, const std::string& path) {
  h5::Handle d(H5Dopen2(file, path.c_str(), H5P_DEFAULT));
  REQUIRE(d.valid());
  h5::Handle t(H5Dget_type(d.get()));
  return {H5Tget_class(t.get()), H5Tget_size(t.get())};
}

}  // namespace

TEST_CASE("H5MD frames read back bit for bit", "[md][io]") {
  const std::string path = tempPath("roundtrip.h5");
  const std::size_t n = 16;
  const auto written = writeTrajectory(path, n, 3);

  H5mdReader r(path);
  CHECK(r.particleGroup() == "all");
  REQUIRE(r.size() == n);
  REQUIRE(r.frames() == 3);
  CHECK(r.hasVelocity());
  CHECK(r.hasCharge());
  CHECK(r.hasImage());
  for (std::size_t k = 0; k < 3; ++k) {
    const Frame f = engineFrame(r.readFrame(k));
    CHECK(sameFrame(f, written[k]));
    CHECK(r.step(k) == written[k].step);
    CHECK(r.time(k) == written[k].time);
    CHECK(r.box(k) == written[k].box);
  }
  CHECK_THROWS_WITH(engineFrame(r.readFrame(3)),
                    Catch::Contains(path) && Catch::Contains("frame 3"));

  // provenance
  const auto params = r.parameters();
  for (const auto& kv : PARAMS) CHECK(std::find(params.begin(), params.end(), kv) != params.end());
  CHECK(r.configToml() == TOML);
  CHECK(r.creator().first == "granagg");
  CHECK(r.creator().second.rfind("granagg ", 0) == 0);

  // finely sampled observables, kept apart from the frame grid
  const auto names = r.observableNames();
  REQUIRE(names.size() == 2);
  const ObservableSeries ke = r.readObservable("kinetic_energy");
  REQUIRE(ke.value.size() == 12);
  CHECK(ke.step[5] == 125);
  CHECK(ke.time[5] == 1e-3 * 125);
  CHECK(ke.value[5] == 1.5 + 125);
  CHECK(r.readObservable("temperature").value[11] == 1.0 / (1 + 275));  // last sample: step 275
  CHECK_THROWS_WITH(r.readObservable("pressure"),
                    Catch::Contains("no observable named 'pressure'"));
  r = H5mdReader(tempPath("roundtrip.h5"));  // move assignment closes the previous file
  removeTrajectory(path);
}

TEST_CASE("Writer and reader release every HDF5 handle", "[md][io]") {
  const std::string path = tempPath("handles.h5");
  writeTrajectory(path, 4, 2);
  {
    H5mdReader r(path);
    (void)engineFrame(r.readFrame(1));
    (void)r.readObservable("temperature");
    (void)r.parameters();
  }
  {
    H5mdWriter w = H5mdWriter::reopen(path, 4, 0);
    w.writeObservables(10, 0.01, {{"temperature", 1.0}, {"kinetic_energy", 2.0}});
  }
  CHECK(H5Fget_obj_count(H5F_OBJ_ALL, H5F_OBJ_ALL) == 0);
  removeTrajectory(path);
}

TEST_CASE("H5MD layout follows the H5MD 1.1 specification and MDAnalysis' reader", "[md][io]") {
  const std::string path = tempPath("layout.h5");
  const std::size_t n = 5;
  const auto written = writeTrajectory(path, n, 2);
  h5::silenceErrors();
  h5::Handle file(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT));
  REQUIRE(file.valid());
  const hid_t f = file.get();

  // /h5md: version = [1, 1] (integer), author name, creator name and version
  {
    h5::Handle g(H5Gopen2(f, "/h5md", H5P_DEFAULT));
    REQUIRE(g.valid());
    h5::Handle a = h5::openAttribute(g.get(), "version");
    REQUIRE(a.valid());
    h5::Handle t(H5Aget_type(a.get()));
    CHECK(H5Tget_class(t.get()) == H5T_INTEGER);
    CHECK(h5::readNumericAttribute<std::int64_t>(a.get(), H5T_NATIVE_INT64, "version") ==
          std::vector<std::int64_t>{1, 1});
    h5::Handle author(H5Gopen2(f, "/h5md/author", H5P_DEFAULT));
    h5::Handle aname = h5::openAttribute(author.get(), "name");
    REQUIRE(aname.valid());
    CHECK_FALSE(h5::readString(aname.get(), true, "author").empty());
    h5::Handle creator(H5Gopen2(f, "/h5md/creator", H5P_DEFAULT));
    h5::Handle cname = h5::openAttribute(creator.get(), "name");
    h5::Handle cver = h5::openAttribute(creator.get(), "version");
    REQUIRE(cname.valid());
    REQUIRE(cver.valid());
    CHECK(h5::readString(cname.get(), true, "creator") == "granagg");
  }

  // box: dimension 3, boundary periodic x3, edges a [frames,3,3] time series with diag L
  {
    h5::Handle box(H5Gopen2(f, "/particles/all/box", H5P_DEFAULT));
    REQUIRE(box.valid());
    h5::Handle dim = h5::openAttribute(box.get(), "dimension");
    REQUIRE(dim.valid());
    CHECK(h5::readNumericAttribute<std::int64_t>(dim.get(), H5T_NATIVE_INT64, "dimension") ==
          std::vector<std::int64_t>{3});
    h5::Handle bnd = h5::openAttribute(box.get(), "boundary");
    REQUIRE(bnd.valid());
    CHECK(h5::readStringArrayAttribute(bnd.get(), "boundary") ==
          std::vector<std::string>{"periodic", "periodic", "periodic"});
    CHECK(dimsOf(f, "/particles/all/box/edges/value") == std::vector<hsize_t>{2, 3, 3});
    h5::Handle e(H5Dopen2(f, "/particles/all/box/edges/value", H5P_DEFAULT));
    const auto edges = h5::readAll<double>(e.get(), H5T_NATIVE_DOUBLE, "edges");
    CHECK(edges[0] == written[0].box);
    CHECK(edges[4] == written[0].box);
    CHECK(edges[8] == written[0].box);
    CHECK(edges[1] == 0.0);
  }

  // time series: value [frames, N, 3] extendible, step int64, time double, no unit attributes
  std::vector<hsize_t> maxdims;
  CHECK(dimsOf(f, "/particles/all/position/value", &maxdims) == std::vector<hsize_t>{2, n, 3});
  CHECK(maxdims[0] == H5S_UNLIMITED);
  CHECK(dimsOf(f, "/particles/all/velocity/value") == std::vector<hsize_t>{2, n, 3});
  CHECK(dimsOf(f, "/particles/all/charge/value") == std::vector<hsize_t>{2, n});
  CHECK(dimsOf(f, "/particles/all/image/value") == std::vector<hsize_t>{2, n, 3});
  CHECK(dimsOf(f, "/particles/all/position/step") == std::vector<hsize_t>{2});
  CHECK(dimsOf(f, "/particles/all/position/time") == std::vector<hsize_t>{2});
  CHECK(typeOf(f, "/particles/all/position/value") == std::make_pair(H5T_FLOAT, std::size_t{8}));
  CHECK(typeOf(f, "/particles/all/image/value") == std::make_pair(H5T_INTEGER, std::size_t{4}));
  CHECK(typeOf(f, "/particles/all/position/step") == std::make_pair(H5T_INTEGER, std::size_t{8}));
  CHECK(typeOf(f, "/particles/all/position/time") == std::make_pair(H5T_FLOAT, std::size_t{8}));
  {
    h5::Handle d(H5Dopen2(f, "/particles/all/position/value", H5P_DEFAULT));
    CHECK_FALSE(h5::openAttribute(d.get(), "unit").valid());
  }
  // one step/time pair shared by hard links: position, velocity, charge, image, box/edges
  CHECK(linkCount(f, "/particles/all/position/step") == 5);
  CHECK(linkCount(f, "/particles/all/box/edges/time") == 5);

  // observables kept out of /observables (MDAnalysis indexes those by frame)
  CHECK_FALSE(h5::exists(f, "/observables"));
  CHECK(dimsOf(f, "/granagg/observables/kinetic_energy/value") == std::vector<hsize_t>{8});
  CHECK(dimsOf(f, "/granagg/observables/temperature/step") == std::vector<hsize_t>{8});

  // MDAnalysis picks the first group under /particles: ours is the only one
  h5::Handle particles(H5Gopen2(f, "/particles", H5P_DEFAULT));
  CHECK(h5::children(particles.get()) == std::vector<std::string>{"all"});

  // /parameters: string attributes and the TOML text
  {
    h5::Handle par(H5Gopen2(f, "/parameters", H5P_DEFAULT));
    REQUIRE(par.valid());
    h5::Handle seed = h5::openAttribute(par.get(), "seed");
    REQUIRE(seed.valid());
    CHECK(h5::readString(seed.get(), true, "seed") == "42");
    h5::Handle toml(H5Dopen2(f, "/parameters/config_toml", H5P_DEFAULT));
    REQUIRE(toml.valid());
    CHECK(h5::readString(toml.get(), false, "toml") == TOML);
  }
  file.reset();
  removeTrajectory(path);
}

TEST_CASE("H5mdWriter never overwrites silently", "[md][io]") {
  const std::string path = tempPath("exists.h5");
  removeTrajectory(path);
  { H5mdWriter w(path, 4, {}, "", false); }
  CHECK_THROWS_AS(H5mdWriter(path, 4, {}, "", false), std::invalid_argument);
  CHECK_THROWS_WITH(H5mdWriter(path, 4, {}, "", false),
                    Catch::Contains(path) && Catch::Contains("already exists"));
  CHECK_NOTHROW(H5mdWriter(path, 4, {}, "", /*overwrite=*/true));
  removeTrajectory(path);
}

TEST_CASE("H5mdWriter rejects bad arguments and frames", "[md][io]") {
  const std::string path = tempPath("bad.h5");
  removeTrajectory(path);
  CHECK_THROWS_WITH(H5mdWriter(path, 0, {}, "", false), Catch::Contains("N >= 1"));
  CHECK_THROWS_WITH(H5mdWriter(path, 3, {{"seed", "1"}, {"seed", "2"}}, "", false),
                    Catch::Contains("'seed' is given twice"));
  H5mdWriter w(path, 3, {}, "", true);
  Frame f = makeFrame(3, 10, 1);
  Frame small = makeFrame(2, 10, 1);
  CHECK_THROWS_WITH(w.writeFrame(small), Catch::Contains("2 particles, expected 3"));
  Frame novel = f;
  novel.vy.clear();
  CHECK_THROWS_WITH(w.writeFrame(novel), Catch::Contains("vy"));
  Frame nan = f;
  nan.z[1] = std::nan("");
  CHECK_THROWS_WITH(w.writeFrame(nan), Catch::Contains("particle 1") && Catch::Contains("z"));
  w.writeFrame(f);
  CHECK_THROWS_WITH(w.writeFrame(f), Catch::Contains("steps must increase"));
  w.writeObservables(1, 0.1, {{"a", 1.0}});
  CHECK_THROWS_WITH(w.writeObservables(2, 0.2, {{"b", 1.0}}),
                    Catch::Contains("unknown observable 'b'"));
  CHECK_THROWS_WITH(w.writeObservables(1, 0.2, {{"a", 1.0}}), Catch::Contains("must increase"));
  CHECK(w.frames() == 1);
  w.close();
  CHECK_THROWS_AS(w.writeFrame(f), std::logic_error);
  removeTrajectory(path);
}

TEST_CASE("H5mdWriter wraps stray positions and keeps unwrapped coordinates", "[md][io]") {
  const std::string path = tempPath("wrap.h5");
  removeTrajectory(path);
  Frame f = makeFrame(4, 0, 3, 10.0);
  f.x[1] = 10.0;   // exactly L: engine round-off
  f.y[2] = -0.25;  // just outside
  f.z[3] = 35.5;   // several boxes away
  f.ix[1] = 2;
  f.iy[2] = 0;
  f.iz[3] = -1;
  f.charge.clear();  // neutral gas: written as zeros
  {
    H5mdWriter w(path, 4, {}, "", true);
    w.writeFrame(f);
  }
  const Frame g = engineFrame(H5mdReader(path).readFrame(0));
  CHECK(g.x[1] == 0.0);
  CHECK(g.ix[1] == 3);
  CHECK(g.y[2] == 9.75);
  CHECK(g.iy[2] == -1);
  CHECK(g.z[3] == 5.5);
  CHECK(g.iz[3] == 2);
  CHECK(g.x[0] == f.x[0]);  // untouched particles bit for bit
  CHECK(g.charge == std::vector<double>(4, 0.0));
  removeTrajectory(path);
}

TEST_CASE("H5MD reader errors name the file: truncated, not HDF5, missing", "[md][io]") {
  const std::string path = tempPath("full.h5");
  writeTrajectory(path, 64, 4);
  const std::string bytes = slurp(path);
  REQUIRE(bytes.size() > 1000);

  const std::string half = tempPath("half.h5");
  {
    std::ofstream out(half, std::ios::binary);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size() / 2));
  }
  CHECK_THROWS_AS(H5mdReader(half), std::runtime_error);
  CHECK_THROWS_WITH(H5mdReader(half), Catch::Contains(half));

  const std::string text = tempPath("text.h5");
  {
    std::ofstream out(text);
    out << "x,y,z\n1,2,3\n";
  }
  CHECK_THROWS_WITH(H5mdReader(text), Catch::Contains(text) && Catch::Contains("not an HDF5 file"));
  CHECK_THROWS_WITH(H5mdReader(tempPath("nonexistent.h5")), Catch::Contains("does not exist"));
  CHECK_THROWS_WITH(H5mdReader(path, "solvent"),
                    Catch::Contains("no particle group '/particles/solvent'") &&
                        Catch::Contains("available: all"));
  std::remove(half.c_str());
  std::remove(text.c_str());
  removeTrajectory(path);
}

TEST_CASE("H5MD reader accepts another engine's file and names bad datasets", "[md][io]") {
  // A minimal H5MD file as another engine might write it: group "atoms", float32 unwrapped
  // positions, fixed-increment step/time (scalar + offset), a fixed box edges vector, no image,
  // no velocity, no charge.
  const std::string path = tempPath("foreign.h5");
  std::remove(path.c_str());
  const std::size_t n = 3, frames = 2;
  const double L = 4.0;
  auto build = [&](bool with_box, bool bad_velocity) {
    std::remove(path.c_str());
    h5::silenceErrors();
    h5::Handle file(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT));
    REQUIRE(file.valid());
    const hid_t f = file.get();
    {
      h5::Handle g = h5::createGroup(f, "h5md", "t");
      const int v[2] = {1, 0};
      h5::writeAttribute(g.get(), "version", H5T_STD_I32LE, H5T_NATIVE_INT, v, {2}, "t");
      h5::Handle c = h5::createGroup(g.get(), "creator", "t");
      h5::writeStringAttribute(c.get(), "name", "other-engine", "t");
    }
    h5::Handle pos = h5::createGroup(f, "particles/atoms/position", "t");
    const float xyz[frames][n][3] = {{{0.5f, 1.f, 1.5f}, {4.5f, -1.f, 2.f}, {3.f, 3.f, 9.f}},
                                     {{0.75f, 1.f, 1.5f}, {4.25f, -0.5f, 2.f}, {3.f, 3.f, -2.f}}};
    const hsize_t dims[3] = {frames, n, 3};
    h5::Handle space(H5Screate_simple(3, dims, nullptr));
    h5::Handle d(H5Dcreate2(pos.get(), "value", H5T_IEEE_F32LE, space.get(), H5P_DEFAULT,
                            H5P_DEFAULT, H5P_DEFAULT));
    H5Dwrite(d.get(), H5T_NATIVE_FLOAT, H5S_ALL, H5S_ALL, H5P_DEFAULT, xyz);
    h5::Handle scalar(H5Screate(H5S_SCALAR));
    const std::int64_t inc = 50;
    h5::Handle st(H5Dcreate2(pos.get(), "step", H5T_STD_I64LE, scalar.get(), H5P_DEFAULT,
                             H5P_DEFAULT, H5P_DEFAULT));
    H5Dwrite(st.get(), H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, &inc);
    h5::writeAttribute(st.get(), "offset", std::int64_t{1000}, "t");
    const double dtime = 0.5;
    h5::Handle tm(H5Dcreate2(pos.get(), "time", H5T_IEEE_F64LE, scalar.get(), H5P_DEFAULT,
                             H5P_DEFAULT, H5P_DEFAULT));
    H5Dwrite(tm.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, &dtime);
    if (with_box) {
      h5::Handle box = h5::createGroup(f, "particles/atoms/box", "t");
      const int dim = 3;
      h5::writeAttribute(box.get(), "dimension", H5T_STD_I32LE, H5T_NATIVE_INT, &dim, {}, "t");
      h5::writeFixedStringArrayAttribute(box.get(), "boundary",
                                         {"periodic", "periodic", "periodic"}, "t");
      const double e[3] = {L, L, L};
      const hsize_t d3[1] = {3};
      h5::Handle s3(H5Screate_simple(1, d3, nullptr));
      h5::Handle ed(H5Dcreate2(box.get(), "edges", H5T_IEEE_F64LE, s3.get(), H5P_DEFAULT,
                               H5P_DEFAULT, H5P_DEFAULT));
      H5Dwrite(ed.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, e);
    }
    if (bad_velocity) {
      h5::Handle vel = h5::createGroup(f, "particles/atoms/velocity", "t");
      const hsize_t vd[3] = {frames, n + 1, 3};
      h5::Handle vs(H5Screate_simple(3, vd, nullptr));
      h5::Handle vv(H5Dcreate2(vel.get(), "value", H5T_IEEE_F64LE, vs.get(), H5P_DEFAULT,
                               H5P_DEFAULT, H5P_DEFAULT));
      const std::int64_t steps[frames] = {1000, 1050};
      const hsize_t fd[1] = {frames};
      h5::Handle ss(H5Screate_simple(1, fd, nullptr));
      h5::Handle vst(H5Dcreate2(vel.get(), "step", H5T_STD_I64LE, ss.get(), H5P_DEFAULT,
                                H5P_DEFAULT, H5P_DEFAULT));
      H5Dwrite(vst.get(), H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, steps);
    }
  };

  build(true, false);
  {
    H5mdReader r(path);
    r.keepWrapCrossings(true);  // no image element: the crossings of the unwrapped positions
    CHECK(r.particleGroup() == "atoms");
    REQUIRE(r.size() == n);
    REQUIRE(r.frames() == frames);
    CHECK_FALSE(r.hasVelocity());
    CHECK_FALSE(r.hasImage());
    CHECK(r.creator().first == "other-engine");
    const Frame f = engineFrame(r.readFrame(1));
    CHECK(f.step == 1050);
    CHECK(f.time == 0.5);
    CHECK(f.box == L);
    CHECK(f.vx.empty());
    CHECK(f.charge == std::vector<double>(n, 0.0));
    // unwrapped positions come back wrapped, the crossings as image counts
    CHECK(f.x[1] == 0.25);
    CHECK(f.ix[1] == 1);
    CHECK(f.y[1] == 3.5);
    CHECK(f.iy[1] == -1);
    CHECK(f.z[2] == 2.0);
    CHECK(f.iz[2] == -1);
    CHECK(engineFrame(r.readFrame(0)).z[2] == 1.0);
    CHECK(engineFrame(r.readFrame(0)).iz[2] == 2);
  }
  build(false, false);
  CHECK_THROWS_WITH(H5mdReader(path),
                    Catch::Contains(path) && Catch::Contains("particles/atoms/box"));
  build(true, true);
  CHECK_THROWS_WITH(H5mdReader(path), Catch::Contains(path) &&
                                          Catch::Contains("particles/atoms/velocity/value") &&
                                          Catch::Contains("shape [2,4,3]"));
  std::remove(path.c_str());
}

TEST_CASE("A killed run leaves a readable trajectory", "[md][io]") {
  // The child writes two frames and dies by SIGKILL without closing the file: every flushed
  // frame must be readable (HDF5's default superblock carries no "open for writing" flag that
  // would lock the file after a crash).
  const std::string path = tempPath("killed.h5");
  removeTrajectory(path);
  const Frame f0 = makeFrame(10, 0, 11), f1 = makeFrame(10, 100, 12);
  const pid_t pid = ::fork();
  REQUIRE(pid >= 0);
  if (pid == 0) {
    try {
      H5mdWriter w(path, 10, PARAMS, TOML, false);
      w.writeObservables(0, 0.0, {{"e", 1.0}});
      w.writeFrame(f0);
      w.writeObservables(50, 0.05, {{"e", 2.0}});
      w.writeFrame(f1);
      w.writeObservables(60, 0.06, {{"e", 3.0}});  // buffered, lost with the process
      std::raise(SIGKILL);
    } catch (...) {
    }
    ::_exit(3);
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  REQUIRE(WIFSIGNALED(status));
  H5mdReader r(path);
  REQUIRE(r.frames() == 2);
  CHECK(sameFrame(engineFrame(r.readFrame(0)), f0));
  CHECK(sameFrame(engineFrame(r.readFrame(1)), f1));
  CHECK(r.readObservable("e").value == std::vector<double>{1.0, 2.0});
  CHECK(slurp(H5mdWriter::xdmfPathFor(path)).find("<Grid Name=\"frame1\"") != std::string::npos);
  removeTrajectory(path);
}

TEST_CASE("A partially written last frame is not counted", "[md][io]") {
  // A run killed between writing a frame's values and its step/time leaves longer value
  // datasets; the reader counts complete frames only.
  const std::string path = tempPath("partial.h5");
  const auto written = writeTrajectory(path, 6, 2);
  {
    h5::Handle file(H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT));
    h5::Handle d(H5Dopen2(file.get(), "/particles/all/position/value", H5P_DEFAULT));
    const hsize_t dims[3] = {3, 6, 3};
    REQUIRE(H5Dset_extent(d.get(), dims) >= 0);
  }
  H5mdReader r(path);
  CHECK(r.frames() == 2);
  CHECK(sameFrame(engineFrame(r.readFrame(1)), written[1]));
  removeTrajectory(path);
}

TEST_CASE("Reopening for a restart drops what followed the checkpoint", "[md][io]") {
  const std::string path = tempPath("restart.h5");
  const auto written = writeTrajectory(path, 8, 4);  // frames at steps 0..300, observables every 25
  {
    H5mdWriter w = H5mdWriter::reopen(path, 8, /*restart_step=*/150);
    CHECK(w.frames() == 2);                                            // steps 0 and 100 kept
    CHECK(w.observableSamples() == 7);                                 // steps 0..150
    CHECK_THROWS_AS(w.writeFrame(written[1]), std::invalid_argument);  // step 100 already there
    w.writeObservables(175, 0.175, {{"temperature", 0.5}, {"kinetic_energy", 2.0}});
    w.writeFrame(written[2]);
    w.writeFrame(written[3]);
  }
  {
    H5mdReader r(path);
    REQUIRE(r.frames() == 4);
    for (std::size_t k = 0; k < 4; ++k) CHECK(sameFrame(engineFrame(r.readFrame(k)), written[k]));
    const auto t = r.readObservable("temperature");
    REQUIRE(t.step.size() == 8);
    CHECK(t.step[6] == 150);
    CHECK(t.step[7] == 175);
    CHECK(t.value[7] == 0.5);
    CHECK(r.readObservable("kinetic_energy").value[7] == 2.0);
  }
  CHECK_THROWS_WITH(H5mdWriter::reopen(path, 9, 0), Catch::Contains("expected N = 9"));
  CHECK_THROWS_WITH(H5mdWriter::reopen(path, 8, 0, false), Catch::Contains("write_velocities"));
  removeTrajectory(path);
}

TEST_CASE("A restart by a newer granagg may add or omit observables", "[md][io]") {
  // A run started by a granagg without an observable (here "dt") is continued by one that writes
  // it: the series is added with NaN before the restart, and a series the new program no longer
  // writes gets NaN after it. The other series and the frames are untouched.
  const std::string path = tempPath("restart_obs.h5");
  writeTrajectory(path, 8, 4);  // temperature and kinetic_energy every 25 steps, to step 300
  {
    H5mdWriter w = H5mdWriter::reopen(path, 8, /*restart_step=*/150);
    w.writeObservables(175, 0.175, {{"temperature", 0.5}, {"dt", 1e-3}});
    w.writeObservables(200, 0.2, {{"dt", 2e-3}, {"temperature", 0.25}, {"kinetic_energy", 4.0}});
    CHECK_THROWS_WITH(w.writeObservables(225, 0.225, {{"dt", 1.0}, {"dt", 2.0}}),
                      Catch::Contains("'dt' given twice"));
  }
  H5mdReader r(path);
  const auto dt = r.readObservable("dt");
  REQUIRE(dt.step.size() == 9);  // steps 0..150 kept, then 175 and 200
  for (std::size_t k = 0; k < 7; ++k) CHECK(std::isnan(dt.value[k]));
  CHECK(dt.value[7] == 1e-3);
  CHECK(dt.value[8] == 2e-3);
  CHECK(dt.step[8] == 200);
  const auto t = r.readObservable("temperature");
  CHECK(t.value[6] == 1.0 / (1 + 150));  // before the restart: as written
  CHECK(t.value[7] == 0.5);
  CHECK(t.value[8] == 0.25);
  const auto ke = r.readObservable("kinetic_energy");
  CHECK(std::isnan(ke.value[7]));
  CHECK(ke.value[8] == 4.0);
  removeTrajectory(path);
}

TEST_CASE("XDMF sidecar describes every frame as a Polyvertex point cloud", "[md][io]") {
  const std::string path = tempPath("xdmf.h5");
  writeTrajectory(path, 7, 3);
  const std::string xdmf = H5mdWriter::xdmfPathFor(path);
  CHECK(xdmf == path.substr(0, path.size() - 3) + ".xdmf");
  CHECK(H5mdWriter::xdmfPathFor("run/traj") == "run/traj.xdmf");
  const std::string text = slurp(xdmf);
  REQUIRE_FALSE(text.empty());
  std::size_t grids = 0;
  for (std::size_t p = text.find("<Grid Name=\"frame"); p != std::string::npos;
       p = text.find("<Grid Name=\"frame", p + 1))
    ++grids;
  CHECK(grids == 3);
  CHECK(text.find("TopologyType=\"Polyvertex\" NumberOfElements=\"7\"") != std::string::npos);
  const std::string base = path.substr(path.find_last_of('/') + 1);
  CHECK(text.find(base + ":/particles/all/position/value") != std::string::npos);
  CHECK(text.find("Dimensions=\"3 7 3\"") != std::string::npos);  // full dataset extent
  CHECK(text.find("CollectionType=\"Temporal\"") != std::string::npos);
  removeTrajectory(path);
}

TEST_CASE("scripts/check_h5md.py accepts our trajectories and rejects broken ones", "[md][io]") {
  if (std::system("/usr/bin/python3 -c 'import h5py, numpy' >/dev/null 2>&1") != 0) {
    WARN("/usr/bin/python3 with h5py not available: check_h5md.py not exercised");
    return;
  }
  // GRANAGG_TEST_DATA is <source>/tests/data (which need not exist): strip it to the source root
  std::string root = GRANAGG_TEST_DATA;
  root = root.substr(0, root.rfind("/tests/data"));
  const std::string script = root + "/scripts/check_h5md.py";
  const std::string path = tempPath("check.h5");
  writeTrajectory(path, 9, 3);
  const std::string out = tempPath("check.txt");
  const int rc =
      std::system(("/usr/bin/python3 " + script + " " + path + " > " + out + " 2>&1").c_str());
  const std::string report = slurp(out);
  INFO(report);
  CHECK(rc == 0);
  CHECK(report.find("N = 9") != std::string::npos);
  CHECK(report.find("frames = 3") != std::string::npos);

  // the XDMF sidecar in ParaView's own XDMF Reader, where ParaView's Python module exists
  if (std::system("/usr/bin/python3 -c 'import paraview.simple' >/dev/null 2>&1") == 0) {
    const int rc_pv = std::system(
        ("/usr/bin/python3 " + script + " --paraview " + path + " > " + out + " 2>&1").c_str());
    const std::string pv = slurp(out);
    INFO(pv);
    CHECK(rc_pv == 0);
    CHECK(pv.find("ParaView XDMF Reader: 3 time steps, 9 points, last frame exact") !=
          std::string::npos);
  } else {
    WARN("ParaView's Python module not available: XDMF sidecar not loaded in ParaView");
  }

  // break it: remove the boundary attribute
  {
    h5::Handle file(H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT));
    h5::Handle box(H5Gopen2(file.get(), "/particles/all/box", H5P_DEFAULT));
    REQUIRE(H5Adelete(box.get(), "boundary") >= 0);
  }
  const int rc2 =
      std::system(("/usr/bin/python3 " + script + " " + path + " > " + out + " 2>&1").c_str());
  INFO(slurp(out));
  CHECK(rc2 != 0);
  CHECK(slurp(out).find("boundary") != std::string::npos);
  std::remove(out.c_str());
  removeTrajectory(path);
}
