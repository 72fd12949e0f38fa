/// \file SmolTables.cpp
/// The tables of `granagg smol` (SmolTables.h).
#include "meanfield/solvers/SmolTables.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

#include "common/Strings.h"
#include "meanfield/growth/GrowthExponent.h"
#include "meanfield/kernels/Kernel.h"
#include "meanfield/solvers/DiscreteSolver.h"
#include "meanfield/solvers/MonodisperseSolver.h"
#include "meanfield/solvers/SectionalSolver.h"

namespace granagg::meanfield {

namespace {

void requireRange(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument(what);
}

std::vector<double> outputTimes(double t_min, double t_end, int per_decade) {
  requireRange(t_min > 0.0 && std::isfinite(t_min),
               "--t-min must be positive (got " + common::formatReal(t_min) + ").");
  requireRange(t_end > t_min && std::isfinite(t_end),
               "--t-end must be larger than --t-min = " + common::formatReal(t_min) + " (got " +
                   common::formatReal(t_end) + ").");
  requireRange(per_decade >= 1 && per_decade <= 10000, "--per-decade must lie in [1, 10000].");
  const double count = std::max(2.0, std::ceil(std::log10(t_end / t_min) * per_decade) + 1.0);
  // (t_end = 1e300 at 10000 per decade wrote 357 MB)
  requireRange(count <= 1e6, "--t-end = " + common::formatReal(t_end) +
                                 " and --per-decade = " + std::to_string(per_decade) +
                                 " ask for more than 1e6 output "
                                 "times: lower one of them.");
  return logSpacedTimes(t_min, t_end, static_cast<int>(count));
}

/// Times and S of the valid samples only (a truncated solution never enters a fit).
void validSeries(const SmolResult& r, std::vector<double>& t, std::vector<double>& S) {
  t.clear();
  S.clear();
  for (const auto& s : r.samples)
    if (s.valid) {
      t.push_back(s.t);
      S.push_back(s.S);
    }
}

/// What the user of `granagg smol` can change when a solve stops early: options of that
/// command that act on `method`.
std::string smolAdvice(const SmolResult& r, const std::string& method) {
  switch (r.stop_cause) {
    case StopCause::Truncation:
      return method == "discrete" ? "raise --M, or use --method sectional (its grid grows with S)"
                                  : "raise --ratio (coarser sections reach larger sizes)";
    case StopCause::MassGained:
      return method == "discrete" ? "tighten --rtol, or use --integrator adams (it conserves "
                                    "mass to round-off)"
                                  : "tighten --rtol or --atol";
    case StopCause::SizeCeiling:
    case StopCause::NotFinite:
      return "lower --t-end, or stop at a mean size with --s-end";
    case StopCause::None:
      break;
  }
  return "";
}

/// The same for `granagg smol zbeta`, whose solves take only --method, --s-end and --ratio.
std::string zbetaAdvice(const SmolResult& r, const std::string& method) {
  switch (r.stop_cause) {
    case StopCause::Truncation:
      return method == "discrete"
                 ? "lower --s-end, or use --method sectional (its grid grows with S)"
                 : "raise --ratio (coarser sections reach larger sizes)";
    case StopCause::MassGained:
    case StopCause::SizeCeiling:
    case StopCause::NotFinite:
      return "lower --s-end";
    case StopCause::None:
      break;
  }
  return "";
}

/// The methods solveSmoluchowski dispatches to; the one sentence that names them.
void requireSmolMethod(const std::string& method) {
  requireRange(method == "sectional" || method == "discrete" || method == "mono",
               "--method must be one of sectional, discrete, mono (got '" + method + "').");
}

/// "cause; advice", or "" when the solve reached its end.
std::string stopLine(const SmolResult& r, const std::string& advice) {
  if (r.stopped_early.empty()) return "";
  return advice.empty() ? r.stopped_early : r.stopped_early + "; " + advice;
}

}  // namespace

/// Runs the chosen method; all three return moments on the same output times.
SmolResult solveSmoluchowski(const Kernel& kernel, const std::string& method,
                             const std::vector<double>& times, double s_end, int max_size,
                             double ratio, double rtol, double atol, const std::string& integrator,
                             int snapshot_max_size) {
  if (method == "discrete") {
    DiscreteOptions o;
    o.times = times;
    o.s_end = s_end;
    o.max_size = max_size;
    o.snapshot_max_size = snapshot_max_size;
    o.rtol = rtol;
    o.atol = atol;
    o.integrator = integrator;
    return solveDiscrete(kernel, o);
  }
  if (method == "sectional") {
    SectionalOptions o;
    o.times = times;
    o.s_end = s_end;
    o.ratio = ratio;
    o.rtol = rtol;
    o.atol = atol;
    return solveSectional(kernel, o);
  }
  if (method == "mono") {
    MonodisperseOptions o;
    o.times = times;
    o.s_end = s_end;
    return solveMonodisperse(kernel, o);
  }
  requireSmolMethod(method);
  throw std::logic_error("solveSmoluchowski: method '" + method + "' has no solver");
}

namespace {

/// A request that passed the checks: its kernel and output times, which the solve uses.
struct CheckedSmol {
  Kernel kernel;
  std::vector<double> times;
};

/// The one check of a SmolRequest (checkSmolRequest, solveSmol, writeSmolTable).
CheckedSmol checkedSmol(const SmolRequest& a) {
  Kernel kernel = Kernel::fromName(a.kernel, a.beta, a.K0);
  requireRange(a.method != "discrete" ||
                   (a.max_size >= 2 && a.max_size <= std::numeric_limits<int>::max()),
               "--M must lie in [2, " + std::to_string(std::numeric_limits<int>::max()) +
                   "] (got " + std::to_string(a.max_size) + ").");
  requireRange(a.ratio > 1.0, "--ratio must be > 1 (got " + common::formatReal(a.ratio) + ").");
  requireRange(a.rtol > 0.0 && a.rtol < 1.0, "--rtol must lie in (0, 1).");
  requireRange(a.atol > 0.0, "--atol must be positive.");
  requireRange(a.p > 1.0, "--p must be > 1.");
  if (kernel.gels() && a.t_end >= 1.0 / a.K0)
    throw std::invalid_argument("--t-end must be below the gel time 1/K0 = " +
                                common::formatReal(1.0 / a.K0) + " for the multiplicative kernel.");
  std::vector<double> times = outputTimes(a.t_min, a.t_end, a.per_decade);
  requireSmolMethod(a.method);
  // no option of the command sets it: the message names the field
  requireRange(a.snapshot_max_size >= 0,
               "snapshot_max_size must be >= 0 (got " + std::to_string(a.snapshot_max_size) + ").");
  return CheckedSmol{std::move(kernel), std::move(times)};
}

/// The solve of a checked request, with the local slope per sample as the table has it.
SmolSolution solveChecked(const SmolRequest& a, const CheckedSmol& c) {
  SmolSolution out;
  out.kernel_name = c.kernel.name();
  const auto wall0 = std::chrono::steady_clock::now();
  // only the discrete method uses M (its range checked above)
  const int M = static_cast<int>(
      std::clamp<long long>(a.max_size, 2, std::numeric_limits<int>::max()));
  out.result = solveSmoluchowski(c.kernel, a.method, c.times, a.s_end, M, a.ratio, a.rtol, a.atol,
                                 a.integrator, a.snapshot_max_size);
  out.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  const SmolResult& r = out.result;

  std::vector<double> t, S;
  validSeries(r, t, S);
  const LocalSlope ls = t.size() >= 2 ? localSlope(t, S, a.p) : LocalSlope{};
  out.z_local.reserve(r.samples.size());
  std::size_t j = 0;
  for (const auto& s : r.samples) {
    if (!std::isfinite(s.S))  // an overflow is an error, never a table that ends in NaN rows
      throw std::runtime_error("S(t) is no longer finite at t = " + common::formatReal(s.t) +
                               " (the solver's numbers overflowed): lower --t-end");
    double z = std::nan("");
    if (s.valid && j < ls.t.size() && ls.t[j] == s.t) z = ls.z[j++];
    out.z_local.push_back(z);
  }
  out.stopped = stopLine(r, smolAdvice(r, a.method));
  return out;
}

}  // namespace

void checkSmolRequest(const SmolRequest& request) { checkedSmol(request); }

SmolSolution solveSmol(const SmolRequest& request) {
  return solveChecked(request, checkedSmol(request));
}

void writeSmolTable(const SmolRequest& a, const common::CsvTarget& target, const LogLine& log) {
  const CheckedSmol checked = checkedSmol(a);
  target.checkWritable();
  const SmolSolution solution = solveChecked(a, checked);
  const Kernel& kernel = checked.kernel;
  const SmolResult& r = solution.result;

  common::Provenance prov(target.command_line);
  prov.add("kernel", solution.kernel_name);
  if (kernel.type() == KernelType::Beta) prov.add("beta", a.beta);
  prov.add("K0", a.K0);
  prov.add("method", a.method);
  if (a.method == "sectional") prov.add("ratio", a.ratio);
  if (a.method == "discrete") {
    prov.add("M", a.max_size);
    prov.add("integrator", a.integrator);
  }
  prov.add("rtol", a.rtol);
  prov.add("atol", a.atol);
  prov.add("initial_state", std::string("monodisperse n_1(0) = 1"));
  prov.add("local_slope_ratio_p", a.p);
  prov.add("columns",
           std::string("t: time in 1/(K0 n_1(0)); M_p = sum k^p n_k; S = M2/M1; z_local = "
                       "log[S(t)/S(t/p)]/log p; "
                       "mass_loss = (M1(0)-M1(t))/M1(0); valid = 0 where truncation lost mass"));
  common::CsvWriter w(target.path, prov,
                      {"t", "S", "M0", "M1", "M2", "z_local", "mass_loss", "valid", "max_size"},
                      target.force);
  for (std::size_t i = 0; i < r.samples.size(); ++i) {
    const MomentSample& s = r.samples[i];
    w.row({s.t, s.S, s.M0, s.M1, s.M2, solution.z_local[i], s.mass_loss, s.valid ? 1.0 : 0.0,
           s.max_size});
  }
  const std::string& stopped = solution.stopped;
  if (!stopped.empty()) w.comment("stopped early: " + stopped);
  w.close();

  if (!log) return;
  log(common::printfString(
      "smol: kernel %s%s, method %s: %zu samples to t = %.4g, S = %.6g (%.2f s, %ld steps, %ld "
      "RHS)",
      solution.kernel_name.c_str(),
      kernel.type() == KernelType::Beta ? (" beta=" + common::formatReal(a.beta)).c_str() : "",
      a.method.c_str(), r.samples.size(), r.samples.empty() ? 0.0 : r.samples.back().t,
      r.samples.empty() ? 0.0 : r.samples.back().S, solution.wall_seconds, r.stats.steps,
      r.stats.rhs_evaluations));
  if (!stopped.empty()) log("smol: stopped early: " + stopped);
  if (kernel.homogeneity() < 1.0) {
    log(common::printfString("smol: scaling prediction z = 1/(1 - lambda) = %.6f",
                             kernel.scalingExponent()));
    std::vector<double> t, S;
    validSeries(r, t, S);
    try {
      const auto az = asymptoticExponent(t, S, a.p, a.z_tolerance);
      log("smol: asymptotic " + az.describe());
    } catch (const std::invalid_argument& e) {
      log(std::string("smol: no asymptotic z: ") + e.what());
    }
  }
  if (target.path != "-") log("smol: wrote " + target.path);
}

void writeZbetaTable(const ZbetaRequest& a, const common::CsvTarget& target, const LogLine& log) {
  requireRange(a.beta_min > 0.0,
               "--beta-min must be positive (got " + common::formatReal(a.beta_min) + ").");
  requireRange(a.beta_max >= a.beta_min, "--beta-max must be >= --beta-min.");
  requireRange(a.count >= 1 && a.count <= 1000, "--count must lie in [1, 1000].");
  requireRange(a.s_end >= 1e3, "--s-end must be at least 1e3 for an asymptotic exponent.");
  requireRange(a.method == "sectional" || a.method == "discrete",
               "--method must be sectional or discrete for zbeta (got '" + a.method + "').");
  target.checkWritable();

  common::Provenance prov(target.command_line);
  prov.add("method", a.method);
  prov.add("s_end", a.s_end);
  if (a.method == "sectional") prov.add("ratio", a.ratio);
  prov.add("columns",
           std::string(
               "z_asymptotic: 1/t-extrapolated local slope of S(t) (GrowthExponent.h); "
               "z_scaling = 3 beta/(beta+3); z_local_S250 and z_local_S2500: local slopes (p = 2) "
               "where S first exceeds 250 and 2500 (the paper's 1.19 and 1.49 are such)"));
  common::CsvWriter w(target.path, prov,
                      {"beta", "z_asymptotic", "z_scaling", "difference", "converged", "S_final",
                       "z_local_S250", "z_local_S2500"},
                      target.force);
  // t_end from the scaling law S ~ t^z with a generous margin; s_end stops the solve.
  for (int i = 0; i < a.count; ++i) {
    const double beta =
        a.count == 1 ? a.beta_min : a.beta_min + (a.beta_max - a.beta_min) * i / (a.count - 1);
    const Kernel kernel = Kernel::beta(beta);
    const double z_th = kernel.scalingExponent();
    const double t_end = 100.0 * std::pow(a.s_end, 1.0 / z_th);
    const auto times = outputTimes(1e-2, t_end, 20);
    const auto r =
        solveSmoluchowski(kernel, a.method, times, a.s_end, 1 << 21, a.ratio, 1e-8, 1e-14, "adams");
    std::vector<double> t, S;
    validSeries(r, t, S);
    const auto az = asymptoticExponent(t, S, 2.0, 1e-3);
    const auto ls = localSlope(t, S, 2.0);
    auto slopeAt = [&](double s_target) {
      for (std::size_t j = 0; j < ls.t.size(); ++j) {
        // S at ls.t[j]: same index in (t, S) as the local-slope time
        const auto it = std::lower_bound(t.begin(), t.end(), ls.t[j]);
        if (S[it - t.begin()] >= s_target) return ls.z[j];
      }
      return std::nan("");
    };
    w.row({beta, az.z, z_th, az.z - z_th, az.converged ? 1.0 : 0.0, S.back(), slopeAt(250.0),
           slopeAt(2500.0)});
    if (log) {
      log(common::printfString(
          "zbeta: beta = %.4f  z = %.5f  3beta/(beta+3) = %.5f  diff = %+.1e  (S_final = %.3g%s)",
          beta, az.z, z_th, az.z - z_th, S.back(), az.converged ? "" : ", NOT converged"));
      const std::string stopped = stopLine(r, zbetaAdvice(r, a.method));
      if (!stopped.empty()) log("zbeta: stopped early: " + stopped);
    }
  }
  w.close();
  if (log && target.path != "-") log("zbeta: wrote " + target.path);
}

}  // namespace granagg::meanfield
