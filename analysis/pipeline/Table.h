#pragma once
/// \file Table.h
/// A numeric table (one observable), its ensemble average over runs, and its CSV output.
#include <string>
#include <vector>

#include "common/Csv.h"

namespace granagg::analysis {

struct Table {
  std::string name;         ///< file stem, e.g. "S_t"
  std::string description;  ///< what the columns mean, with units (goes into provenance)
  std::vector<std::string> columns;
  std::size_t key_columns = 1;   ///< leading columns that identify a row across runs (t; t and s)
  bool missing_is_zero = false;  ///< ensemble: a key absent from a run counts as 0 (counts N_s)
  bool ensemble = true;          ///< false: per-run only (e.g. per-particle scatter)
  std::vector<std::vector<double>> rows;

  Table() = default;
  Table(std::string name_, std::string description_, std::vector<std::string> columns_,
        std::size_t keys = 1)
      : name(std::move(name_)),
        description(std::move(description_)),
        columns(std::move(columns_)),
        key_columns(keys) {}
  /// Appends a row; throws std::logic_error when its length differs from the columns.
  void add(std::vector<double> row);
  /// Index of a column; throws std::out_of_range naming it.
  std::size_t column(const std::string& name) const;
  /// All values of one column.
  std::vector<double> values(const std::string& name) const;
};

/// Ensemble average over runs of the same table: rows matched by their key columns (compared
/// after rounding to 9 significant digits, so that times written by different engines match);
/// each other column c becomes c_mean and c_se (standard error of the mean, s / sqrt(n), NaN
/// for fewer than 2 values), NaN values are left out; a last column n_runs counts the runs
/// holding the row. Rows are sorted by key.
Table ensembleAverage(const std::vector<const Table*>& runs);

/// Per-run tables stacked in long format with a leading "run" column (the run's index).
Table stackRuns(const std::vector<const Table*>& runs);

/// Writes a table as CSV with provenance (description added as "columns = ...").
void writeCsv(const Table& table, const std::string& path, const common::Provenance& provenance,
              bool overwrite);

}  // namespace granagg::analysis
