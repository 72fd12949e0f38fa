/// \file OutputPath.cpp
/// Output checks by probe (OutputPath.h).
#include "common/OutputPath.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <system_error>

namespace granagg::common {
namespace fs = std::filesystem;

namespace {

/// A name no other process uses for its own probe.
fs::path probeName(const fs::path& dir) {
  return dir / (".granagg-probe-" + std::to_string(::getpid()));
}

/// errno text of creating (and removing) a probe file in `dir`, or "" when it can be done.
std::string fileProbe(const fs::path& dir) {
  const fs::path p = probeName(dir);
  const int fd = ::open(p.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd < 0) return std::strerror(errno);
  ::close(fd);
  ::unlink(p.c_str());
  return "";
}

/// errno text of creating (and removing) a probe folder in `dir`, or "" when it can be done.
std::string folderProbe(const fs::path& dir) {
  const fs::path p = probeName(dir);
  if (::mkdir(p.c_str(), 0755) != 0) return std::strerror(errno);
  ::rmdir(p.c_str());
  return "";
}

/// `dir` itself when it exists, else the nearest existing path above it ("." for a relative path
/// whose first part is missing).
fs::path nearestExisting(const fs::path& dir) {
  std::error_code ec;
  fs::path p = dir;
  while (!p.empty() && !fs::exists(p, ec)) p = p.parent_path();
  return p.empty() ? fs::path(".") : p;
}

std::string quoted(const std::string& option, const fs::path& p) {
  return option + " '" + p.string() + "'";
}

}  // namespace

void checkOutputFile(const fs::path& path, const std::string& option) {
  std::error_code ec;
  if (fs::is_directory(path, ec))
    throw std::invalid_argument(quoted(option, path) + " is a folder; give a file name");
  const fs::path dir = path.has_parent_path() ? path.parent_path() : fs::path(".");
  if (!fs::exists(dir, ec))
    throw std::invalid_argument(quoted(option, path) + ": the folder '" + dir.string() +
                                "' does not exist");
  if (!fs::is_directory(dir, ec))
    throw std::invalid_argument(quoted(option, path) + ": '" + dir.string() +
                                "' is not a folder");
  const std::string why = fileProbe(dir);
  if (!why.empty())
    throw std::invalid_argument(quoted(option, path) + ": cannot create a file in '" +
                                dir.string() + "' (" + why + ")");
}

void checkOutputFolder(const fs::path& folder, const std::string& option) {
  std::error_code ec;
  if (fs::exists(folder, ec) && !fs::is_directory(folder, ec))
    throw std::invalid_argument(quoted(option, folder) + " is a file, not a folder; give a folder");
  if (fs::is_directory(folder, ec)) {
    const std::string why = fileProbe(folder);
    if (!why.empty())
      throw std::invalid_argument(quoted(option, folder) + ": cannot write in it (" + why + ")");
    return;
  }
  const fs::path above = nearestExisting(folder.parent_path());
  std::string why = fs::is_directory(above, ec) ? folderProbe(above) : std::strerror(ENOTDIR);
  if (!why.empty())
    throw std::invalid_argument(quoted(option, folder) + ": cannot create the folder (" + why +
                                ")");
}

}  // namespace granagg::common
