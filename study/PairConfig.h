#pragma once
/// \file PairConfig.h
/// The configuration of a paired MD / mean-field study (data/pair/*.toml; keys in docs/pair.md):
/// read with toml++ (every unknown section or key refused with its file position), checked, and
/// written back resolved (DIR/config/pair.toml, which resumes and batch array tasks read).
#include <string>
#include <vector>

namespace granagg::study {

/// Runs per K at most: a study of 2 x 10000 runs is far beyond any this code is for, and the
/// bound keeps a typo from allocating the study's bookkeeping until the machine runs out.
constexpr int MAX_RUNS = 10000;

struct PairConfig {
  std::string source;  ///< the file it was read from (absolute)
  std::string name = "custom";
  std::vector<double> K{0.0, 5.0};  ///< Coulomb constants, one ensemble each
  int runs = 3;                     ///< runs per K; run r has seed `seed + r` for every K
  long long seed = 1;
  std::string md_preset, md_config;  ///< exactly one is set (md_config absolute)
  std::vector<std::string> md_set;   ///< `granagg md --set` assignments for every K
  double charged_Q = 0.05;  ///< docs/validation.md: the largest stable value of its Q scan at K = 5
  std::vector<std::string> charged_set;    ///< further assignments for K > 0
  std::vector<std::string> analysis_args;  ///< extra `granagg analyze` arguments
  std::vector<double> betas{2.0, 3.0};     ///< mean-field kernel exponents
  double mf_t_end = 1e7, mf_s_end = 1e6;
  double zbeta_min = 2.0, zbeta_max = 4.0;
  int zbeta_count = 5;
  std::vector<double> fit_window;  ///< [] (fit-beta chooses) or [t0, t1]
  std::string fit_column;          ///< "" (fit-beta's default) or a column of S_t.csv
};

/// Reads a pair configuration. Throws std::invalid_argument with file:line:column and the key for
/// a missing file, invalid TOML, an unknown section or key, or a value of the wrong type; paths
/// in [md] config are taken relative to the file.
PairConfig parsePairConfig(const std::string& path);

/// The resolved configuration as TOML (toml++'s writer), with a comment naming its source;
/// parsePairConfig of it gives the same configuration back.
std::string toToml(const PairConfig& c);

/// "0,5" -> {0, 5}. Throws std::invalid_argument naming --K unless every item is a number >= 0.
std::vector<double> parseKList(const std::string& s);

/// Throws std::invalid_argument naming the key and its allowed range for the first bad value.
void validate(const PairConfig& c);

/// The folder and file name of the ensemble at K: "K0", "K5", "K2.5".
std::string kName(double K);

}  // namespace granagg::study
