#include "meanfield/solvers/DiscreteSolver.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>

#include "common/Csv.h"
#include "meanfield/solvers/CvodeSolver.h"
#include "meanfield/solvers/SmoluchowskiRhs.h"

namespace granagg::meanfield {

namespace {

void validate(const DiscreteOptions& o) {
  if (o.times.empty())
    throw std::invalid_argument("the discrete solver needs at least one output time.");
  for (std::size_t i = 0; i < o.times.size(); ++i) {
    if (!(o.times[i] > 0.0) || !std::isfinite(o.times[i]))
      throw std::invalid_argument("output times must be positive and finite (got " +
                                  common::formatReal(o.times[i]) + ").");
    if (i && !(o.times[i] > o.times[i - 1]))
      throw std::invalid_argument("output times must increase strictly.");
  }
  if (o.max_size < 2)
    throw std::invalid_argument("the largest size M must be at least 2 (got " +
                                std::to_string(o.max_size) + ").");
  if (o.initial_size < 0) throw std::invalid_argument("initial_size must be >= 0.");
  if (!(o.range_factor >= 4.0))
    throw std::invalid_argument("range_factor must be at least 4 (got " +
                                common::formatReal(o.range_factor) + ").");
  if (!(o.rtol > 0.0 && o.rtol < 1.0)) throw std::invalid_argument("rtol must lie in (0, 1).");
  if (!(o.atol > 0.0)) throw std::invalid_argument("atol must be positive.");
  if (!(o.mass_loss_tolerance > 0.0))
    throw std::invalid_argument("mass_loss_tolerance must be positive.");
  if (o.snapshot_max_size < 0) throw std::invalid_argument("snapshot_max_size must be >= 0.");
}

struct Moments {
  double M0 = 0.0, M1 = 0.0, M2 = 0.0;
};
Moments moments(const double* n, int M) {
  Moments m;
  for (int k = 1; k <= M; ++k) {
    const double v = n[k - 1];
    m.M0 += v;
    m.M1 += k * v;
    m.M2 += double(k) * k * v;
  }
  return m;
}

/// The initial n_k (k = 1..len; n_1 = 1 without `initial`), checked against the largest size.
std::vector<double> initialDistribution(const std::vector<double>* initial, int max_size) {
  std::vector<double> n0 = initial ? *initial : std::vector<double>{1.0};
  if (n0.empty()) throw std::invalid_argument("the initial distribution is empty.");
  for (double v : n0)
    if (!(v >= 0.0) || !std::isfinite(v))
      throw std::invalid_argument("initial number densities must be >= 0 and finite.");
  if (static_cast<int>(n0.size()) > max_size)
    throw std::invalid_argument("the initial distribution has sizes up to " +
                                std::to_string(n0.size()) +
                                ", beyond the largest size M = " + std::to_string(max_size) + ".");
  return n0;
}

/// The moments of n_1..n_M at time t, with the mass lost since M1(0) = M1_0.
MomentSample discreteMoments(double t, const double* n, int M, double M1_0,
                             double mass_loss_tolerance) {
  const Moments m = moments(n, M);
  MomentSample s;
  s.t = t;
  s.M0 = m.M0;
  s.M1 = m.M1;
  s.M2 = m.M2;
  s.S = m.M2 / m.M1;
  s.mass_loss = (M1_0 - m.M1) / M1_0;
  s.valid = std::fabs(s.mass_loss) <= mass_loss_tolerance;
  s.max_size = M;
  return s;
}

/// n_k for k = 1..min(max_size, M) at time t.
Snapshot snapshotUpTo(double t, const std::vector<double>& n, int M, int max_size) {
  Snapshot snap;
  snap.t = t;
  const int kmax = std::min(max_size, M);
  for (int k = 1; k <= kmax; ++k) {
    snap.size.push_back(k);
    snap.n.push_back(n[k - 1]);
  }
  return snap;
}

/// The stop of a run whose sample `s` lost (or gained) more mass than allowed, over M sizes.
void stopOnMassLoss(const MomentSample& s, int M, const DiscreteOptions& o, SmolResult& res) {
  const std::string head = "relative mass loss " + common::formatReal(s.mass_loss) +
                           " at t = " + common::formatReal(s.t) + " exceeds the tolerance " +
                           common::formatReal(o.mass_loss_tolerance) +
                           " (S = " + common::formatReal(s.S) + "): ";
  res.stop_cause = s.mass_loss > 0.0 ? StopCause::Truncation : StopCause::MassGained;
  res.stopped_early =
      s.mass_loss > 0.0
          ? head + "the size range M = " + std::to_string(M) +
                (M >= o.max_size ? " (the largest allowed)" : "") + " truncates the distribution"
          : head + "mass was gained, an integration error (Adams conserves mass to round-off)";
}

}  // namespace

SmolResult solveDiscrete(const Kernel& kernel, const DiscreteOptions& o,
                         const std::vector<double>* initial) {
  validate(o);
  const auto wall0 = std::chrono::steady_clock::now();
  const std::vector<double> n0 = initialDistribution(initial, o.max_size);
  const double M1_0 = moments(n0.data(), static_cast<int>(n0.size())).M1;
  if (!(M1_0 > 0.0)) throw std::invalid_argument("the initial distribution has no mass.");

  int M = o.max_size;
  if (o.grow) {
    const int want =
        o.initial_size > 0 ? o.initial_size : std::max(128, 4 * static_cast<int>(n0.size()));
    M = std::min(o.max_size, std::max(fftFriendlySize(want), static_cast<int>(n0.size())));
  }

  CvodeSolver::Options copt;
  copt.method = CvodeSolver::parseMethod(o.integrator);
  copt.rtol = o.rtol;
  copt.atol = o.atol * M1_0;

  SmolResult res;
  res.method = "discrete";
  std::vector<double> y(M, 0.0);
  std::copy(n0.begin(), n0.end(), y.begin());
  auto rhs = std::make_unique<SmoluchowskiRhs>(kernel, M);
  auto makeSolver = [&](double t0) {
    SmoluchowskiRhs* r = rhs.get();
    if (copt.method == CvodeSolver::Method::BdfGmres)
      copt.jacobian_diagonal = [r](double, const double* n, double* jd) {
        r->jacobianDiagonal(n, jd);
      };
    return std::make_unique<CvodeSolver>(
        M, [r](double, const double* n, double* f) { r->evaluate(n, f); }, copt, t0, y.data());
  };
  auto solver = makeSolver(0.0);

  const double t_final = o.times.back();
  std::vector<double> buf;
  std::size_t iout = 0;
  bool done = false;
  while (!done && iout < o.times.size()) {
    const double tcur = solver->step(t_final);
    // samples inside the step just taken, from CVODE's interpolating polynomial
    while (iout < o.times.size() && o.times[iout] <= tcur) {
      const double t = o.times[iout++];
      buf.resize(M);
      solver->interpolate(t, buf.data());
      const MomentSample s = discreteMoments(t, buf.data(), M, M1_0, o.mass_loss_tolerance);
      res.samples.push_back(s);
      if (o.snapshot_max_size > 0)
        res.snapshots.push_back(snapshotUpTo(t, buf, M, o.snapshot_max_size));
      if (o.on_sample) o.on_sample(s);
      if (!s.valid && o.stop_on_truncation) {
        stopOnMassLoss(s, M, o, res);
        done = true;
        break;
      }
      if (s.S >= o.s_end) {
        done = true;
        break;
      }
    }
    if (done || !o.grow || M >= o.max_size) continue;
    // enlarge the active range when S has outgrown it (checked after every internal step)
    const double* st = solver->state();
    const Moments m = moments(st, M);
    const double S = m.M2 / m.M1;
    if (S * o.range_factor > M) {
      const int newM = std::min(
          o.max_size, fftFriendlySize(static_cast<int>(std::ceil(2.0 * o.range_factor * S))));
      y.assign(newM, 0.0);
      std::copy(st, st + M, y.begin());
      addStats(res.stats, solver->stats());
      solver.reset();
      M = newM;
      rhs = std::make_unique<SmoluchowskiRhs>(kernel, M);
      solver = makeSolver(tcur);
      ++res.stats.resizes;
    }
  }
  addStats(res.stats, solver->stats());
  res.stats.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  return res;
}

}  // namespace granagg::meanfield
