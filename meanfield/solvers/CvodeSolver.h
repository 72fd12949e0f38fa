#pragma once
/// \file CvodeSolver.h
/// A small RAII wrapper around SUNDIALS CVODE (6.4) for y' = f(t, y) with y in R^N, shared by the
/// Smoluchowski solvers (STYLE.md, meanfield: "CvodeSolver owns context, vectors, matrix and linear
/// solver (RAII, freed in reverse order), as Cantera does").
///
/// Methods (SUNDIALS CVODE user guide, sections 2.1 and 2.2):
/// - Adams: Adams-Moulton (orders 1-12) with fixed-point (functional) iteration. Non-stiff; no
///   Jacobian. Every iterate is a linear combination of y and f values, so linear invariants of the
///   ODE (e.g. total mass of a conservative Smoluchowski system) are preserved to round-off.
/// - BdfGmres: BDF (orders 1-5) with Newton iteration and matrix-free GMRES (difference-quotient
///   Jacobian-vector products, no preconditioner). Stiff, O(N) memory.
/// - BdfDense: BDF with Newton and a dense direct solver (difference-quotient Jacobian, O(N^2)
///   memory, O(N^3) per factorisation: N up to a few thousand).
///
/// Errors: the right-hand side is called through an extern "C" trampoline that catches any C++
/// exception, stores it and returns -1 (unrecoverable) — or 1 (recoverable: CVODE retries with a
/// smaller step) for CvodeRecoverableError; the exception is rethrown once CVode returns
/// (Cantera #119, deal.II's callback policy). CVODE failures throw std::runtime_error whose message
/// carries CVodeGetReturnFlagName(flag) and CVODE's own error text. SUNDIALS never prints to
/// stderr.
///
/// Version-specific calls (SUNContext_Create(NULL, &ctx) of SUNDIALS 6) live in CvodeSolver.cpp
/// only.
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "meanfield/solvers/SmolResult.h"

namespace granagg::meanfield {

/// Throw this from a right-hand side to ask CVODE to retry with a smaller step (the trampoline
/// returns 1 instead of -1). If CVODE gives up, this exception is rethrown.
class CvodeRecoverableError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class CvodeSolver {
 public:
  /// Right-hand side: dydt[0..N) = f(t, y[0..N)). Time and state in the caller's units.
  using Rhs = std::function<void(double t, const double* y, double* dydt)>;

  enum class Method { Adams, BdfGmres, BdfDense };

  struct Options {
    Method method = Method::Adams;
    /// Relative tolerance (dimensionless), > 0.
    double rtol = 1e-8;
    /// Scalar absolute tolerance (units of y), > 0. Ignored when atol_vector is not empty.
    double atol = 1e-14;
    /// Per-component absolute tolerances (length N, all > 0), optional.
    std::vector<double> atol_vector;
    /// Largest number of internal steps per call of advance() (CVodeSetMaxNumSteps); > 0.
    long max_steps = 1000000;
    /// Largest method order; 0 keeps CVODE's default (12 for Adams, 5 for BDF).
    int max_order = 0;
    /// Largest step size (time units); 0 means unbounded.
    double max_step = 0.0;
    /// First step size (time units); 0 lets CVODE estimate it.
    double initial_step = 0.0;
    /// Krylov subspace dimension for BdfGmres; 0 keeps the SUNDIALS default (5).
    int krylov_dim = 0;
    /// Anderson acceleration vectors for the Adams fixed-point iteration (0: plain iteration).
    int anderson_depth = 0;
    /// BdfGmres only, optional: the diagonal of the Jacobian df/dy at (t, y), written to jdiag
    /// (length N). When given, GMRES is left-preconditioned with P = I - gamma diag(J) (CVODE
    /// guide, "Preconditioning"); recomputed only when CVODE asks for a fresh Jacobian (jok false).
    std::function<void(double t, const double* y, double* jdiag)> jacobian_diagonal;
  };

  /// Cost counters since construction (summed across reset() calls).
  struct Stats {
    long steps = 0;
    long rhs_evaluations = 0;    ///< including those for difference-quotient Jacobians
    long linear_iterations = 0;  ///< GMRES iterations (BdfGmres)
    long nonlinear_iterations = 0;
    long nonlinear_failures = 0;  ///< nonlinear-solver convergence failures
    long error_test_failures = 0;
    double last_step = 0.0;  ///< size of the last internal step (time units)
  };

  /// Sets up CVODE for N >= 1 unknowns starting from y(t0) = y0[0..N). Throws
  /// std::invalid_argument for bad sizes or tolerances, std::runtime_error if CVODE setup fails.
  CvodeSolver(int n, Rhs rhs, const Options& options, double t0, const double* y0);
  ~CvodeSolver();
  CvodeSolver(const CvodeSolver&) = delete;
  CvodeSolver& operator=(const CvodeSolver&) = delete;

  /// Restarts the integration from y(t0) = y0 (CVodeReInit: the multistep history is dropped;
  /// statistics keep accumulating).
  void reset(double t0, const double* y0);

  /// Integrates to tout (CV_NORMAL: CVODE may step past tout and interpolates back) and writes
  /// y(tout) to y (length N, may be null). Returns tout.
  double advance(double tout, double* y = nullptr);

  /// Takes one internal step towards tout (CV_ONE_STEP) and returns the time reached. The state
  /// there is state(); values between the previous and the current time come from interpolate().
  double step(double tout);

  /// Dense output (CVodeGetDky): the k-th time derivative of the interpolating polynomial at t,
  /// which must lie in [time() - lastStep(), time()]. Writes N values to out.
  void interpolate(double t, double* out, int k = 0) const;

  /// Forbids stepping past tstop (CVodeSetStopTime); cleared by CVODE once reached.
  void setStopTime(double tstop);
  /// Changes the largest step size (0: unbounded).
  void setMaxStep(double hmax);

  /// Current internal time of the integrator (time units).
  double time() const;
  /// State returned by the last advance() or step() (the initial state before any), at
  /// stateTime() (length N, owned by the solver; overwritten by the next advance/step/reset).
  const double* state() const;
  /// Time of state(): tout after advance(), the internal time after step().
  double stateTime() const;
  int size() const { return m_n; }
  Stats stats() const;
  /// Name of the method: "adams", "bdf-gmres" or "bdf-dense".
  std::string methodName() const;

  /// Parses "adams", "bdf" / "bdf-gmres" or "bdf-dense"; throws std::invalid_argument otherwise.
  static Method parseMethod(const std::string& name);

 private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
  int m_n;
};

/// Adds the cost of one CVODE instance to a solve's totals (a solve may use several: the
/// discrete solver after each resize, the sectional one after each grid growth).
inline void addStats(SolveStats& acc, const CvodeSolver::Stats& s) {
  acc.steps += s.steps;
  acc.rhs_evaluations += s.rhs_evaluations;
  acc.linear_iterations += s.linear_iterations;
  acc.nonlinear_failures += s.nonlinear_failures;
  acc.error_test_failures += s.error_test_failures;
}

}  // namespace granagg::meanfield
