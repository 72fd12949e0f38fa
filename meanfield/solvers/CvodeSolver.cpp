#include "meanfield/solvers/CvodeSolver.h"

#include <cvode/cvode.h>
#include <cvode/cvode_ls.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunlinsol/sunlinsol_spgmr.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <exception>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/Csv.h"

namespace granagg::meanfield {

namespace {
/// What the extern "C" callbacks see through CVODE's user_data pointer.
struct CallbackData {
  CvodeSolver::Rhs rhs;
  std::exception_ptr error;  // exception caught in the trampoline, rethrown after CVode returns
  bool recoverable = false;  // the stored exception was a CvodeRecoverableError
  std::string last_message;  // CVODE's last error text (its error handler writes here)
  // diagonal preconditioner P = I - gamma diag(J) (BdfGmres with Options::jacobian_diagonal)
  std::function<void(double, const double*, double*)> jacobian_diagonal;
  std::vector<double> jdiag;
};
}  // namespace

struct CvodeSolver::Impl {
  CallbackData cb;
  Method method = Method::Adams;
  int n = 0;
  SUNContext ctx = nullptr;
  N_Vector y = nullptr;
  N_Vector abstol = nullptr;
  N_Vector work = nullptr;  // scratch for dense output
  SUNMatrix A = nullptr;
  SUNLinearSolver LS = nullptr;
  SUNNonlinearSolver NLS = nullptr;
  void* mem = nullptr;
  double t_last = 0.0;  // time of the state held in y
  Stats accumulated;    // counters of integrations before the last reset()

  ~Impl() {
    // Reverse order of creation (CVODE memory references LS, NLS, A and the vectors).
    if (mem) CVodeFree(&mem);
    if (LS) SUNLinSolFree(LS);
    if (NLS) SUNNonlinSolFree(NLS);
    if (A) SUNMatDestroy(A);
    if (work) N_VDestroy(work);
    if (abstol) N_VDestroy(abstol);
    if (y) N_VDestroy(y);
    if (ctx) SUNContext_Free(&ctx);
  }

  Stats current() const {
    Stats s;
    if (!mem) return s;
    CVodeGetNumSteps(mem, &s.steps);
    CVodeGetNumRhsEvals(mem, &s.rhs_evaluations);
    CVodeGetNumNonlinSolvIters(mem, &s.nonlinear_iterations);
    CVodeGetNumNonlinSolvConvFails(mem, &s.nonlinear_failures);
    CVodeGetNumErrTestFails(mem, &s.error_test_failures);
    CVodeGetLastStep(mem, &s.last_step);
    if (method != Method::Adams) {
      long nli = 0, nfels = 0;
      CVodeGetNumLinIters(mem, &nli);
      CVodeGetNumLinRhsEvals(mem, &nfels);
      s.linear_iterations = nli;
      s.rhs_evaluations += nfels;
    }
    return s;
  }

  /// Throws for a negative CVODE flag, rethrowing a stored callback exception first.
  void check(int flag, const char* what) {
    if (flag >= 0) {
      cb.error = nullptr;  // a recoverable failure that CVODE overcame is no error
      return;
    }
    // An unrecoverable callback exception is the cause of the failure; a recoverable one only when
    // CVODE gave up on the right-hand side (otherwise it is stale and the flag tells the cause).
    const bool rhs_flag = flag == CV_RHSFUNC_FAIL || flag == CV_FIRST_RHSFUNC_ERR ||
                          flag == CV_REPTD_RHSFUNC_ERR || flag == CV_UNREC_RHSFUNC_ERR;
    if (cb.error && (!cb.recoverable || rhs_flag)) {
      std::exception_ptr e = cb.error;
      cb.error = nullptr;
      cb.last_message.clear();
      std::rethrow_exception(e);
    }
    cb.error = nullptr;
    char* name = CVodeGetReturnFlagName(flag);  // malloc'ed by SUNDIALS
    std::string flag_name = name ? name : "unknown flag";
    std::free(name);
    std::string msg = std::string("CVODE ") + what + " failed with " + flag_name;
    if (!cb.last_message.empty()) msg += ": " + cb.last_message;
    cb.last_message.clear();
    throw std::runtime_error(msg);
  }
};

namespace {

extern "C" int cvodeRhsTrampoline(realtype t, N_Vector y, N_Vector ydot, void* user_data) {
  auto* impl = static_cast<CallbackData*>(user_data);
  // Sticky failure: with the fixed-point nonlinear solver SUNDIALS 6.4 treats a -1 from the
  // right-hand side like a convergence failure and retries with smaller steps (measured: 1.8e6
  // calls for a right-hand side failing beyond some t). Failing every later call too makes CVODE
  // give up after its few convergence-failure retries; the first exception is the one rethrown.
  if (impl->error && !impl->recoverable) return -1;
  try {
    impl->rhs(t, N_VGetArrayPointer(y), N_VGetArrayPointer(ydot));
    return 0;
  } catch (const CvodeRecoverableError&) {
    impl->error = std::current_exception();
    impl->recoverable = true;
    return 1;  // recoverable: CVODE retries with a smaller step; cleared if it succeeds
  } catch (...) {
    impl->error = std::current_exception();
    impl->recoverable = false;
    return -1;
  }
}

extern "C" int cvodePrecSetup(realtype t, N_Vector y, N_Vector, booleantype jok,
                              booleantype* jcurPtr, realtype, void* user_data) {
  auto* impl = static_cast<CallbackData*>(user_data);
  if (jok) {  // CVODE allows reusing the stored Jacobian data
    *jcurPtr = SUNFALSE;
    return 0;
  }
  try {
    impl->jacobian_diagonal(t, N_VGetArrayPointer(y), impl->jdiag.data());
    *jcurPtr = SUNTRUE;
    return 0;
  } catch (...) {
    impl->error = std::current_exception();
    impl->recoverable = false;
    return -1;
  }
}

extern "C" int cvodePrecSolve(realtype, N_Vector, N_Vector, N_Vector r, N_Vector z, realtype gamma,
                              realtype, int, void* user_data) {
  auto* impl = static_cast<CallbackData*>(user_data);
  const double* rv = N_VGetArrayPointer(r);
  double* zv = N_VGetArrayPointer(z);
  const std::size_t n = impl->jdiag.size();
  for (std::size_t i = 0; i < n; ++i) zv[i] = rv[i] / (1.0 - gamma * impl->jdiag[i]);
  return 0;
}

extern "C" void cvodeErrorHandler(int error_code, const char* module, const char* function,
                                  char* msg, void* user_data) {
  auto* impl = static_cast<CallbackData*>(user_data);
  if (error_code == CV_WARNING) return;  // warnings (e.g. t + h = t) are not errors; stay quiet
  impl->last_message = std::string(module ? module : "") + "/" + (function ? function : "") + ": " +
                       (msg ? msg : "");
}

}  // namespace

CvodeSolver::Method CvodeSolver::parseMethod(const std::string& name) {
  if (name == "adams") return Method::Adams;
  if (name == "bdf" || name == "bdf-gmres") return Method::BdfGmres;
  if (name == "bdf-dense") return Method::BdfDense;
  throw std::invalid_argument("unknown CVODE integrator '" + name +
                              "' (allowed: adams, bdf, bdf-gmres, bdf-dense).");
}

std::string CvodeSolver::methodName() const {
  switch (m_impl->method) {
    case Method::Adams:
      return "adams";
    case Method::BdfGmres:
      return "bdf-gmres";
    case Method::BdfDense:
      return "bdf-dense";
  }
  return "?";
}

CvodeSolver::CvodeSolver(int n, Rhs rhs, const Options& options, double t0, const double* y0)
    : m_impl(std::make_unique<Impl>()), m_n(n) {
  if (n < 1)
    throw std::invalid_argument(
        "CvodeSolver requires at least one unknown (got N = " + std::to_string(n) + ").");
  if (!rhs) throw std::invalid_argument("CvodeSolver requires a right-hand side function.");
  if (!y0) throw std::invalid_argument("CvodeSolver requires an initial state y0.");
  if (!(options.rtol > 0.0) || !std::isfinite(options.rtol))
    throw std::invalid_argument("CVODE rtol must be positive and finite (got " +
                                common::formatReal(options.rtol) + ").");
  if (options.atol_vector.empty()) {
    if (!(options.atol > 0.0) || !std::isfinite(options.atol))
      throw std::invalid_argument("CVODE atol must be positive and finite (got " +
                                  common::formatReal(options.atol) + ").");
  } else {
    if (static_cast<int>(options.atol_vector.size()) != n)
      throw std::invalid_argument("CVODE atol_vector must have N = " + std::to_string(n) +
                                  " entries (got " + std::to_string(options.atol_vector.size()) +
                                  ").");
    for (double a : options.atol_vector)
      if (!(a > 0.0) || !std::isfinite(a))
        throw std::invalid_argument("CVODE atol_vector entries must be positive and finite (got " +
                                    common::formatReal(a) + ").");
  }
  if (options.max_steps <= 0)
    throw std::invalid_argument("CVODE max_steps must be positive (got " +
                                std::to_string(options.max_steps) + ").");
  if (options.max_order < 0 || options.max_step < 0.0 || options.initial_step < 0.0 ||
      options.krylov_dim < 0 || options.anderson_depth < 0)
    throw std::invalid_argument(
        "CVODE max_order, max_step, initial_step, krylov_dim and anderson_depth must not be "
        "negative.");

  Impl& d = *m_impl;
  d.cb.rhs = std::move(rhs);
  d.t_last = t0;
  d.method = options.method;
  d.n = n;

  // SUNDIALS 6.x: every object belongs to a context (no MPI communicator: NULL).
  if (SUNContext_Create(nullptr, &d.ctx) != 0 || !d.ctx)
    throw std::runtime_error("SUNContext_Create failed.");
  d.y = N_VNew_Serial(n, d.ctx);
  d.work = N_VNew_Serial(n, d.ctx);
  if (!d.y || !d.work)
    throw std::runtime_error("CVODE: could not allocate N_Vector of length " + std::to_string(n) +
                             ".");
  std::copy(y0, y0 + n, N_VGetArrayPointer(d.y));

  d.mem = CVodeCreate(d.method == Method::Adams ? CV_ADAMS : CV_BDF, d.ctx);
  if (!d.mem) throw std::runtime_error("CVodeCreate failed.");
  d.check(CVodeSetErrHandlerFn(d.mem, cvodeErrorHandler, &d.cb), "CVodeSetErrHandlerFn");
  d.check(CVodeInit(d.mem, cvodeRhsTrampoline, t0, d.y), "CVodeInit");
  d.check(CVodeSetUserData(d.mem, &d.cb), "CVodeSetUserData");
  if (options.atol_vector.empty()) {
    d.check(CVodeSStolerances(d.mem, options.rtol, options.atol), "CVodeSStolerances");
  } else {
    d.abstol = N_VNew_Serial(n, d.ctx);
    std::copy(options.atol_vector.begin(), options.atol_vector.end(), N_VGetArrayPointer(d.abstol));
    d.check(CVodeSVtolerances(d.mem, options.rtol, d.abstol), "CVodeSVtolerances");
  }
  d.check(CVodeSetMaxNumSteps(d.mem, options.max_steps), "CVodeSetMaxNumSteps");
  if (options.max_order > 0) d.check(CVodeSetMaxOrd(d.mem, options.max_order), "CVodeSetMaxOrd");
  if (options.max_step > 0.0) d.check(CVodeSetMaxStep(d.mem, options.max_step), "CVodeSetMaxStep");
  if (options.initial_step > 0.0)
    d.check(CVodeSetInitStep(d.mem, options.initial_step), "CVodeSetInitStep");

  switch (d.method) {
    case Method::Adams:
      // Fixed-point (functional) iteration: the classic non-stiff Adams setup (CVODE guide 2.1).
      d.NLS = SUNNonlinSol_FixedPoint(d.y, options.anderson_depth, d.ctx);
      if (!d.NLS) throw std::runtime_error("SUNNonlinSol_FixedPoint failed.");
      d.check(CVodeSetNonlinearSolver(d.mem, d.NLS), "CVodeSetNonlinearSolver");
      break;
    case Method::BdfGmres:
      // Newton (CVODE's default nonlinear solver) with matrix-free GMRES; left-preconditioned
      // with the Jacobian diagonal when the caller provides it.
      d.LS = SUNLinSol_SPGMR(d.y, options.jacobian_diagonal ? SUN_PREC_LEFT : SUN_PREC_NONE,
                             options.krylov_dim, d.ctx);
      if (!d.LS) throw std::runtime_error("SUNLinSol_SPGMR failed.");
      d.check(CVodeSetLinearSolver(d.mem, d.LS, nullptr), "CVodeSetLinearSolver");
      if (options.jacobian_diagonal) {
        d.cb.jacobian_diagonal = options.jacobian_diagonal;
        d.cb.jdiag.assign(n, 0.0);
        d.check(CVodeSetPreconditioner(d.mem, cvodePrecSetup, cvodePrecSolve),
                "CVodeSetPreconditioner");
      }
      break;
    case Method::BdfDense:
      d.A = SUNDenseMatrix(n, n, d.ctx);
      if (!d.A) throw std::runtime_error("SUNDenseMatrix failed (N = " + std::to_string(n) + ").");
      d.LS = SUNLinSol_Dense(d.y, d.A, d.ctx);
      if (!d.LS) throw std::runtime_error("SUNLinSol_Dense failed.");
      d.check(CVodeSetLinearSolver(d.mem, d.LS, d.A), "CVodeSetLinearSolver");
      break;
  }
}

CvodeSolver::~CvodeSolver() = default;

void CvodeSolver::reset(double t0, const double* y0) {
  Impl& d = *m_impl;
  // CVodeReInit zeroes CVODE's counters: keep what was spent so far.
  const Stats s = d.current();
  d.accumulated.steps += s.steps;
  d.accumulated.rhs_evaluations += s.rhs_evaluations;
  d.accumulated.linear_iterations += s.linear_iterations;
  d.accumulated.nonlinear_iterations += s.nonlinear_iterations;
  d.accumulated.nonlinear_failures += s.nonlinear_failures;
  d.accumulated.error_test_failures += s.error_test_failures;
  std::copy(y0, y0 + m_n, N_VGetArrayPointer(d.y));
  d.check(CVodeReInit(d.mem, t0, d.y), "CVodeReInit");
  d.t_last = t0;
}

double CvodeSolver::advance(double tout, double* y) {
  Impl& d = *m_impl;
  double tret = 0.0;
  d.cb.error = nullptr;
  const int flag = CVode(d.mem, tout, d.y, &tret, CV_NORMAL);
  d.check(flag, "CVode");
  d.t_last = tret;
  if (y) std::copy(N_VGetArrayPointer(d.y), N_VGetArrayPointer(d.y) + m_n, y);
  return tret;
}

double CvodeSolver::step(double tout) {
  Impl& d = *m_impl;
  double tret = 0.0;
  d.cb.error = nullptr;
  const int flag = CVode(d.mem, tout, d.y, &tret, CV_ONE_STEP);
  d.check(flag, "CVode");
  d.t_last = tret;
  return tret;
}

void CvodeSolver::interpolate(double t, double* out, int k) const {
  Impl& d = *m_impl;
  d.check(CVodeGetDky(d.mem, t, k, d.work), "CVodeGetDky");
  std::copy(N_VGetArrayPointer(d.work), N_VGetArrayPointer(d.work) + m_n, out);
}

void CvodeSolver::setStopTime(double tstop) {
  m_impl->check(CVodeSetStopTime(m_impl->mem, tstop), "CVodeSetStopTime");
}

void CvodeSolver::setMaxStep(double hmax) {
  if (hmax < 0.0)
    throw std::invalid_argument("CVODE max_step must not be negative (got " +
                                common::formatReal(hmax) + ").");
  m_impl->check(CVodeSetMaxStep(m_impl->mem, hmax), "CVodeSetMaxStep");
}

double CvodeSolver::time() const {
  double t = 0.0;
  m_impl->check(CVodeGetCurrentTime(m_impl->mem, &t), "CVodeGetCurrentTime");
  return t;
}

double CvodeSolver::stateTime() const { return m_impl->t_last; }

const double* CvodeSolver::state() const { return N_VGetArrayPointer(m_impl->y); }

CvodeSolver::Stats CvodeSolver::stats() const {
  Stats s = m_impl->current();
  const Stats& a = m_impl->accumulated;
  s.steps += a.steps;
  s.rhs_evaluations += a.rhs_evaluations;
  s.linear_iterations += a.linear_iterations;
  s.nonlinear_iterations += a.nonlinear_iterations;
  s.nonlinear_failures += a.nonlinear_failures;
  s.error_test_failures += a.error_test_failures;
  return s;
}

}  // namespace granagg::meanfield
