#include "analysis/pipeline/Table.h"

#include <cmath>
#include <cstdio>
#include <map>
#include <stdexcept>

namespace granagg::analysis {

void Table::add(std::vector<double> row) {
  if (row.size() != columns.size())
    throw std::logic_error("table " + name + ": row of " + std::to_string(row.size()) +
                           " values, " + std::to_string(columns.size()) + " columns");
  rows.push_back(std::move(row));
}

std::size_t Table::column(const std::string& c) const {
  for (std::size_t k = 0; k < columns.size(); ++k)
    if (columns[k] == c) return k;
  throw std::out_of_range("table " + name + " has no column '" + c + "'");
}

std::vector<double> Table::values(const std::string& c) const {
  const std::size_t k = column(c);
  std::vector<double> v;
  v.reserve(rows.size());
  for (const auto& r : rows) v.push_back(r[k]);
  return v;
}

namespace {
double round9(double x) {
  if (!std::isfinite(x) || x == 0) return x;
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", x);
  return std::strtod(buf, nullptr);
}
}  // namespace

Table ensembleAverage(const std::vector<const Table*>& runs) {
  if (runs.empty()) throw std::invalid_argument("ensembleAverage needs at least one run.");
  const Table& first = *runs.front();
  const std::size_t nk = first.key_columns, nc = first.columns.size();
  Table out;
  out.name = first.name;
  out.description = first.description +
                    "; ensemble: <col>_mean over runs, <col>_se = standard error of the mean, "
                    "n_runs = runs holding the row";
  out.key_columns = nk;
  out.missing_is_zero = first.missing_is_zero;
  for (std::size_t k = 0; k < nk; ++k) out.columns.push_back(first.columns[k]);
  for (std::size_t k = nk; k < nc; ++k) {
    out.columns.push_back(first.columns[k] + "_mean");
    out.columns.push_back(first.columns[k] + "_se");
  }
  out.columns.push_back("n_runs");
  struct Acc {
    std::vector<double> key;
    std::vector<double> sum, sum2;
    std::vector<std::size_t> n;
    std::size_t runs = 0;
  };
  std::map<std::vector<double>, Acc> acc;
  for (const Table* t : runs) {
    if (t->columns != first.columns)
      throw std::invalid_argument("ensembleAverage: table " + first.name +
                                  " differs between runs.");
    for (const auto& r : t->rows) {
      std::vector<double> key(r.begin(), r.begin() + static_cast<long>(nk));
      for (double& x : key) x = round9(x);
      Acc& a = acc[key];
      if (a.sum.empty()) {
        a.key.assign(r.begin(), r.begin() + static_cast<long>(nk));
        a.sum.assign(nc - nk, 0.0);
        a.sum2.assign(nc - nk, 0.0);
        a.n.assign(nc - nk, 0);
      }
      ++a.runs;
      for (std::size_t k = nk; k < nc; ++k)
        if (std::isfinite(r[k])) {
          a.sum[k - nk] += r[k];
          a.sum2[k - nk] += r[k] * r[k];
          ++a.n[k - nk];
        }
    }
  }
  const double R = static_cast<double>(runs.size());
  for (auto& [key, a] : acc) {
    std::vector<double> row = a.key;
    for (std::size_t k = 0; k < nc - nk; ++k) {
      // Counts absent from a run are zeros of that run (N_s(s) = 0).
      const double n = first.missing_is_zero ? R : static_cast<double>(a.n[k]);
      if (n < 1) {
        row.push_back(std::nan(""));
        row.push_back(std::nan(""));
        continue;
      }
      const double mean = a.sum[k] / n;
      const double var =
          n > 1 ? std::max(0.0, (a.sum2[k] - n * mean * mean) / (n - 1)) : std::nan("");
      row.push_back(mean);
      row.push_back(n > 1 ? std::sqrt(var / n) : std::nan(""));
    }
    row.push_back(static_cast<double>(a.runs));
    out.rows.push_back(std::move(row));
  }
  return out;
}

Table stackRuns(const std::vector<const Table*>& runs) {
  if (runs.empty()) throw std::invalid_argument("stackRuns needs at least one run.");
  Table out;
  out.name = runs.front()->name;
  out.description = "run: index of the run (see run.<k> lines); " + runs.front()->description;
  out.columns.push_back("run");
  for (const auto& c : runs.front()->columns) out.columns.push_back(c);
  out.key_columns = runs.front()->key_columns + 1;
  for (std::size_t r = 0; r < runs.size(); ++r)
    for (const auto& row : runs[r]->rows) {
      std::vector<double> v{static_cast<double>(r)};
      v.insert(v.end(), row.begin(), row.end());
      out.rows.push_back(std::move(v));
    }
  return out;
}

void writeCsv(const Table& t, const std::string& path, const common::Provenance& provenance,
              bool overwrite) {
  common::Provenance p = provenance;
  p.add("table", t.name);
  p.add("columns", t.description);
  common::CsvWriter w(path, p, t.columns, overwrite);
  for (const auto& r : t.rows) w.row(r);
  w.close();
}

}  // namespace granagg::analysis
