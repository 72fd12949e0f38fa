#include "common/Csv.h"

#include <sys/stat.h>
#include <cerrno>
#include <cstring>
#include <charconv>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "common/OutputPath.h"
#include "common/Strings.h"
#include "common/Version.h"

namespace granagg::common {

std::string formatReal(double x) {
  char buf[64];
  auto res = std::to_chars(buf, buf + sizeof buf, x);
  return std::string(buf, res.ptr);
}

void Provenance::add(const std::string& key, const std::string& value) {
  m_params.emplace_back(key, value);
}
void Provenance::add(const std::string& key, double value) { add(key, formatReal(value)); }
void Provenance::add(const std::string& key, long long value) { add(key, std::to_string(value)); }

std::string commandLine(int argc, const char* const* argv) {
  std::string line;
  for (int i = 0; i < argc; ++i) {
    std::string a = argv[i];
    if (i) line += ' ';
    if (a.find_first_of(" \t\"'") != std::string::npos)
      line += '\'' + a + '\'';
    else
      line += a;
  }
  return line;
}

void CsvTarget::checkWritable() const {
  if (path == "-") return;
  checkOutputFile(path, "--out");  // a folder given as the file, a missing or read-only folder
  refuseToOverwrite();
}

void refuseToOverwrite(const std::string& path, bool overwrite) {
  struct stat st;
  if (!overwrite && ::stat(path.c_str(), &st) == 0)
    throw std::invalid_argument(
        "output file '" + path +
        "' already exists; choose another --out or pass --force to overwrite it");
}

CsvWriter::CsvWriter(const std::string& path, const Provenance& prov,
                     const std::vector<std::string>& columns, bool overwrite)
    : m_path(path), m_ncol(columns.size()) {
  if (columns.empty()) throw std::invalid_argument("CsvWriter requires at least one column.");
  if (path == "-") {
    m_file = stdout;
  } else {
    refuseToOverwrite(path, overwrite);
    // written as PATH.partial and renamed at close(): a failed command leaves no header-only or
    // half-written table behind to block (or mislead) its rerun
    m_partial = path + ".partial";
    m_file = std::fopen(m_partial.c_str(), "w");
    if (!m_file) throw std::runtime_error("cannot open '" + path + "' for writing");
    m_owns = true;
  }
  std::fprintf(m_file, "# %s\n", versionString().c_str());
  if (!prov.command().empty()) std::fprintf(m_file, "# command = %s\n", prov.command().c_str());
  for (const auto& [k, v] : prov.parameters())
    std::fprintf(m_file, "# %s = %s\n", k.c_str(), v.c_str());
  for (std::size_t c = 0; c < columns.size(); ++c)
    std::fprintf(m_file, "%s%s", c ? "," : "", columns[c].c_str());
  std::fputc('\n', m_file);
}

CsvWriter::~CsvWriter() {
  if (m_file && m_owns) {  // not closed: the command failed; its table is not a result
    std::fclose(m_file);
    std::remove(m_partial.c_str());
  }
}

void CsvWriter::row(const std::vector<double>& values) {
  if (values.size() != m_ncol)
    throw std::logic_error("CsvWriter::row: " + std::to_string(values.size()) + " values for " +
                           std::to_string(m_ncol) + " columns");
  std::string line;
  for (std::size_t c = 0; c < values.size(); ++c) {
    if (c) line += ',';
    line += formatReal(values[c]);
  }
  line += '\n';
  if (std::fputs(line.c_str(), m_file) == EOF && m_errno == 0) m_errno = errno;
}

void CsvWriter::comment(const std::string& text) { std::fprintf(m_file, "# %s\n", text.c_str()); }

void CsvWriter::close() {
  if (!m_file) return;
  errno = 0;
  bool bad = std::ferror(m_file) != 0;
  int err = bad ? m_errno : 0;
  if (m_owns) {
    if (std::fclose(m_file) != 0) {
      bad = true;
      if (!err) err = errno;
    }
    if (!bad && std::rename(m_partial.c_str(), m_path.c_str()) != 0) {
      bad = true;
      err = errno;
    }
    if (bad) std::remove(m_partial.c_str());
  } else {
    std::fflush(m_file);
  }
  m_file = nullptr;
  if (bad)
    throw std::runtime_error("writing '" + m_path + "' failed" +
                             (err ? ": " + writeErrorReason(err) : std::string()));
}

bool CsvTable::hasColumn(const std::string& name) const {
  for (const auto& c : columns)
    if (c == name) return true;
  return false;
}

std::size_t CsvTable::column(const std::string& name) const {
  for (std::size_t c = 0; c < columns.size(); ++c)
    if (columns[c] == name) return c;
  throw std::invalid_argument(source + ": no column named '" + name +
                              "' (columns: " + join(columns, ",") + ")");
}

CsvTable readCsv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::invalid_argument("cannot open '" + path + "'");
  CsvTable t;
  t.source = path;
  std::string line;
  std::size_t lineno = 0;
  while (std::getline(in, line)) {
    ++lineno;
    std::string s = trim(line);
    if (s.empty()) continue;
    if (s[0] == '#') {
      auto eq = s.find('=');
      if (eq != std::string::npos)
        t.meta.emplace_back(trim(s.substr(1, eq - 1)), trim(s.substr(eq + 1)));
      continue;
    }
    auto fields = split(s, ',');
    if (t.columns.empty()) {
      for (auto& f : fields) t.columns.push_back(trim(f));
      continue;
    }
    if (fields.size() != t.columns.size())
      throw std::invalid_argument(path + ":" + std::to_string(lineno) + ": expected " +
                                  std::to_string(t.columns.size()) + " fields, found " +
                                  std::to_string(fields.size()));
    std::vector<double> row;
    row.reserve(fields.size());
    for (auto& f : fields) {
      double v;
      if (!parseReal(trim(f), v))
        throw std::invalid_argument(path + ":" + std::to_string(lineno) + ": '" + trim(f) +
                                    "' is not a number");
      row.push_back(v);
    }
    t.rows.push_back(std::move(row));
  }
  if (t.columns.empty()) throw std::invalid_argument(path + ": no header row (empty file?)");
  return t;
}

}  // namespace granagg::common
