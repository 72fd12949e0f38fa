// The repository stands alone: no source, document or data file cites a specification or a paper
// file that a clone does not contain, docs/model.md (the model's specification) exists with
// numbered sections, and every "docs/model.md section N" (or "model.md §N") citation names one of
// them. Scans the source tree (GRANAGG_SOURCE_DIR) without git, skipping build and results folders.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

const fs::path ROOT = GRANAGG_SOURCE_DIR;

std::string readAll(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

bool startsWith(const std::string& s, const std::string& prefix) {
  return s.compare(0, prefix.size(), prefix) == 0;
}

/// Folders that are not part of the repository's text: git's, build trees and outputs (the root's
/// .gitignore), caches.
bool skipDirectory(const fs::path& dir) {
  const std::string name = dir.filename().string();
  if (name == "__pycache__") return true;
  if (startsWith(name, ".") && name != ".ci") return true;
  if (dir.parent_path() == ROOT)
    for (const char* p : {"build", "results", "out", "md-out"})
      if (startsWith(name, p)) return true;
  return false;
}

bool isText(const fs::path& file) {
  static const std::set<std::string> EXT = {".cpp", ".h",    ".hpp",  ".cu",    ".c",
                                            ".md",  ".txt",  ".in",   ".cmake", ".py",
                                            ".sh",  ".toml", ".json", ".yml",   ".yaml"};
  const std::string ext = file.extension().string();
  if (EXT.count(ext)) return true;
  // extension-less scripts (.ci/run) and the root's dot files (.clang-format, .gitignore)
  return ext.empty() || file.parent_path() == ROOT;
}

/// Every text file of the source tree (sorted, so that failures list in a stable order).
std::vector<fs::path> textFiles() {
  std::vector<fs::path> out;
  for (auto it = fs::recursive_directory_iterator(ROOT); it != fs::recursive_directory_iterator();
       ++it) {
    if (it->is_directory()) {
      if (skipDirectory(it->path())) it.disable_recursion_pending();
      continue;
    }
    if (!it->is_regular_file() || it->file_size() > (2u << 20) || !isText(it->path())) continue;
    out.push_back(it->path());
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::string inTree(const fs::path& p) { return fs::relative(p, ROOT).generic_string(); }

int lineOf(const std::string& text, std::size_t pos) {
  return 1 + static_cast<int>(std::count(text.begin(), text.begin() + pos, '\n'));
}

/// The text after a match with line breaks, their indentation and comment markers (///, //, #, *)
/// turned into one space, so that a citation wrapped over two comment lines reads as one.
std::string joinedWindow(const std::string& text, std::size_t pos, std::size_t length) {
  std::string w;
  for (std::size_t i = pos; i < text.size() && w.size() < length; ++i) {
    if (text[i] != '\n') {
      w += text[i];
      continue;
    }
    std::size_t j = i + 1;
    while (j < text.size() && (text[j] == ' ' || text[j] == '\t')) ++j;
    while (j < text.size() && (text[j] == '/' || text[j] == '#' || text[j] == '*')) ++j;
    while (j < text.size() && text[j] == ' ') ++j;
    if (!w.empty() && w.back() != ' ') w += ' ';
    i = j - 1;
  }
  return w;
}

/// Section numbers of docs/model.md: its "## N. Title" headings.
std::set<int> modelSections(const std::string& text) {
  std::set<int> out;
  std::istringstream in(text);
  std::string line;
  const std::regex heading(R"(^## (\d+)\. \S.*)");
  std::smatch m;
  while (std::getline(in, line))
    if (std::regex_match(line, m, heading)) out.insert(std::stoi(m[1].str()));
  return out;
}

}  // namespace

TEST_CASE("no file cites a specification or paper file outside the repository",
          "[common][repository]") {
  // Written in pieces so that this file does not match itself.
  const std::vector<std::string> outside = {std::string("design") + ".md",
                                            std::string("shared") + "/reference",
                                            std::string("000_2f9cb") + "220"};
  const auto files = textFiles();
  REQUIRE(files.size() > 100);  // the walk found the tree (about 400 text files)
  std::vector<std::string> hits;
  for (const auto& f : files) {
    const std::string text = readAll(f);
    for (const auto& needle : outside)
      for (std::size_t pos = text.find(needle); pos != std::string::npos;
           pos = text.find(needle, pos + 1))
        hits.push_back(inTree(f) + ":" + std::to_string(lineOf(text, pos)) + ": cites " + needle);
  }
  for (const auto& h : hits) UNSCOPED_INFO(h);
  CHECK(hits.empty());
}

TEST_CASE("every docs/model.md section cited exists", "[common][repository]") {
  const fs::path model = ROOT / "docs" / "model.md";
  REQUIRE(fs::is_regular_file(model));
  const std::set<int> sections = modelSections(readAll(model));
  REQUIRE(sections.size() >= 10);
  // numbered 1..n without gaps, so that a citation's number is a heading's number
  CHECK(*sections.begin() == 1);
  CHECK(*sections.rbegin() == static_cast<int>(sections.size()));

  // "model.md section 7", "model.md sections 1, 11 and 12", "model.md §3-§7",
  // "model.md §9, §12"
  const std::regex citation(R"(^model\.md,?\s+(?:sections?\s+|§ ?))"
                            R"((\d+(?:\s*(?:,\s*|and\s+|-|–)\s*(?:and\s+)?(?:§)?\d+)*))");
  const std::regex number(R"(\d+)");
  const std::string key = "model.md";
  std::size_t citations = 0;
  std::vector<std::string> bad;
  for (const auto& f : textFiles()) {
    const std::string text = readAll(f);
    for (std::size_t pos = text.find(key); pos != std::string::npos;
         pos = text.find(key, pos + 1)) {
      const std::string window = joinedWindow(text, pos, 120);
      std::smatch m;
      if (!std::regex_search(window, m, citation)) continue;
      const std::string list = m[1].str();
      for (auto it = std::sregex_iterator(list.begin(), list.end(), number);
           it != std::sregex_iterator(); ++it) {
        ++citations;
        const int n = std::stoi(it->str());
        if (!sections.count(n))
          bad.push_back(inTree(f) + ":" + std::to_string(lineOf(text, pos)) +
                        ": docs/model.md has no section " + std::to_string(n));
      }
    }
  }
  for (const auto& b : bad) UNSCOPED_INFO(b);
  CHECK(bad.empty());
  CHECK(citations > 50);  // the code and docs do cite it (about 150 references)
}

TEST_CASE("md, analysis and meanfield never include each other, nor study or cli",
          "[common][repository]") {
  // the one rule of the layout (docs/ARCHITECTURE.md): what passes between them is files, and
  // where md and analysis meet in one process (study/insitu) it is above both
  const std::vector<std::string> modules = {"md", "analysis", "meanfield"};
  const std::regex include("#include\\s+\"([a-z_]+)/");
  std::vector<std::string> bad;
  for (const std::string& m : modules)
    for (auto it = fs::recursive_directory_iterator(ROOT / m);
         it != fs::recursive_directory_iterator(); ++it) {
      if (!it->is_regular_file()) continue;
      const std::string text = readAll(it->path());
      for (auto i = std::sregex_iterator(text.begin(), text.end(), include);
           i != std::sregex_iterator(); ++i) {
        const std::string target = (*i)[1].str();
        if (target != m && target != "common")
          bad.push_back(fs::relative(it->path(), ROOT).string() + " includes " + target + "/");
      }
    }
  for (const auto& b : bad) UNSCOPED_INFO(b);
  CHECK(bad.empty());
}
