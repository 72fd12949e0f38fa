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
/// MPI ranks, nodes or tasks per node of a granagg-lammps run at most (2^20: beyond any machine;
/// the bound catches typos such as a missing separator).
constexpr int MAX_RANKS = 1048576;

struct PairConfig {
  std::string source;  ///< the file it was read from (absolute)
  std::string name = "custom";
  std::vector<double> K{0.0, 5.0};  ///< Coulomb constants, one ensemble each
  int runs = 3;                     ///< runs per K; run r has seed `seed + r` for every K
  long long seed = 1;
  std::string md_preset, md_config;  ///< exactly one is set (md_config absolute)
  std::vector<std::string> md_set;   ///< `granagg md --set` assignments for every K
  /// The program that runs the MD: "granagg" (`granagg md`) or "lammps" (granagg-lammps under
  /// an MPI launcher, docs/lammps.md); MD_ENGINES lists them.
  std::string md_engine = "granagg";
  double charged_Q = 0.05;  ///< docs/validation.md: the largest stable value of its Q scan at K = 5
  std::vector<std::string> charged_set;    ///< further assignments for K > 0
  std::vector<std::string> analysis_args;  ///< extra `granagg analyze` arguments
  std::vector<double> betas{2.0, 3.0};     ///< mean-field kernel exponents
  double mf_t_end = 1e7, mf_s_end = 1e6;
  double zbeta_min = 2.0, zbeta_max = 4.0;
  int zbeta_count = 5;
  std::vector<double> fit_window;  ///< [] (fit-beta chooses) or [t0, t1]
  std::string fit_column;          ///< "" (fit-beta's default) or a column of S_t.csv
  /// How granagg-lammps runs are started here (md_engine = "lammps"): the launcher's words
  /// (split at blanks, no shell), `{ranks}` replaced by lammps_ranks; granagg-lammps and its
  /// arguments follow them.
  std::string lammps_launcher = "mpirun -np {ranks}";
  int lammps_ranks = 2;  ///< MPI ranks of one run here (the job pool counts them as cores)
  /// In the Slurm script (--emit-batch slurm): every array task holds lammps_nodes nodes with
  /// lammps_tasks_per_node ranks each, and starts its run with
  /// `lammps_slurm_launcher --nodes=N --ntasks-per-node=T`.
  std::string lammps_slurm_launcher = "srun";
  int lammps_nodes = 1, lammps_tasks_per_node = 2;
};

/// The values of [md] engine.
inline const char* const MD_ENGINES[] = {"granagg", "lammps"};

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

/// A launcher's words: `launcher` split at blanks, each `{ranks}` replaced by `ranks`
/// ("mpirun -np {ranks}", 2 -> mpirun, -np, 2). No shell runs them, so quotes, `$` and other shell
/// syntax are refused, as is an empty launcher: std::invalid_argument naming `key`.
std::vector<std::string> launcherWords(const std::string& launcher, long long ranks,
                                       const std::string& key);

/// The folder and file name of the ensemble at K: "K0", "K5", "K2.5".
std::string kName(double K);

}  // namespace granagg::study
