#pragma once
/// \file PairStudy.h
/// A paired MD / mean-field study (docs/pair.md): the MD ensembles (one `granagg md` process per
/// run, up to `jobs` at a time, resumable), their analysis (`granagg analyze`), the mean field
/// (`granagg smol`, `granagg kinetic`), the beta fit (`granagg fit-beta`), the figures and report
/// (scripts/plot_figures.py, scripts/make_report.py) and summary.json. Every step is a subprocess
/// of the granagg binary, with its output in DIR/logs/ and its command line in DIR/commands.txt;
/// each run and stage leaves a record, so that the same request again resumes where it stopped.
///
/// The library includes none of md/, analysis/ or meanfield/: what it needs of them comes in
/// StudyServices, wired by the command line (cli/PairCommand.cpp).
#include <sys/types.h>

#include <chrono>
#include <csignal>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "common/FolderLock.h"
#include "common/PaperValues.h"
#include "study/MdLaunch.h"
#include "study/PairConfig.h"

namespace granagg::study {

/// One ensemble's MD configuration, resolved by the MD library (StudyServices::resolve_md).
struct MdPlan {
  std::string toml;  ///< every key resolved (its hash identifies the runs made with it)
  long long N = 0;
  double phi = 0, t_end = 0, charging_Q = 0, kappa = 0, E = 0, D = 0;
  double steps = 0;  ///< time steps to t_end (the job pool starts the longest runs first)
};

/// The growth regime of an ensemble's S(t) (analysis/stats/GrowthMarkers.h).
struct GrowthSummary {
  std::string regime = "unknown", reason;
  double growth_factor = 0.0;
};

/// What a study needs from the rest of granagg.
struct StudyServices {
  std::string exe;  ///< the granagg binary that runs every step (granagg-lammps lies beside it)
  std::string command_line;  ///< of this study's command, for provenance
  std::string backend;       ///< the MD backend's description, for summary.json
  /// The MD configuration file behind [md] preset = "name" (std::invalid_argument if unknown).
  std::function<std::string(const std::string& name)> find_md_preset;
  /// Base configuration file + `--set` assignments -> the resolved configuration (throws
  /// std::invalid_argument for a bad key or value: before anything is written).
  std::function<MdPlan(const std::string& base, const std::vector<std::string>& set)> resolve_md;
  /// The regime of S(t) with its local slope z(t).
  std::function<GrowthSummary(const std::vector<double>& t, const std::vector<double>& S,
                              const std::vector<double>& z)>
      classify_growth;
  double flat_slope_tolerance = 0.1;   ///< relative spread of z(t) that still counts as flat
  std::vector<std::string> data_dirs;  ///< where data/validation/verdict.csv is looked for
  common::PaperValues paper;
  bool fit_available = true;                         ///< this build has `granagg fit-beta`
  const volatile std::sig_atomic_t* stop = nullptr;  ///< set (to the signal) to stop the study
  std::filesystem::path scripts;                     ///< scripts/ (figures and report)
  std::string python = "/usr/bin/python3";
};

/// What to do with the study (the command line's options).
struct StudyRequest {
  std::string out;         ///< "" : pair-<name>
  std::string emit_batch;  ///< "slurm": write DIR/batch.slurm instead of running
  int jobs = 0;            ///< MD runs at a time; 0: max(1, cores / 2)
  int threads = 0;         ///< threads per run; 0: max(1, cores / jobs)
  int run_index = -1;      ///< >= 0: run only this run (a batch array task)
  std::string launcher;    ///< "" : lammps.launcher; else the launcher of granagg-lammps runs
  bool force = false, quiet = false, no_figures = false;
  /// granagg md's runs store their particle frames (traj.h5) besides their in-situ analysis
  bool keep_trajectories = false;
};

/// One MD run of the study.
struct RunJob {
  double K = 0;
  int r = 0;
  long long seed = 0;
  int index = 0;  ///< k * runs + r: the batch array index
  std::filesystem::path dir, config, log;
  /// the resolved configuration's hash, the seed and the engine unless granagg's own: what a
  /// record must match
  std::string spec;
  std::string
      legacy_spec;  ///< the same with the legacy hash basis of older records (Process.h)
  double cost = 0;  ///< particle-steps, x100 with Coulomb: longest first
  bool restart = false;
};

class PairStudy {
 public:
  /// Checks the request and resolves every ensemble's MD configuration: bad input throws
  /// std::invalid_argument before anything is written.
  PairStudy(PairConfig config, StudyRequest request, StudyServices services);

  /// Runs (or resumes) the study. A stop signal throws common::Interrupted once the runs have
  /// stopped with their checkpoints; failed steps throw std::runtime_error at the end.
  void run();

  const std::filesystem::path& out() const { return m_out; }
  const std::vector<RunJob>& runs() const { return m_runs; }

 private:
  using clock = std::chrono::steady_clock;
  void prepareFolder();
  void say(const std::string& line, bool terminal = true);
  std::string batchCommand() const;
  void emitSlurm();
  void setUpLaunch();
  /// The runs of `all` still to do (finished ones counted in `done`), restarts marked.
  std::vector<RunJob> runsToDo(std::vector<RunJob>& all, int& done);
  void runMd(std::vector<RunJob> jobs);
  pid_t startRun(const RunJob& j, int threads, bool echo);
  void recordFinished(const RunJob& job, double wall, int threads);
  void stopRun(pid_t pid);
  std::string runLastLine(const RunJob& j) const;
  int runStep(const std::string& label, std::vector<std::string> argv, const std::string& logname,
              bool quiet_failure = false);
  /// One resumable step of a post-processing stage (analyse, mean field, fit): one command whose
  /// marker file holds the step's spec once it has run. A step is skipped when its marker holds
  /// `spec` and `made` exists, unless `redo` (an input changed); otherwise `clear` is removed,
  /// the command run (runStep) and on success the marker written.
  struct StageStep {
    std::string label, logname;
    std::vector<std::string> argv;
    std::string spec;
    std::filesystem::path marker, made, clear;
    bool redo = false;
    bool quiet_failure = false;
  };
  /// Runs `step` as StageStep says; returns its exit status, or STEP_SKIPPED.
  int runStageStep(const StageStep& step);
  static constexpr int STEP_SKIPPED = -1;
  void analyse();
  void meanField();
  void fitBeta();
  void pythonStage(const std::string& stage, const std::string& script,
                   const std::filesystem::path& made);
  void figuresAndReport();  ///< the figures, the summary (once) and report.html
  void writeSummary();
  void printSummary();
  double seconds() const { return std::chrono::duration<double>(clock::now() - m_start).count(); }
  int stopped() const { return m_s.stop ? static_cast<int>(*m_s.stop) : 0; }

  PairConfig m_c;
  StudyRequest m_a;
  StudyServices m_s;
  std::filesystem::path m_out;
  std::optional<common::FolderLock> m_lock;  ///< the study folder's, while run() writes it
  int m_cores;
  clock::time_point m_start;
  std::map<std::string, MdPlan> m_md;            ///< per K name
  std::map<std::string, std::string> m_md_text;  ///< path -> resolved MD TOML to write
  std::vector<RunJob> m_runs;                    ///< every run of the study
  MdLaunch m_launch;                             ///< how the runs are started
  std::set<std::string> m_changed_k;             ///< K names with a run (re)done now
  std::map<std::string, double> m_timing;
  std::map<std::string, std::string> m_status;    ///< step -> done / skipped: ... / failed: ...
  std::map<std::string, std::string> m_fit_note;  ///< K name -> why fit-beta gave no result
  int m_failures = 0;
};

}  // namespace granagg::study
