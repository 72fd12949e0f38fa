#include "meanfield/solvers/SectionalSolver.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>

#include "common/Csv.h"
#include "meanfield/solvers/CvodeSolver.h"

namespace granagg::meanfield {

namespace {

constexpr int MAX_SECTIONS = SECTIONAL_MAX_SECTIONS;
/// The grid grows at an output time when the largest section holding mass lies within this
/// factor of the last pivot (SectionalSolver.h)...
constexpr double GROW_TRIGGER = 100.0;
/// ...to this factor beyond that section (about 280 more sections at r = 1.05).
constexpr double GROW_TARGET = 1e6;
/// Mass (relative to M1(0), in units of mass_loss_tolerance) that may escape during one output
/// interval before the interval is integrated again on a larger grid.
constexpr double ESCAPE_REDO_FRACTION = 1e-3;

/// Index of the section pair (j, k), j <= k, in the upper-triangular pair table of I sections.
inline size_t rowStart(size_t j, size_t I) {
  return j * I - j * (j - 1) / 2 - j;
}  // + k gives (j, k)

/// Splits an aggregate of size v between the two pivots around it (Kumar & Ramkrishna 1996, eq.
/// 27): returns the lower pivot t with x_t <= v <= x_{t+1} and the share b that goes to x_{t+1}; 1
/// - b goes to x_t. Then (1 - b) + b = 1 (number) and (1 - b) x_t + b x_{t+1} = v (mass). t = -1
/// when v lies beyond the last pivot.
void splitSize(const std::vector<double>& x, double v, int& t, double& b) {
  const int I = static_cast<int>(x.size());
  if (v > x.back()) {
    t = -1;
    b = 0.0;
    return;
  }
  // first pivot > v, minus one: x_t <= v < x_{t+1}; v == x.back() goes to (I-2, b = 1)
  int hi = static_cast<int>(std::upper_bound(x.begin(), x.end(), v) - x.begin());
  t = std::min(hi - 1, I - 2);
  b = (v - x[t]) / (x[t + 1] - x[t]);
  // exact pivots (all sums in the integer region) give b == 0 or 1 exactly
  if (b < 0.0) b = 0.0;
  if (b > 1.0) b = 1.0;
}

/// Pair table and right-hand side of the fixed-pivot equations.
class FixedPivotRhs {
 public:
  FixedPivotRhs(const Kernel& kernel, std::vector<double> pivots, double cutoff_mass)
      : m_x(std::move(pivots)), m_I(m_x.size()), m_cutoff(cutoff_mass) {
    const size_t pairs = m_I * (m_I + 1) / 2;
    m_c.resize(pairs);
    m_b.resize(pairs);
    m_t.resize(pairs);
    m_escape.assign(m_I, m_I);
    m_loss.assign(m_I, 0.0);
    m_gain_lo.assign(m_I, 0.0);
    m_gain_hi.assign(m_I, 0.0);
    for (size_t j = 0; j < m_I; ++j) {
      const size_t row = rowStart(j, m_I);
      for (size_t k = j; k < m_I; ++k) {
        const size_t idx = row + k;
        // collision rate per N_j N_k: K for j < k, K/2 for j == k (each unordered pair once)
        m_c[idx] = kernel(m_x[j], m_x[k]) * (j == k ? 0.5 : 1.0);
        const double v = m_x[j] + m_x[k];
        int t;
        double b;
        splitSize(m_x, v, t, b);
        m_t[idx] = t;
        m_b[idx] = t >= 0 ? b : v;  // escaped pairs keep their mass v in the b slot
        if (t < 0 && m_escape[j] == m_I) m_escape[j] = k;  // x_j + x_k increases with k
      }
    }
  }

  size_t sections() const { return m_I; }
  const std::vector<double>& pivots() const { return m_x; }

  /// Range [lo, hi] of sections whose mass |N_i| x_i exceeds the cutoff (lo > hi when none).
  void activeRange(const double* N, size_t& lo, size_t& hi) const {
    lo = 0;
    while (lo < m_I && !(std::fabs(N[lo]) * m_x[lo] > m_cutoff)) ++lo;
    hi = m_I;
    while (hi > lo && !(std::fabs(N[hi - 1]) * m_x[hi - 1] > m_cutoff)) --hi;
    hi = hi == 0 ? 0 : hi - 1;
    if (lo >= m_I) hi = 0;
  }

  /// y = (N_0..N_{I-1}, escaped mass); dydt likewise.
  void operator()(const double* y, double* dydt) {
    std::fill(dydt, dydt + m_I + 1, 0.0);
    size_t lo, hi;
    activeRange(y, lo, hi);
    if (lo >= m_I) return;
    // Loss and the two gain shares go to separate arrays: within a row every k, and almost every
    // target t, is distinct, so successive iterations do not wait on each other's stores.
    double* loss = m_loss.data();
    double* gain_lo = m_gain_lo.data();
    double* gain_hi = m_gain_hi.data();
    // largest target of the pairs within [lo, hi]: that of (hi, hi), as x_j + x_k grows with j and
    // k
    const int32_t t_hh = m_t[rowStart(hi, m_I) + hi];
    const size_t top = t_hh >= 0 ? static_cast<size_t>(t_hh) : m_I - 2;
    std::fill(loss + lo, loss + hi + 1, 0.0);
    std::fill(gain_lo, gain_lo + top + 1, 0.0);
    std::fill(gain_hi, gain_hi + top + 1, 0.0);
    const double* c = m_c.data();
    const double* bw = m_b.data();
    const int32_t* tg = m_t.data();
    double escaped = 0.0;
    for (size_t j = lo; j <= hi; ++j) {
      const double Nj = y[j];
      if (Nj == 0.0) continue;
      const size_t row = rowStart(j, m_I);
      double loss_j = 0.0;
      // pairs that stay on the grid (k < m_escape[j]): no branch in the hot loop
      const size_t k_stay = std::min(hi + 1, m_escape[j]);
      for (size_t k = j; k < k_stay; ++k) {
        const size_t idx = row + k;
        const double R = c[idx] * Nj * y[k];  // collisions per unit time and volume
        loss_j += R;
        loss[k] += R;
        const double bR = bw[idx] * R;
        const int32_t t = tg[idx];
        gain_lo[t] += R - bR;  // to pivot t
        gain_hi[t] += bR;      // to pivot t + 1
      }
      for (size_t k = std::max(j, k_stay); k <= hi; ++k) {
        const size_t idx = row + k;
        const double R = c[idx] * Nj * y[k];
        loss_j += R;
        loss[k] += R;
        escaped += bw[idx] * R;  // mass x_j + x_k leaves the grid
      }
      loss[j] += loss_j;  // with loss[k] += R at k == j, the j == k pair removes 2 R = K N_j^2
    }
    for (size_t i = lo; i <= hi; ++i) dydt[i] -= loss[i];
    for (size_t t = 0; t <= top; ++t) {
      dydt[t] += gain_lo[t];
      dydt[t + 1] += gain_hi[t];
    }
    dydt[m_I] = escaped;
  }

 private:
  std::vector<double> m_x;
  size_t m_I;
  double m_cutoff;
  std::vector<double> m_c;   // (1 - delta_jk / 2) K(x_j, x_k)
  std::vector<double> m_b;   // share to the upper target pivot (or v for escaped pairs)
  std::vector<int32_t> m_t;  // lower target pivot, -1 if the aggregate leaves the grid
  std::vector<size_t> m_escape;
  std::vector<double> m_loss, m_gain_lo, m_gain_hi;  // scratch of operator()  // first k >= j whose
                                                     // pair (j, k) leaves the grid (I if none)
};

void validate(const SectionalOptions& o) {
  using common::formatReal;
  if (o.times.empty())
    throw std::invalid_argument(
        "sectional solver requires at least one output time (times is empty).");
  for (size_t i = 0; i < o.times.size(); ++i) {
    if (!(o.times[i] > 0.0) || !std::isfinite(o.times[i]))
      throw std::invalid_argument("sectional times must be positive and finite (got " +
                                  formatReal(o.times[i]) + ").");
    if (i > 0 && !(o.times[i] > o.times[i - 1]))
      throw std::invalid_argument("sectional times must increase strictly (got " +
                                  formatReal(o.times[i - 1]) + " then " + formatReal(o.times[i]) +
                                  ").");
  }
  if (!(o.rtol > 0.0) || !std::isfinite(o.rtol))
    throw std::invalid_argument("sectional rtol must be positive and finite (got " +
                                formatReal(o.rtol) + ").");
  if (!(o.atol > 0.0) || !std::isfinite(o.atol))
    throw std::invalid_argument("sectional atol must be positive and finite (got " +
                                formatReal(o.atol) + ").");
  if (!(o.s_end > 0.0))
    throw std::invalid_argument("sectional s_end must be positive (got " + formatReal(o.s_end) +
                                ").");
  if (!(o.mass_loss_tolerance >= 0.0))
    throw std::invalid_argument("sectional mass_loss_tolerance must not be negative (got " +
                                formatReal(o.mass_loss_tolerance) + ").");
  if (!(o.section_cutoff >= 0.0) || !(o.section_cutoff < 1e-6))
    throw std::invalid_argument("sectional section_cutoff must lie in [0, 1e-6) (got " +
                                formatReal(o.section_cutoff) + ").");
  if (!(o.max_size >= 2.0))
    throw std::invalid_argument("sectional max_size must be >= 2 (got " + formatReal(o.max_size) +
                                ").");
  if (!(o.initial_size >= 2.0 && o.initial_size <= SECTIONAL_MAX_PIVOT))
    throw std::invalid_argument("sectional initial_size must lie in [2, " +
                                formatReal(SECTIONAL_MAX_PIVOT) + "] (got " +
                                formatReal(o.initial_size) + ").");
  CvodeSolver::parseMethod(o.integrator);  // throws for an unknown name
}

/// The pivots of the file comment up to the first >= top, or up to `max_sections` pivots. Every
/// grid of one ratio is a prefix of the grids with a larger top, so a grown grid keeps its pivots.
SectionalGrid buildGrid(double ratio, double top, size_t max_sections) {
  SectionalGrid g;
  // integers 1..m with m the first integer whose geometric step m (r - 1) is at least one
  const int m = std::max(1, static_cast<int>(std::ceil(1.0 / (ratio - 1.0) - 1e-12)));
  for (int k = 1; k <= m && g.pivots.size() < max_sections; ++k) {
    g.pivots.push_back(k);
    if (k >= top) break;
  }
  g.integer_pivots = static_cast<int>(g.pivots.size());
  while (g.pivots.back() < top && g.pivots.size() < max_sections)
    g.pivots.push_back(g.pivots.back() * ratio);
  return g;
}

/// Throws std::invalid_argument unless ratio > 1 leaves room for the integer pivots.
void checkRatio(double ratio) {
  using common::formatReal;
  if (!(ratio > 1.0) || !std::isfinite(ratio))
    throw std::invalid_argument("sectional ratio must be a finite number > 1 (got " +
                                formatReal(ratio) + ").");
  if (std::ceil(1.0 / (ratio - 1.0) - 1e-12) > MAX_SECTIONS)
    throw std::invalid_argument("sectional ratio " + formatReal(ratio) +
                                " is too close to 1: more than " + std::to_string(MAX_SECTIONS) +
                                " integer pivots.");
}

}  // namespace

SectionalGrid makeSectionalGrid(double ratio, double max_size) {
  using common::formatReal;
  checkRatio(ratio);
  if (!(max_size >= 2.0 && max_size <= SECTIONAL_MAX_PIVOT))
    throw std::invalid_argument("sectional max_size must lie in [2, " +
                                formatReal(SECTIONAL_MAX_PIVOT) + "] (got " + formatReal(max_size) +
                                ").");
  SectionalGrid g = buildGrid(ratio, max_size, MAX_SECTIONS + 1);
  if (g.pivots.size() > static_cast<size_t>(MAX_SECTIONS))
    throw std::invalid_argument("sectional grid with ratio " + formatReal(ratio) + " up to size " +
                                formatReal(max_size) + " needs more than " +
                                std::to_string(MAX_SECTIONS) + " sections: raise the ratio.");
  return g;
}

namespace {

/// The initial state on the pivots, with the escaped mass last (zero): n_k for k = 1..len split
/// onto the two pivots around k, conserving number and mass; without `initial`, n_1 = 1.
std::vector<double> initialSections(const SectionalGrid& grid, const std::vector<double>* initial,
                                    double max_size) {
  using common::formatReal;
  std::vector<double> y(grid.pivots.size() + 1, 0.0);
  if (!initial) {
    y[0] = 1.0;  // monodisperse n_1 = 1
    return y;
  }
  if (initial->empty()) throw std::invalid_argument("sectional initial distribution is empty.");
  for (size_t k = 0; k < initial->size(); ++k) {
    const double n = (*initial)[k];
    if (!(n >= 0.0) || !std::isfinite(n))
      throw std::invalid_argument("sectional initial n_k must be finite and >= 0 (got " +
                                  formatReal(n) + " at k = " + std::to_string(k + 1) + ").");
    if (n == 0.0) continue;
    int t;
    double b;
    splitSize(grid.pivots, static_cast<double>(k + 1), t, b);
    if (t < 0)
      throw std::invalid_argument("sectional initial distribution reaches size " +
                                  std::to_string(k + 1) + ", beyond max_size " +
                                  formatReal(max_size) + ".");
    y[t] += (1.0 - b) * n;
    y[t + 1] += b * n;
  }
  return y;
}

/// Gelling kernels: the solution exists only before t_gel = 1 / (K0 M2(0)) (Ziff 1980 for
/// K = K0 i j); other gelling kernels have no known gel time and are refused.
void checkGelTime(const Kernel& kernel, double t_last, double M2_0) {
  using common::formatReal;
  if (kernel.type() == KernelType::Multiplicative) {
    const double t_gel = 1.0 / (kernel.K0() * M2_0);
    if (t_last >= t_gel)
      throw std::invalid_argument(
          "sectional times must stay before the gel time 1/(K0 M2(0)) = " + formatReal(t_gel) +
          " of the multiplicative kernel (got " + formatReal(t_last) + ").");
  } else if (kernel.gels()) {
    throw std::invalid_argument("sectional solver: kernel '" + kernel.name() +
                                "' gels; no gel time known.");
  }
}

/// The moments of the sections y (pivots x) at time t, with the mass lost since M1(0) = M1_0.
MomentSample sectionMoments(double t, const std::vector<double>& x, const std::vector<double>& y,
                            double M1_0, double mass_loss_tolerance) {
  MomentSample s;
  s.t = t;
  for (size_t i = 0; i < x.size(); ++i) {
    const double N = y[i];
    s.M0 += N;
    s.M1 += x[i] * N;
    s.M2 += x[i] * x[i] * N;
  }
  s.S = s.M2 / s.M1;
  s.mass_loss = (M1_0 - s.M1) / M1_0;
  s.valid = std::fabs(s.mass_loss) <= mass_loss_tolerance;
  return s;
}

/// The stop of a run whose sample `s` lost (or gained) more mass than allowed: its cause and the
/// message that names the grid's limit (last pivot `x_last`).
void stopOnMassLoss(const MomentSample& s, const SectionalOptions& options, double x_last,
                    SmolResult& result) {
  using common::formatReal;
  const std::string head = "mass loss " + formatReal(s.mass_loss) + " at t = " + formatReal(s.t) +
                           " exceeds mass_loss_tolerance " +
                           formatReal(options.mass_loss_tolerance);
  if (s.mass_loss < 0.0) {
    result.stop_cause = StopCause::MassGained;
    result.stopped_early = head + ": mass was gained, an integration error";
    return;
  }
  result.stop_cause = StopCause::Truncation;
  std::string limit = "the grid holds its most sections, " + std::to_string(MAX_SECTIONS) +
                      ", at ratio " + formatReal(options.ratio);
  if (!options.grow) {
    limit = "the grid is fixed";
  } else if (x_last >= options.max_size) {
    limit = "the largest size allowed, max_size " + formatReal(options.max_size);
  } else if (x_last >= SECTIONAL_MAX_PIVOT) {
    result.stop_cause = StopCause::SizeCeiling;
    limit = "no grid goes beyond " + formatReal(SECTIONAL_MAX_PIVOT);
  }
  result.stopped_early = head + ": aggregates left the grid beyond its last pivot " +
                         formatReal(x_last) + " (" + limit + ")";
}

}  // namespace

SmolResult solveSectional(const Kernel& kernel, const SectionalOptions& options,
                          const std::vector<double>* initial) {
  const auto wall_start = std::chrono::steady_clock::now();
  validate(options);
  // The first grid also covers the initial distribution; beyond max_size it is refused below.
  double first_top = std::min(options.initial_size, options.max_size);
  if (initial) first_top = std::min(options.max_size, std::max(first_top, double(initial->size())));
  checkRatio(options.ratio);
  // A growing grid may start within the section budget and stop growing there; a fixed grid
  // that does not fit is refused.
  SectionalGrid grid = options.grow ? buildGrid(options.ratio, first_top, MAX_SECTIONS)
                                    : makeSectionalGrid(options.ratio, first_top);

  const std::vector<double> y = initialSections(grid, initial, options.max_size);
  double M1_0 = 0.0, M2_0 = 0.0;
  for (size_t i = 0; i < grid.pivots.size(); ++i) {
    M1_0 += grid.pivots[i] * y[i];
    M2_0 += grid.pivots[i] * grid.pivots[i] * y[i];
  }
  if (!(M1_0 > 0.0)) throw std::invalid_argument("sectional initial distribution has no mass.");
  checkGelTime(kernel, options.times.back(), M2_0);

  SmolResult result;
  result.method = "sectional";
  CvodeSolver::Options co;
  co.method = CvodeSolver::parseMethod(options.integrator);
  co.rtol = options.rtol;
  co.max_steps = 1000000;
  std::unique_ptr<FixedPivotRhs> rhs;
  std::unique_ptr<CvodeSolver> cvode;
  // The right-hand side and CVODE on the current grid, from y(t0) = y0.
  auto startSolver = [&](double t0, const std::vector<double>& y0) {
    if (cvode) addStats(result.stats, cvode->stats());
    cvode.reset();
    const std::vector<double>& x = grid.pivots;
    const size_t I = x.size();
    rhs = std::make_unique<FixedPivotRhs>(kernel, x, options.section_cutoff * M1_0);
    co.atol_vector.resize(I + 1);
    for (size_t i = 0; i < I; ++i) co.atol_vector[i] = options.atol * M1_0 / x[i];  // by mass
    co.atol_vector[I] = options.atol * M1_0;                                        // escaped
    FixedPivotRhs* r = rhs.get();
    cvode = std::make_unique<CvodeSolver>(
        static_cast<int>(I + 1), [r](double, const double* yy, double* dd) { (*r)(yy, dd); }, co,
        t0, y0.data());
    cvode->setStopTime(options.times.back());  // never past the last output (gel time, blow-up)
  };
  // Appends pivots up to min(top, max_size) within the section budget, and zero sections to
  // `state` (the escaped mass stays last). False when the grid cannot grow.
  auto growGrid = [&](double top, std::vector<double>& state) {
    const size_t I_old = grid.pivots.size();
    const double ceiling = std::min(options.max_size, SECTIONAL_MAX_PIVOT);
    if (!options.grow || grid.pivots.back() >= ceiling) return false;
    grid = buildGrid(options.ratio, std::min(top, ceiling), MAX_SECTIONS);
    const size_t I = grid.pivots.size();
    if (I == I_old) return false;
    const double escaped = state[I_old];
    state.resize(I + 1, 0.0);
    state[I_old] = 0.0;
    state[I] = escaped;
    ++result.stats.resizes;
    return true;
  };
  startSolver(0.0, y);

  double t_prev = 0.0;
  std::vector<double> y_prev = y;  // the state at t_prev, on the current grid
  std::vector<double> yout;
  for (size_t k = 0; k < options.times.size();) {
    const double tout = options.times[k];
    const std::vector<double>& x = grid.pivots;
    const size_t I = x.size();
    yout.resize(I + 1);
    cvode->advance(tout, yout.data());
    // Mass left the grid during this interval: integrate it again from t_prev on a larger grid.
    if (yout[I] - y_prev[I] > ESCAPE_REDO_FRACTION * options.mass_loss_tolerance * M1_0 &&
        growGrid(GROW_TARGET * x.back(), y_prev)) {
      startSolver(t_prev, y_prev);
      continue;
    }
    MomentSample s = sectionMoments(tout, x, yout, M1_0, options.mass_loss_tolerance);
    size_t lo, hi;
    rhs->activeRange(yout.data(), lo, hi);
    s.max_size = lo < I ? x[hi] : 0.0;
    result.samples.push_back(s);
    if (options.snapshots) {
      Snapshot snap;
      snap.t = tout;
      snap.size = x;
      snap.n.assign(yout.begin(), yout.begin() + static_cast<long>(I));
      result.snapshots.push_back(std::move(snap));
    }
    if (!s.valid && options.stop_on_truncation) {
      stopOnMassLoss(s, options, x.back(), result);
      break;
    }
    if (s.S >= options.s_end) break;
    // The distribution nears the grid's end: more pivots before the next interval.
    if (k + 1 < options.times.size() && lo < I && x[hi] * GROW_TRIGGER > x.back() &&
        growGrid(GROW_TARGET * x[hi], yout))
      startSolver(tout, yout);
    y_prev = yout;
    t_prev = tout;
    ++k;
  }

  addStats(result.stats, cvode->stats());
  result.stats.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  return result;
}

}  // namespace granagg::meanfield
