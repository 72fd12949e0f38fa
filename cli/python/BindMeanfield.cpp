/// \file BindMeanfield.cpp
/// granagg.meanfield: the Smoluchowski solvers, the kinetic-theory tables and the beta fit as
/// arrays (docs/python.md). Each function fills the request struct that `granagg smol`,
/// `granagg kinetic` and `granagg fit-beta` fill from their options and calls the same library
/// function; results come back as read-only NumPy arrays or a pandas DataFrame. Errors are the
/// commands' own sentences (they name the command-line option, e.g. "--t-end"), raised as
/// ValueError.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "cli/CliContext.h"
#include "cli/python/Arrays.h"
#include "meanfield/fit/FitBetaRun.h"
#include "meanfield/kinetic/KineticTables.h"
#include "meanfield/solvers/SmolTables.h"

namespace granagg::python {
namespace mf = granagg::meanfield;
using namespace pybind11::literals;

namespace {

/// One solution of the Smoluchowski equation as arrays.
struct SmolCurve {
  std::string method, kernel, stopped;
  py::array t, S, M0, M1, M2, mass_loss, valid, max_size, local_slope;
  py::object N_s = py::none(), sizes = py::none();
  double wall_seconds = 0.0;
  long steps = 0, rhs_evaluations = 0;
};

SmolCurve smoluchowski(double beta, const std::string& method, double t_end,
                       const std::string& kernel, double K0, double t_min, int per_decade,
                       double s_end, long long M, double ratio, double rtol, double atol,
                       const std::string& integrator, double p, int n_s_max) {
  mf::SmolRequest r;
  r.kernel = kernel;
  r.beta = beta;
  r.K0 = K0;
  r.method = method;
  r.t_min = t_min;
  r.t_end = t_end;
  r.per_decade = per_decade;
  r.s_end = s_end;
  r.max_size = M;
  r.ratio = ratio;
  r.rtol = rtol;
  r.atol = atol;
  r.integrator = integrator;
  r.p = p;
  if (n_s_max < 0) throw py::value_error("n_s_max must be >= 0 (got " +
                                         std::to_string(n_s_max) + ").");
  r.snapshot_max_size = method == "discrete" ? n_s_max : 0;
  mf::SmolSolution sol;
  {
    py::gil_scoped_release unlocked;
    sol = mf::solveSmol(r);
  }
  const auto& samples = sol.result.samples;
  std::vector<double> t, S, M0, M1, M2, loss, mx;
  std::vector<bool> valid;
  for (const auto& s : samples) {
    t.push_back(s.t);
    S.push_back(s.S);
    M0.push_back(s.M0);
    M1.push_back(s.M1);
    M2.push_back(s.M2);
    loss.push_back(s.mass_loss);
    mx.push_back(s.max_size);
    valid.push_back(s.valid);
  }
  SmolCurve c;
  c.method = method;
  c.kernel = sol.kernel_name;
  c.stopped = sol.stopped;
  c.wall_seconds = sol.wall_seconds;
  c.steps = sol.result.stats.steps;
  c.rhs_evaluations = sol.result.stats.rhs_evaluations;
  c.t = readOnlyArray(std::move(t));
  c.S = readOnlyArray(std::move(S));
  c.M0 = readOnlyArray(std::move(M0));
  c.M1 = readOnlyArray(std::move(M1));
  c.M2 = readOnlyArray(std::move(M2));
  c.mass_loss = readOnlyArray(std::move(loss));
  c.max_size = readOnlyArray(std::move(mx));
  std::vector<std::uint8_t> v8(valid.begin(), valid.end());
  c.valid = readOnlyArray(std::move(v8)).attr("astype")("bool");
  c.valid.attr("setflags")("write"_a = false);
  c.local_slope = readOnlyArray(std::vector<double>(sol.z_local));
  const auto& snaps = sol.result.snapshots;
  if (!snaps.empty()) {
    const std::size_t K = snaps.front().size.size();
    std::vector<double> n(snaps.size() * K, std::nan(""));
    for (std::size_t i = 0; i < snaps.size(); ++i)
      for (std::size_t k = 0; k < snaps[i].n.size() && k < K; ++k) n[i * K + k] = snaps[i].n[k];
    c.N_s = readOnlyArray(std::move(n), {py::ssize_t(snaps.size()), py::ssize_t(K)});
    c.sizes = readOnlyCopy(snaps.front().size);
  }
  return c;
}

/// A KineticTable as a pandas DataFrame, its parameters and comments in .attrs.
py::object dataFrame(const mf::KineticTable& table) {
  py::dict attrs;
  for (const auto& [k, v] : table.provenance.parameters()) attrs[py::str(k)] = v;
  if (!table.comments.empty()) attrs["comments"] = py::cast(table.comments);
  return python::dataFrame(table.columns, table.rows, attrs);
}

/// Keyword arguments into a request's fields, by name; an unknown one is a TypeError that
/// lists the known ones.
class Fields {
 public:
  Fields(const char* kind, const py::kwargs& kw) : m_kind(kind), m_kw(kw) {}
  template <class T>
  Fields& take(const char* name, T& field) {
    m_known.push_back(name);
    if (m_kw.contains(name)) field = py::cast<T>(m_kw[name]);
    return *this;
  }
  void done() const {
    for (const auto& item : m_kw) {
      const std::string key = py::str(item.first);
      bool known = false;
      for (const auto& k : m_known) known = known || k == key;
      if (!known) {
        std::string list;
        for (const auto& k : m_known) list += (list.empty() ? "" : ", ") + k;
        throw py::type_error("kinetic('" + m_kind + "'): unknown option '" + key +
                             "' (known: " + list + ")");
      }
    }
  }

 private:
  std::string m_kind;
  const py::kwargs& m_kw;
  std::vector<std::string> m_known;
};

py::object kinetic(const std::string& kind, const py::kwargs& kw) {
  mf::KineticTable table;
  if (kind == "restitution") {
    mf::RestitutionRequest r;
    py::object speeds = py::none();
    Fields(kind.c_str(), kw).take("E", r.E).take("D", r.D).take("unclamped", r.unclamped)
        .take("speeds", speeds).done();
    if (!speeds.is_none()) {
      std::string text;
      for (double v : vectorArg(speeds, "speeds", 1))
        text += (text.empty() ? "" : ",") + common::formatReal(v);
      r.speeds = text;
    }
    table = mf::kineticTable(r);
  } else if (kind == "haff") {
    mf::HaffRequest r;
    Fields(kind.c_str(), kw).take("eps", r.eps).take("phi", r.phi).take("T0", r.T0)
        .take("t_min", r.t_min).take("t_end", r.t_end).take("points", r.points).done();
    table = mf::kineticTable(r);
  } else if (kind == "cooling") {
    mf::CoolingRequest r;
    Fields(kind.c_str(), kw).take("E", r.E).take("D", r.D).take("unclamped", r.unclamped)
        .take("phi", r.phi).take("t_min", r.t_min).take("t_end", r.t_end)
        .take("points", r.points).done();
    py::gil_scoped_release unlocked;
    table = mf::kineticTable(r);
  } else if (kind == "enskog") {
    mf::EnskogRequest r;
    Fields(kind.c_str(), kw).take("phi", r.phi).take("T", r.T).done();
    table = mf::kineticTable(r);
  } else if (kind == "charging") {
    mf::ChargingRequest r;
    Fields(kind.c_str(), kw).take("kappa", r.kappa)
        .take("cooling_exponent", r.cooling_exponent).done();
    table = mf::kineticTable(r);
  } else {
    throw py::value_error("kind must be one of restitution, haff, cooling, enskog, charging "
                          "(got '" + kind + "').");
  }
  return dataFrame(table);
}

struct BetaFitResult {
  mf::FitBetaResult r;
  std::vector<std::string> report;
};

BetaFitResult fitBeta(py::handle t, py::handle S, py::handle window, double beta_min,
                      double beta_max, bool curve_fit, int min_points) {
  mf::GrowthInput input;
  input.source = "(arrays)";
  input.column = "S";
  input.t = vectorArg(t, "t", 1);
  DoubleArray y = DoubleArray::ensure(S);
  if (!y || (y.ndim() != 1 && y.ndim() != 2) ||
      y.shape(y.ndim() - 1) != py::ssize_t(input.t.size()))
    throw py::value_error("S must have the length of t (" + std::to_string(input.t.size()) +
                          "), or shape (runs, " + std::to_string(input.t.size()) + ").");
  const std::size_t R = y.ndim() == 1 ? 1 : static_cast<std::size_t>(y.shape(0));
  for (std::size_t r = 0; r < R; ++r)
    input.runs.emplace_back(y.data() + r * input.t.size(), y.data() + (r + 1) * input.t.size());
  mf::FitBetaRequest req;
  if (!window.is_none()) {
    req.window = vectorArg(window, "window");
    if (req.window.size() != 2) throw py::value_error("window must be (t0, t1) or None.");
  }
  req.beta_min = beta_min;
  req.beta_max = beta_max;
  req.curve_fit = curve_fit;
  req.min_points = min_points;
  BetaFitResult out;
  {
    py::gil_scoped_release unlocked;
    out.r = mf::runFitBeta(std::move(input), req);
  }
  out.report = mf::fitBetaReport(out.r, cli::paperValues());
  return out;
}

}  // namespace

void bindMeanfield(py::module_& top) {
  py::module_ m = top.def_submodule(
      "meanfield",
      "Mean-field theory as arrays: Smoluchowski solutions, kinetic-theory tables and the fit "
      "of the kernel exponent beta to S(t) (docs/python.md; the same code as granagg smol, "
      "granagg kinetic and granagg fit-beta).");

  py::class_<SmolCurve>(m, "SmolCurve", "One solution of the Smoluchowski equation from a "
                                        "monodisperse start, n_1(0) = 1.")
      .def_readonly("t", &SmolCurve::t, "Output times, in 1/(K0 n_1(0)).")
      .def_readonly("S", &SmolCurve::S, "Mean cluster size M2 / M1.")
      .def_readonly("M0", &SmolCurve::M0, "Number of clusters per unit volume.")
      .def_readonly("M1", &SmolCurve::M1, "Mass per unit volume.")
      .def_readonly("M2", &SmolCurve::M2, "Second moment.")
      .def_readonly("mass_loss", &SmolCurve::mass_loss, "(M1(0) - M1(t)) / M1(0).")
      .def_readonly("valid", &SmolCurve::valid,
                    "False where truncation lost mass: S is then no solution of the equation.")
      .def_readonly("max_size", &SmolCurve::max_size, "Size range in use.")
      .def_readonly("local_slope", &SmolCurve::local_slope,
                    "ln[S(t)/S(t/p)] / ln p at every t (NaN where undefined or invalid).")
      .def_readonly("N_s", &SmolCurve::N_s,
                    "Discrete method: n_k at every output time, shape (times, sizes); else None.")
      .def_readonly("sizes", &SmolCurve::sizes, "The sizes k of N_s's columns, or None.")
      .def_readonly("method", &SmolCurve::method, "'sectional', 'discrete' or 'mono'.")
      .def_readonly("kernel", &SmolCurve::kernel, "The kernel's name.")
      .def_readonly("stopped", &SmolCurve::stopped,
                    "Why the solve stopped before t_end, with advice; '' when it reached it.")
      .def_readonly("wall_seconds", &SmolCurve::wall_seconds, "Wall time of the solve.")
      .def_readonly("steps", &SmolCurve::steps, "Integrator steps.")
      .def_readonly("rhs_evaluations", &SmolCurve::rhs_evaluations,
                    "Right-hand side evaluations.")
      .def("__repr__", [](const SmolCurve& c) {
        return "<SmolCurve " + c.kernel + ", " + c.method + ", " +
               std::to_string(py::len(c.t)) + " samples>";
      });

  m.def("smoluchowski", &smoluchowski, "beta"_a = 2.0, "method"_a = "sectional",
        "t_end"_a = 1e6, "kernel"_a = "beta", "K0"_a = 1.0, "t_min"_a = 1e-2,
        "per_decade"_a = 20, "s_end"_a = std::numeric_limits<double>::infinity(),
        "M"_a = 1LL << 21, "ratio"_a = 1.05, "rtol"_a = 1e-8, "atol"_a = 1e-14,
        "integrator"_a = "adams", "p"_a = 2.0, "n_s_max"_a = 200,
        "Solves the Smoluchowski equation from n_1(0) = 1, as `granagg smol` does.\n\n"
        "kernel: 'beta' (the kernel of exponent beta, docs/model.md), 'constant', 'additive' "
        "or 'multiplicative'; method: 'sectional', 'discrete' or "
        "'mono'; t_min, t_end, per_decade: log-spaced output times; s_end: stop once S reaches "
        "it; M: the discrete method's largest size; ratio: the sectional grid's ratio; rtol, "
        "atol, integrator: CVODE; p: ratio of the local slope; n_s_max: the discrete method "
        "keeps n_k for k <= n_s_max at every output time. Returns a SmolCurve.");

  m.def("kinetic", &kinetic, "kind"_a = "cooling",
        "A table of `granagg kinetic` as a pandas DataFrame, its parameters in .attrs.\n\n"
        "kind and its options (defaults as the command's):\n"
        "  'restitution': E, D, unclamped, speeds -> e(v) and contact times;\n"
        "  'haff': eps, phi, T0, t_min, t_end, points -> Haff's law T(t);\n"
        "  'cooling': E, D, unclamped, phi, t_min, t_end, points -> viscoelastic cooling T(t) "
        "with Haff's law of the same initial rate and the asymptotes;\n"
        "  'enskog': phi, T -> n, g2 and the Enskog collision frequency;\n"
        "  'charging': kappa, cooling_exponent -> the charging-rate exponent.");

  py::class_<BetaFitResult>(m, "BetaFit", "The fit of the kernel exponent beta to S(t), as "
                                          "`granagg fit-beta` does it (docs/fit-beta.md).")
      .def_property_readonly("z", [](const BetaFitResult& b) { return b.r.z.z; },
                             "Growth exponent over the window.")
      .def_property_readonly(
          "z_interval", [](const BetaFitResult& b) { return py::make_tuple(b.r.z.z_low,
                                                                            b.r.z.z_high); },
          "Its interval.")
      .def_property_readonly(
          "window", [](const BetaFitResult& b) { return py::make_tuple(b.r.window.t0,
                                                                        b.r.window.t1); },
          "(t0, t1) of the fit.")
      .def_property_readonly("beta", [](const BetaFitResult& b) { return b.r.from_z.beta; },
                             "beta from z at the data's S range (NaN outside z(beta)).")
      .def_property_readonly(
          "beta_interval",
          [](const BetaFitResult& b) {
            return py::make_tuple(b.r.from_z.beta_low, b.r.from_z.beta_high);
          },
          "Its interval.")
      .def_property_readonly("beta_asymptotic",
                             [](const BetaFitResult& b) { return b.r.asymptotic.beta; },
                             "3 z / (3 - z), the asymptotic law.")
      .def_property_readonly("beta_curve", [](const BetaFitResult& b) { return b.r.curve.beta; },
                             "beta of the full-curve fit (NaN without it).")
      .def_property_readonly(
          "beta_curve_interval",
          [](const BetaFitResult& b) {
            return py::make_tuple(b.r.curve.beta_low, b.r.curve.beta_high);
          },
          "Its interval.")
      .def_readonly("report", &BetaFitResult::report,
                    "The summary lines `granagg fit-beta` prints, with its verdict.")
      .def("__str__", [](const BetaFitResult& b) {
        std::string s;
        for (const auto& l : b.report) s += l + "\n";
        return s;
      });

  m.def("fit_beta", &fitBeta, "t"_a, "S"_a, "window"_a = py::none(), "beta_min"_a = 1.5,
        "beta_max"_a = 6.0, "curve_fit"_a = true, "min_points"_a = 5,
        "Fits beta to S(t) (S of shape (T,) or (runs, T)) as `granagg fit-beta` does: z over "
        "the window (None: chosen automatically), beta from z, the full-curve fit. Returns a "
        "BetaFit whose .report holds the verdict text the command prints.");
}

}  // namespace granagg::python
