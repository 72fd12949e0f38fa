/// `granagg pair`: the options of a paired MD / mean-field study, wired to the study library
/// (study/PairStudy.h, docs/pair.md) and to what the study needs of md/ and analysis/.
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>

#include "analysis/stats/GrowthMarkers.h"
#include "cli/CliContext.h"
#include "md/config/ConfigParser.h"
#include "md/engine/Engine.h"
#include "study/PairStudy.h"
#include "study/insitu/InSituAnalysis.h"

namespace granagg::cli {
namespace fs = std::filesystem;
using study::MAX_RUNS;

namespace {

struct PairArgs {
  std::string preset, config, K;
  int runs = 0;  // used when given on the command line
  study::StudyRequest request;
};

/// What the study needs of md/ and analysis/ (study/PairStudy.h, StudyServices).
study::StudyServices services(const CliContext& ctx, const CLI::App* root) {
  study::StudyServices s;
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  s.exe = ec ? std::string("granagg") : self.string();
  s.command_line = ctx.command_line;
  s.backend = md::Engine::backendDescription();
  s.find_md_preset = [](const std::string& name) {
    return findPreset("presets", name, "[md] preset");
  };
  s.resolve_md = [](const std::string& base, const std::vector<std::string>& set) {
    md::MdConfig cfg = md::parseConfigFile(base, set);
    cfg.system.seed = 0;  // every run sets its own with --seed
    md::validateConfig(cfg);
    if (cfg.output.analyze) insitu::analysisOptions(cfg);  // [analysis] args refused here
    study::MdPlan p;
    p.toml = md::toToml(cfg);
    p.N = cfg.system.N;
    p.phi = cfg.system.phi;
    p.t_end = cfg.run.t_end;
    p.charging_Q = cfg.charging.Q;
    p.kappa = cfg.charging.kappa;
    p.E = cfg.contact.E;
    p.D = cfg.contact.D;
    p.steps = std::ceil(cfg.run.t_end / md::Engine::chooseTimeStep(cfg));
    return p;
  };
  s.classify_growth = [](const std::vector<double>& t, const std::vector<double>& S,
                         const std::vector<double>& z) {
    const analysis::GrowthRegime g = analysis::classifyGrowth(t, S, z);
    return study::GrowthSummary{g.regime, g.reason, g.growth_factor};
  };
  s.flat_slope_tolerance = analysis::FLAT_SLOPE_TOLERANCE;
  s.data_dirs = dataDirs();
  s.paper = paperValues();
  s.fit_available = false;
  for (const CLI::App* sub : root->get_subcommands({}))
    s.fit_available |= sub->get_name() == "fit-beta";
  s.stop = stopSignal();
  // scripts/ of the source tree: GRANAGG_SCRIPTS, else GRANAGG_DATA_DIR/../scripts
  const char* scripts = std::getenv("GRANAGG_SCRIPTS");
  s.scripts = scripts ? fs::path(scripts) : fs::path(GRANAGG_DATA_DIR).parent_path() / "scripts";
  if (const char* py = std::getenv("GRANAGG_PYTHON"))
    s.python = py;
  else if (!fs::exists(s.python))
    s.python = "python3";
  return s;
}

void runPair(const PairArgs& a, const CliContext& ctx, const CLI::App* root, bool runs_given,
             bool K_given) {
  if (a.preset.empty() == a.config.empty())
    throw std::invalid_argument("give exactly one of --preset NAME or --config FILE");
  study::PairConfig c = study::parsePairConfig(
      a.config.empty() ? findPreset("pair", a.preset, "--preset") : a.config);
  if (K_given) c.K = study::parseKList(a.K);  // (--K "" is refused there, not ignored)
  if (runs_given) c.runs = a.runs;
  study::PairStudy pair(c, a.request, services(ctx, root));  // checks everything first
  catchStopSignals();  // forwarded to the runs, which stop with a checkpoint
  pair.run();
}

}  // namespace

void registerPairCommand(CLI::App& app, const CliContext& ctx) {
  auto a = std::make_shared<PairArgs>();
  CLI::App* c = app.add_subcommand(
      "pair",
      "Paired MD / mean-field study (docs/pair.md): MD ensembles for "
      "each Coulomb constant K (run r has seed pair.seed + r for every K, up to\n"
      "--jobs runs at a time), their analysis, the mean field "
      "(Smoluchowski S(t) for beta = 2, 3 and z(beta)), the\n"
      "beta fit, the paper's figures and report.html, and "
      "summary.json. An interrupted study resumes: run the same\n"
      "command again and finished runs are not redone.");
  c->add_option("--preset", a->preset,
                "Pair preset from data/pair: tiny, quick, paper, validate-neutral, "
                "validate-charged, validate-box");
  c->add_option("-c,--config", a->config, "Pair configuration TOML (keys: docs/pair.md)");
  c->add_option("--K", a->K, "Comma-separated Coulomb constants, e.g. 0,5 (overrides pair.K)");
  // bounded: --runs 1e9 grew to 24 GB before failing; 1e5 wrote a 2e5-task Slurm array
  c->add_option("--runs", a->runs, "Runs per K (1..10000; overrides pair.runs)")
      ->check(CLI::Range(1, MAX_RUNS));
  c->add_option("--jobs", a->request.jobs,
                "MD runs at a time, 1..1024 (default: max(1, cores / 2); with md.engine = "
                "\"lammps\": max(1, cores / lammps.ranks))")
      ->check(CLI::Range(1, 1024));
  c->add_option("--threads", a->request.threads,
                "OpenMP threads per granagg md run, 1..4096 (default: max(1, cores / jobs))")
      ->check(CLI::Range(1, 4096));
  c->add_option("--launcher", a->request.launcher,
                "How granagg-lammps runs start (md.engine = \"lammps\"; overrides "
                "lammps.launcher), e.g. \"mpirun -np {ranks}\"");
  c->add_option("-o,--out", a->request.out,
                "Output folder (default pair-<preset>); an existing study there is resumed");
  c->add_flag("--force", a->request.force,
              "Start over in an existing output folder (redo every run)");
  c->add_option("--emit-batch", a->request.emit_batch,
                "Write DIR/batch.slurm (a Slurm job array + follow-up job) instead of running");
  c->add_option("--run-index", a->request.run_index,
                "Run only the run with this index (k * runs + r); what batch array tasks call")
      ->group("");
  c->add_flag("--no-figures", a->request.no_figures, "Skip the figures and the report");
  c->add_flag("--keep-trajectories", a->request.keep_trajectories,
              "Store every run's particle frames (traj.h5) besides its analysis during the run "
              "(granagg md's runs store none by default; Fig. 2's snapshots need them)");
  c->add_flag("-q,--quiet", a->request.quiet, "No progress line or summary");
  const CLI::App* root = &app;
  c->callback([a, ctx, root, c]() {
    if (c->count("--run-index") > 0 && a->request.run_index < 0)  // -1 would start the whole study
      throw std::invalid_argument("--run-index must be >= 0 (got " +
                                  std::to_string(a->request.run_index) + ")");
    if (c->count("--launcher") > 0 &&
        a->request.launcher.find_first_not_of(" \t") == std::string::npos)
      throw std::invalid_argument(
          "--launcher is empty: give the command that starts MPI ranks, e.g. \"mpirun -np "
          "{ranks}\"");
    runPair(*a, ctx, root, c->count("--runs") > 0, c->count("--K") > 0);
  });
}

}  // namespace granagg::cli
