/// The journaled HDF5 driver (common/H5Journal.h). A kill between a flush's writes and the commit
/// is reproduced exactly by copying the file and its journal at that moment: the copy is what
/// the killed process leaves. The reference is the file's bytes at the last commit, so a rollback
/// must give them back byte for byte. The crash trials (tests/faults/crash_trials.py) kill real
/// runs at random writes.
#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "common/H5Journal.h"
#include "common/Hdf5.h"

#include "TestUtil.h"

using granagg::test::tempPath;
using namespace granagg::common;
namespace fs = std::filesystem;

namespace {

std::string bytesOf(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

/// A 1D extendible dataset "x" of doubles, in chunks of 4.
hid_t createSeries(hid_t file) {
  const hsize_t dims[1] = {0}, max[1] = {H5S_UNLIMITED}, chunk[1] = {4};
  h5::Handle space(H5Screate_simple(1, dims, max));
  h5::Handle dcpl(H5Pcreate(H5P_DATASET_CREATE));
  H5Pset_chunk(dcpl.get(), 1, chunk);
  return H5Dcreate2(file, "x", H5T_NATIVE_DOUBLE, space.get(), H5P_DEFAULT, dcpl.get(),
                    H5P_DEFAULT);
}

void append(hid_t dset, double first, int n) {
  h5::Handle space(H5Dget_space(dset));
  hsize_t size[1];
  H5Sget_simple_extent_dims(space.get(), size, nullptr);
  const hsize_t grown[1] = {size[0] + static_cast<hsize_t>(n)};
  REQUIRE(H5Dset_extent(dset, grown) >= 0);
  h5::Handle fspace(H5Dget_space(dset));
  const hsize_t start[1] = {size[0]}, count[1] = {static_cast<hsize_t>(n)};
  H5Sselect_hyperslab(fspace.get(), H5S_SELECT_SET, start, nullptr, count, nullptr);
  h5::Handle mspace(H5Screate_simple(1, count, nullptr));
  std::vector<double> v(n);
  for (int i = 0; i < n; ++i) v[i] = first + i;
  REQUIRE(H5Dwrite(dset, H5T_NATIVE_DOUBLE, mspace.get(), fspace.get(), H5P_DEFAULT, v.data()) >=
          0);
}

std::vector<double> readSeries(const std::string& path) {
  h5::Handle f(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT));
  REQUIRE(f.valid());
  h5::Handle d(H5Dopen2(f.get(), "x", H5P_DEFAULT));
  h5::Handle space(H5Dget_space(d.get()));
  hsize_t n[1];
  H5Sget_simple_extent_dims(space.get(), n, nullptr);
  std::vector<double> v(n[0]);
  if (n[0] > 0) H5Dread(d.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data());
  return v;
}

}  // namespace

TEST_CASE("h5journal: a flushed but uncommitted write rolls back to the commit, byte for byte") {
  h5::silenceErrors();
  const std::string path = tempPath("journal.h5"), copy = tempPath("journal-killed.h5");
  const std::string committed_copy = tempPath("journal-committed.h5");
  h5::Handle fapl(h5journal::fileAccess());
  h5::Handle file(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl.get()));
  REQUIRE(file.valid());
  h5::Handle x(createSeries(file.get()));
  for (int frame = 0; frame < 5; ++frame) {
    append(x.get(), 10.0 * frame, 7);
    REQUIRE(H5Fflush(file.get(), H5F_SCOPE_GLOBAL) >= 0);
    h5journal::commit(file.get());
  }
  CHECK_FALSE(h5journal::pending(path));
  const std::string at_commit = bytesOf(path);
  fs::copy_file(path, committed_copy, fs::copy_options::overwrite_existing);

  // the next "frame": written and flushed (metadata overwritten in place), never committed
  append(x.get(), 50.0, 7);
  REQUIRE(H5Fflush(file.get(), H5F_SCOPE_GLOBAL) >= 0);
  REQUIRE(fs::exists(h5journal::journalPathFor(path)));
  fs::copy_file(path, copy, fs::copy_options::overwrite_existing);
  fs::copy_file(h5journal::journalPathFor(path), h5journal::journalPathFor(copy),
                fs::copy_options::overwrite_existing);
  CHECK(bytesOf(copy) != at_commit);  // the frame changed the file in place, not only at its end
  CHECK(h5journal::pending(copy));

  const h5journal::Recovery r = h5journal::recover(copy);
  CHECK(r.repaired);
  CHECK(r.entries >= 1);
  CHECK(r.size_after == at_commit.size());
  CHECK(bytesOf(copy) == at_commit);
  CHECK_FALSE(fs::exists(h5journal::journalPathFor(copy)));
  CHECK(readSeries(copy).size() == 35u);
  CHECK(r.summary(copy).find("rolled back the unfinished write of '" + copy + "'") == 0);
  // a second recovery has nothing to do
  CHECK_FALSE(h5journal::recover(copy).repaired);

  // the writer goes on and closes cleanly: no journal, every frame readable
  x.reset();
  REQUIRE(file.reset());
  CHECK_FALSE(fs::exists(h5journal::journalPathFor(path)));
  const std::vector<double> all = readSeries(path);
  REQUIRE(all.size() == 42u);
  CHECK(all[35] == 50.0);
  CHECK(all[41] == 56.0);
  for (const auto& p : {path, copy, committed_copy}) std::remove(p.c_str());
}

TEST_CASE("h5journal: a live writer's file is neither recovered nor opened twice") {
  h5::silenceErrors();
  const std::string path = tempPath("journal-live.h5");
  h5::Handle fapl(h5journal::fileAccess());
  h5::Handle file(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl.get()));
  REQUIRE(file.valid());
  h5::Handle x(createSeries(file.get()));
  append(x.get(), 0.0, 3);
  REQUIRE(H5Fflush(file.get(), H5F_SCOPE_GLOBAL) >= 0);
  h5journal::commit(file.get());
  append(x.get(), 3.0, 3);
  REQUIRE(H5Fflush(file.get(), H5F_SCOPE_GLOBAL) >= 0);  // a transaction in progress
  REQUIRE(h5journal::pending(path));
  // the flock is per open file: this process's second open conflicts as another's would
  CHECK_THROWS_WITH(h5journal::recover(path), Catch::Contains("open for writing in a running"));
  h5::Handle fapl2(h5journal::fileAccess());
  CHECK_FALSE(h5::Handle(H5Fopen(path.c_str(), H5F_ACC_RDWR, fapl2.get())).valid());
  h5::lastError();
  x.reset();
  REQUIRE(file.reset());
  CHECK_FALSE(h5journal::pending(path));
  CHECK(readSeries(path).size() == 6u);
  std::remove(path.c_str());
}

TEST_CASE("h5journal: a pending journal blocks a writer's open until recovered") {
  h5::silenceErrors();
  const std::string path = tempPath("journal-pending.h5"), copy = tempPath("journal-pend2.h5");
  {
    h5::Handle fapl(h5journal::fileAccess());
    h5::Handle file(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl.get()));
    h5::Handle x(createSeries(file.get()));
    append(x.get(), 0.0, 5);
    REQUIRE(H5Fflush(file.get(), H5F_SCOPE_GLOBAL) >= 0);
    h5journal::commit(file.get());
    append(x.get(), 5.0, 5);
    REQUIRE(H5Fflush(file.get(), H5F_SCOPE_GLOBAL) >= 0);
    fs::copy_file(path, copy, fs::copy_options::overwrite_existing);
    fs::copy_file(h5journal::journalPathFor(path), h5journal::journalPathFor(copy),
                  fs::copy_options::overwrite_existing);
  }
  h5::Handle fapl(h5journal::fileAccess());
  CHECK_FALSE(h5::Handle(H5Fopen(copy.c_str(), H5F_ACC_RDWR, fapl.get())).valid());
  CHECK_THAT(h5::lastError(), Catch::Contains("unfinished write"));
  REQUIRE(h5journal::recover(copy).repaired);
  h5::Handle reopened(H5Fopen(copy.c_str(), H5F_ACC_RDWR, fapl.get()));
  CHECK(reopened.valid());
  reopened.reset();
  CHECK(readSeries(copy).size() == 5u);
  // a journal cut inside its header protects nothing yet: recovery just removes it
  {
    std::ofstream j(h5journal::journalPathFor(copy), std::ios::binary);
    j << "GRNGJ";
  }
  CHECK_FALSE(h5journal::pending(copy));
  CHECK_FALSE(h5journal::recover(copy).repaired);
  CHECK_FALSE(fs::exists(h5journal::journalPathFor(copy)));
  for (const auto& p : {path, copy}) std::remove(p.c_str());
}
