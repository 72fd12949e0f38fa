/// `granagg smol`: mean-field Smoluchowski solutions and the z(beta) table
/// (meanfield/solvers/SmolTables.h solves and writes). This file wires the options.
#include <cstdio>
#include <memory>
#include <string>

#include "cli/CliContext.h"
#include "meanfield/solvers/SmolTables.h"

namespace granagg::cli {
namespace mf = granagg::meanfield;

namespace {

/// Adds -o/--force to `cmd`; the target carries the command line for the provenance header.
std::shared_ptr<common::CsvTarget> addOutOptions(CLI::App* cmd, const CliContext& ctx) {
  auto target = std::make_shared<common::CsvTarget>();
  target->command_line = ctx.command_line;
  cmd->add_option("-o,--out", target->path, "Output CSV ('-' = standard output)")
      ->capture_default_str();
  cmd->add_flag("--force", target->force, "Overwrite an existing output file");
  return target;
}

/// The log: stderr, one line each (stdout carries only tables written to "-").
void logLine(const std::string& line) { std::fprintf(stderr, "%s\n", line.c_str()); }

}  // namespace

void registerSmolCommand(CLI::App& app, const CliContext& ctx) {
  auto args = std::make_shared<mf::SmolRequest>();
  CLI::App* smol = app.add_subcommand(
      "smol",
      "Solve the Smoluchowski coagulation equation from a monodisperse start (n_1(0) = 1) and "
      "report S(t) = M2/M1\n"
      "with its local slope and asymptotic growth exponent z. Time unit 1/(K0 n_1(0)).");
  smol->add_option("--kernel", args->kernel,
                   "Aggregation kernel: beta, constant, additive, multiplicative")
      ->capture_default_str();
  smol->add_option("--beta", args->beta,
                   "beta of the kernel (i^{1/3}+j^{1/3})^2 (1/i+1/j)^{1/beta}; > 0")
      ->capture_default_str();
  smol->add_option("--K0", args->K0, "Kernel prefactor (> 0)")->capture_default_str();
  smol->add_option(
          "--method", args->method,
          "sectional (fixed-pivot, reaches S >> 1e8), discrete (CVODE + FFT, exact sizes 1..M), "
          "mono (monodisperse approximation, Odeint)")
      ->capture_default_str();
  smol->add_option("--t-min", args->t_min, "First output time (> 0)")->capture_default_str();
  smol->add_option("--t-end", args->t_end, "Last output time")->capture_default_str();
  smol->add_option("--per-decade", args->per_decade, "Log-spaced output times per decade")
      ->capture_default_str();
  smol->add_option("--s-end", args->s_end,
                   "Stop once S reaches this mean size (default: no limit)");
  smol->add_option("--M", args->max_size,
                   "discrete: largest size class (the active range grows with S up to M); the "
                   "sectional grid needs no bound, it grows with S")
      ->capture_default_str();
  smol->add_option("--ratio", args->ratio,
                   "sectional: geometric grid ratio (> 1); S errors scale as (ratio-1)^2; the "
                   "grid holds at most 4096 sections, so a larger ratio reaches larger S")
      ->capture_default_str();
  smol->add_option("--rtol", args->rtol, "CVODE relative tolerance")->capture_default_str();
  smol->add_option("--atol", args->atol,
                   "CVODE absolute tolerance, relative to the initial mass M1(0)")
      ->capture_default_str();
  smol->add_option("--integrator", args->integrator,
                   "discrete: adams, bdf (matrix-free GMRES) or bdf-dense")
      ->capture_default_str();
  smol->add_option("--p", args->p, "Local-slope ratio p in z(t) = log[S(t)/S(t/p)]/log p")
      ->capture_default_str();
  smol->add_option("--z-tolerance", args->z_tolerance, "Convergence criterion of the asymptotic z")
      ->capture_default_str();
  auto target = addOutOptions(smol, ctx);
  auto quiet = std::make_shared<bool>(false);
  smol->add_flag("-q,--quiet", *quiet, "No summary on the terminal");

  auto zargs = std::make_shared<mf::ZbetaRequest>();
  CLI::App* zbeta = smol->add_subcommand("zbeta",
                                         "Table of the asymptotic growth exponent z(beta) from the "
                                         "full Smoluchowski equation beside 3 beta/(beta+3).");
  zbeta->add_option("--beta-min", zargs->beta_min, "Smallest beta (> 0)")->capture_default_str();
  zbeta->add_option("--beta-max", zargs->beta_max, "Largest beta")->capture_default_str();
  zbeta->add_option("--count", zargs->count, "Number of beta values")->capture_default_str();
  zbeta->add_option("--method", zargs->method, "sectional or discrete")->capture_default_str();
  zbeta->add_option("--s-end", zargs->s_end, "Mean size at which each solve stops")
      ->capture_default_str();
  zbeta->add_option("--ratio", zargs->ratio, "sectional: geometric grid ratio")
      ->capture_default_str();
  auto ztarget = addOutOptions(zbeta, ctx);

  zbeta->callback([zargs, ztarget]() { mf::writeZbetaTable(*zargs, *ztarget, logLine); });
  smol->callback([smol, args, target, quiet, zbeta]() {
    if (zbeta->parsed()) return;  // `smol zbeta` ran its own callback
    if (smol->count("--M") > 0 && args->method != "discrete" && !*quiet)
      logLine("smol: --M applies to --method discrete only; the " + args->method +
              " method does not use it");
    mf::writeSmolTable(*args, *target, *quiet ? mf::LogLine() : mf::LogLine(logLine));
  });
}

}  // namespace granagg::cli
