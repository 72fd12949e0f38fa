// common::FolderLock: one writer per output folder, its holder named, stale locks reported.
#include <catch2/catch.hpp>

#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <stdexcept>
#include <string>

#include "common/FolderLock.h"
#include "TestUtil.h"

using granagg::common::FOLDER_LOCK_FILE;
using granagg::common::FolderLock;
namespace fs = std::filesystem;

namespace {

std::string hostName() {
  char b[256] = {};
  ::gethostname(b, sizeof b - 1);
  return b;
}

/// A pid that ran and ended (reaped): no process has it now, short of reuse in the meantime.
long deadPid() {
  const pid_t pid = ::fork();
  if (pid == 0) ::_exit(0);
  int st = 0;
  ::waitpid(pid, &st, 0);
  return static_cast<long>(pid);
}

void writeLockFile(const fs::path& dir, long pid, const std::string& host) {
  fs::create_directories(dir);
  std::ofstream(dir / FOLDER_LOCK_FILE) << "pid = " << pid << "\nhost = " << host
                                        << "\ncommand = granagg md --out x\nsince = "
                                           "2026-01-01T00:00:00Z\n";
}

std::string messageOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("a locked folder refuses a second lock, naming the holder, until released",
          "[folderlock]") {
  const fs::path dir = granagg::test::tempDir("lock-basic") / "out";
  FolderLock first = FolderLock::acquire(dir, "granagg md --out out", false);
  CHECK(first.createdFolder());
  CHECK(fs::exists(dir / FOLDER_LOCK_FILE));
  // flock conflicts between open file descriptions, even within one process
  const std::string msg =
      messageOf([&] { FolderLock::acquire(dir, "granagg md --force --out out", true); });
  CHECK_THAT(msg, Catch::Contains("is in use by pid " + std::to_string(::getpid())) &&
                      Catch::Contains("granagg md --out out") &&
                      Catch::Contains("kill -TERM " + std::to_string(::getpid())));
  const auto holder = FolderLock::liveHolder(dir);
  REQUIRE(holder);
  CHECK(holder->pid == ::getpid());
  CHECK(holder->host == hostName());
  CHECK_THROWS_AS(FolderLock::checkAvailable(dir, true), std::invalid_argument);
  first.release();
  CHECK_FALSE(fs::exists(dir / FOLDER_LOCK_FILE));  // released: the folder is as it was
  CHECK_FALSE(FolderLock::liveHolder(dir));
  FolderLock again = FolderLock::acquire(dir, "granagg md --out out", false);
  CHECK_FALSE(again.createdFolder());
  CHECK(again.clearedStale().empty());
  again.release();
  fs::remove_all(dir.parent_path());
}

TEST_CASE("a stale lock of a dead pid is reported, and cleared only when asked", "[folderlock]") {
  const fs::path dir = granagg::test::tempDir("lock-stale") / "out";
  const long pid = deadPid();
  writeLockFile(dir, pid, hostName());
  const auto stale = FolderLock::staleHolder(dir);
  REQUIRE(stale);
  CHECK(stale->deadHere());
  CHECK_FALSE(FolderLock::liveHolder(dir));
  const std::string msg = messageOf([&] { FolderLock::acquire(dir, "granagg md", false); });
  CHECK_THAT(msg, Catch::Contains("stale lock") &&
                      Catch::Contains("pid " + std::to_string(pid)) &&
                      Catch::Contains("no longer runs") && Catch::Contains("--force"));
  CHECK(fs::exists(dir / FOLDER_LOCK_FILE));  // refused: the file is left as it was found
  CHECK_THAT(messageOf([&] { FolderLock::checkAvailable(dir, false); }),
             Catch::Contains("stale lock"));
  CHECK_NOTHROW(FolderLock::checkAvailable(dir, true));
  FolderLock taken = FolderLock::acquire(dir, "granagg md --force", true);
  CHECK_THAT(taken.clearedStale(), Catch::Contains("pid " + std::to_string(pid)));
  const auto holder = FolderLock::liveHolder(dir);
  REQUIRE(holder);
  CHECK(holder->pid == ::getpid());
  CHECK(holder->command == "granagg md --force");
  taken.release();
  fs::remove_all(dir.parent_path());
}

TEST_CASE("another host's lock cannot be checked here and needs --force", "[folderlock]") {
  const fs::path dir = granagg::test::tempDir("lock-host") / "out";
  writeLockFile(dir, 4242, "some-other-node");
  const auto stale = FolderLock::staleHolder(dir);
  REQUIRE(stale);
  CHECK_FALSE(stale->deadHere());
  CHECK_THAT(messageOf([&] { FolderLock::acquire(dir, "granagg md", false); }),
             Catch::Contains("host some-other-node") &&
                 Catch::Contains("cannot be checked from host"));
  CHECK_NOTHROW(FolderLock::acquire(dir, "granagg md", true));
  fs::remove_all(dir.parent_path());
}

TEST_CASE("a tree check finds a live lock in a subfolder but not the caller's own",
          "[folderlock]") {
  const fs::path root = granagg::test::tempDir("lock-tree");
  FolderLock own = FolderLock::acquire(root, "granagg pair", false);
  CHECK_NOTHROW(FolderLock::checkTreeAvailable(root));
  FolderLock run = FolderLock::acquire(root / "runs" / "K0" / "run0", "granagg md", false);
  CHECK_THAT(messageOf([&] { FolderLock::checkTreeAvailable(root); }),
             Catch::Contains("run0") && Catch::Contains("is in use by pid"));
  run.release();
  CHECK_NOTHROW(FolderLock::checkTreeAvailable(root));
  own.release();
  fs::remove_all(root);
}

TEST_CASE("a file where a folder is asked for is refused by name", "[folderlock]") {
  const fs::path root = granagg::test::tempDir("lock-file");
  std::ofstream(root / "plain") << "x";
  CHECK_THAT(messageOf([&] { FolderLock::acquire(root / "plain", "granagg md", false, "--out"); }),
             Catch::Contains("--out '") && Catch::Contains("is a file, not a folder"));
  fs::remove_all(root);
}
