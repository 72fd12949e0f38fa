#pragma once
/// \file Csv.h
/// CSV tables with a provenance header (docs/ARCHITECTURE.md, "Files and formats"):
///
///     # granagg 0.1.0 (abc123)
///     # command = granagg smol --beta 3
///     # beta = 3
///     t,S,M0,M1,M2
///     1,1.02,...
///
/// Lines starting with '#' carry "key = value" provenance; one row of column names follows.
/// numpy.loadtxt(..., delimiter=',', skiprows=...) / pandas.read_csv(comment='#') read it.
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

namespace granagg::common {

/// What made an output: the command line and the resolved parameters, in insertion order.
class Provenance {
 public:
  Provenance() = default;
  explicit Provenance(std::string command) : m_command(std::move(command)) {}
  /// Record a parameter; numbers are written with round-trip precision.
  void add(const std::string& key, const std::string& value);
  void add(const std::string& key, const char* value) { add(key, std::string(value)); }
  void add(const std::string& key, double value);
  void add(const std::string& key, long long value);
  void add(const std::string& key, int value) { add(key, static_cast<long long>(value)); }
  void add(const std::string& key, bool value) { add(key, std::string(value ? "true" : "false")); }
  const std::string& command() const { return m_command; }
  const std::vector<std::pair<std::string, std::string>>& parameters() const { return m_params; }

 private:
  std::string m_command;
  std::vector<std::pair<std::string, std::string>> m_params;
};

/// Joins argv into one shell-like line (arguments with spaces are quoted).
std::string commandLine(int argc, const char* const* argv);

/// Shortest decimal representation that reads back to the same double.
std::string formatReal(double x);

/// Writes one CSV table. Path "-" writes to standard output. An existing file is never
/// overwritten unless `overwrite` is true (std::invalid_argument names the file otherwise).
/// The table appears at `path` only when close() succeeds (it is written as `path.partial` and
/// renamed); a writer destroyed without close() -- a command that failed -- leaves nothing.
class CsvWriter {
 public:
  CsvWriter(const std::string& path, const Provenance& provenance,
            const std::vector<std::string>& columns, bool overwrite = false);
  ~CsvWriter();
  CsvWriter(const CsvWriter&) = delete;
  CsvWriter& operator=(const CsvWriter&) = delete;

  /// Appends one row; its length must equal the number of columns.
  void row(const std::vector<double>& values);
  /// Adds a comment line ("# text") between rows, e.g. to flag truncated times.
  void comment(const std::string& text);
  /// Flushes and closes; throws std::runtime_error if the write failed (disk full...).
  void close();
  const std::string& path() const { return m_path; }

 private:
  std::string m_path, m_partial;
  std::size_t m_ncol;
  std::FILE* m_file = nullptr;
  bool m_owns = false;
  int m_errno = 0;  // of the first failed write
};

/// Throws std::invalid_argument if `path` exists and `overwrite` is false.
void refuseToOverwrite(const std::string& path, bool overwrite);

/// Where a command's table goes: a path ("-" = standard output), whether an existing file may be
/// replaced, and the command line its provenance header starts with.
struct CsvTarget {
  std::string path = "-";
  bool force = false;
  std::string command_line;
  /// Throws std::invalid_argument if the table would replace a file without `force` (so that a
  /// command can refuse before it computes anything).
  void refuseToOverwrite() const { common::refuseToOverwrite(path == "-" ? "" : path, force); }
  /// refuseToOverwrite(), and refuses a path whose folder is missing or takes no new file
  /// (common::checkOutputFile, naming --out): what a command checks before it computes.
  void checkWritable() const;
};

/// A CSV table read back: provenance comments, column names and rows.
struct CsvTable {
  std::vector<std::pair<std::string, std::string>> meta;  ///< "# key = value" lines
  std::vector<std::string> columns;
  std::vector<std::vector<double>> rows;
  /// Index of a named column; throws std::invalid_argument naming the file and column.
  std::size_t column(const std::string& name) const;
  /// Whether a column of that name exists.
  bool hasColumn(const std::string& name) const;
  std::string source;
};

/// Reads a numeric CSV table written by CsvWriter (or any CSV with one header row; '#' lines are
/// comments). Errors name the file and the line.
CsvTable readCsv(const std::string& path);

}  // namespace granagg::common
