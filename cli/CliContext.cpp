#include "cli/CliContext.h"

#include <cstdlib>
#include <filesystem>
#include <set>
#include <stdexcept>
#include <system_error>

namespace granagg::cli {
namespace fs = std::filesystem;

std::vector<std::string> dataDirs() {
  std::vector<std::string> dirs;
  if (const char* env = std::getenv("GRANAGG_DATA")) dirs.emplace_back(env);
  dirs.emplace_back(GRANAGG_DATA_DIR);
  return dirs;
}

std::string findPreset(const std::string& sub, const std::string& name, const std::string& what) {
  std::set<std::string> available;
  for (const auto& d : dataDirs()) {
    const fs::path p = fs::path(d) / sub / (name + ".toml");
    if (fs::is_regular_file(p)) return p.string();
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(fs::path(d) / sub, ec))
      if (e.path().extension() == ".toml") available.insert(e.path().stem().string());
  }
  std::string list;
  for (const auto& a : available) list += (list.empty() ? "" : ", ") + a;
  throw std::invalid_argument(what + ": no preset named '" + name + "' in " + dataDirs().back() +
                              "/" + sub + " (available: " + list + ")");
}

const common::PaperValues& paperValues() {
  static const common::PaperValues values = [] {
    for (const auto& d : dataDirs()) {
      const fs::path p = fs::path(d) / "reference" / "paper.json";
      if (fs::is_regular_file(p)) return common::readPaperValues(p.string());
    }
    throw std::runtime_error("no reference/paper.json in " + dataDirs().back());
  }();
  return values;
}

}  // namespace granagg::cli
