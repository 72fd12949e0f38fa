/// \file BindMd.cpp
/// granagg.md: an MD run driven from Python (docs/python.md), HOOMD-blue's model: a
/// md::Simulation (the object `granagg md` wires its options to) with a reporter that calls the
/// user's Python functions between chunks of steps. The physics and the outputs are the
/// Simulation's: a run from Python with the same configuration and seed is bit-identical to
/// `granagg md`.
///
/// Design.
/// - The GIL is released while C++ runs between callbacks; the reporter takes it back to call
///   the functions and to check for signals (PyErr_CheckSignals) at least every CHECK_SECONDS of
///   wall time. It asks the run for chunks of that length (Reporter::nextStep), and it needs no
///   observables (Reporter::needsObservables), so the short chunks cost no observables.
/// - Ctrl-C (KeyboardInterrupt) and an exception in a callback stop the run as SIGINT does in
///   `granagg md` (RunOptions::stop: the chunk in progress ends, a checkpoint is written); the
///   exception then reaches the caller.
/// - The state a callback sees is the engine's frame in particle-id order (the copy the
///   trajectory writer takes), made only when the callback reads an array of it; its arrays
///   are read-only.
/// - out=None runs in a private temporary folder, removed with the object; frames are then not
///   stored (output.trajectory = false; frame-time callbacks still fire).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <stdlib.h>

#include <chrono>
#include <csignal>
#include <cmath>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <system_error>
#include <vector>

#include "cli/CliContext.h"
#include "cli/python/Arrays.h"
#include "common/Csv.h"
#include "common/OutputPath.h"
#include "md/config/ConfigParser.h"
#include "md/run/RunLog.h"
#include "md/run/Simulation.h"
#include "study/insitu/InSituAnalysis.h"

namespace granagg::python {
namespace fs = std::filesystem;
using namespace pybind11::literals;

namespace {

/// Wall time between two checks for pending signals (the bound is 0.1 s).
constexpr double CHECK_SECONDS = 0.05;

/// A Python value as the text of a TOML value (for dict configurations and overrides).
std::string tomlValue(py::handle v, const std::string& key, bool quote_strings) {
  if (py::isinstance<py::bool_>(v)) return v.cast<bool>() ? "true" : "false";
  if (py::isinstance<py::int_>(v)) return py::str(v);
  if (py::isinstance<py::float_>(v)) {
    const double x = v.cast<double>();
    if (std::isnan(x)) return "nan";
    if (std::isinf(x)) return x > 0 ? "inf" : "-inf";
    return common::formatReal(x).find_first_of(".eEn") == std::string::npos
               ? common::formatReal(x) + ".0"
               : common::formatReal(x);
  }
  if (py::isinstance<py::str>(v)) {
    const std::string s = v.cast<std::string>();
    if (!quote_strings) return s;
    return std::string(py::str(py::module_::import("json").attr("dumps")(s)));
  }
  throw py::type_error("config value of '" + key + "' must be a bool, int, float or str (got " +
                       std::string(py::str(py::type::of(v).attr("__name__"))) + ").");
}

/// The configuration: a TOML file, a preset name ("quick", "paper", "haff") or a dict of tables;
/// then the overrides (dotted keys, as --set). Validated with the CLI's messages.
md::MdConfig loadConfig(py::handle config, py::handle overrides) {
  std::vector<std::string> sets;
  if (!overrides.is_none()) {
    if (!py::isinstance<py::dict>(overrides))
      throw py::type_error("overrides must be a dict of dotted keys, e.g. {'system.N': 1000}.");
    for (const auto& [k, v] : overrides.cast<py::dict>()) {
      const std::string key = py::str(k);
      sets.push_back(key + "=" + tomlValue(v, key, false));
    }
  }
  if (py::isinstance<py::dict>(config)) {
    std::string text;
    for (const auto& [section, table] : config.cast<py::dict>()) {
      const std::string name = py::str(section);
      if (!py::isinstance<py::dict>(table))
        throw py::type_error("config['" + name + "'] must be a dict (a TOML table).");
      text += "[" + name + "]\n";
      for (const auto& [k, v] : table.cast<py::dict>()) {
        const std::string key = py::str(k);
        text += key + " = " + tomlValue(v, name + "." + key, true) + "\n";
      }
    }
    return md::parseConfigString(text, "config (dict)", sets);
  }
  if (config.is_none()) return md::parseConfigString("", "(defaults)", sets);
  if (!py::isinstance<py::str>(config) && !py::isinstance(config, py::module_::import("os")
                                                                       .attr("PathLike")))
    throw py::type_error("config must be a TOML file, a preset name or a dict.");
  const std::string c = py::str(py::module_::import("os").attr("fspath")(config));
  if (fs::is_regular_file(c)) return md::parseConfigFile(c, sets);
  if (c.find('/') != std::string::npos || (c.size() > 5 && c.substr(c.size() - 5) == ".toml"))
    throw py::value_error("config: no file '" + c + "'.");
  return md::parseConfigFile(cli::findPreset("presets", c, "config"), sets);
}

/// The state a callback sees; valid during the call only.
struct PyState {
  const md::Simulation* sim = nullptr;
  mutable std::optional<md::Frame> frame;
  mutable py::object positions, velocities, charges, images;

  const md::Simulation& get(const char* what) const {
    if (!sim)
      throw py::attribute_error(std::string("State.") + what +
                                ": the state is valid only during its callback.");
    return *sim;
  }
  const md::Frame& current(const char* what) const {
    const md::Simulation& s = get(what);
    if (!frame) frame = s.engine().frame();
    return *frame;
  }
  template <class T>
  static py::object interleave(const std::vector<T>& x, const std::vector<T>& y,
                               const std::vector<T>& z) {
    std::vector<T> v(3 * x.size());
    for (std::size_t i = 0; i < x.size(); ++i) {
      v[3 * i] = x[i];
      v[3 * i + 1] = y[i];
      v[3 * i + 2] = z[i];
    }
    return readOnlyArray(std::move(v), {py::ssize_t(x.size()), 3});
  }
  py::object getPositions() const {
    get("positions");
    if (!positions) {
      const auto& f = current("positions");
      positions = interleave(f.x, f.y, f.z);
    }
    return positions;
  }
  py::object getVelocities() const {
    get("velocities");
    if (!velocities) {
      const auto& f = current("velocities");
      velocities = interleave(f.vx, f.vy, f.vz);
    }
    return velocities;
  }
  py::object getImages() const {
    get("images");
    if (!images) {
      const auto& f = current("images");
      images = interleave(f.ix, f.iy, f.iz);
    }
    return images;
  }
  py::object getCharges() const {
    get("charges");
    if (!charges) charges = readOnlyCopy(current("charges").charge);
    return charges;
  }
};

struct Callback {
  long every = 0;  ///< steps; 0: at the frame times
  py::object fn;
  std::int64_t last = -1;
};

/// The observables columns of Simulation.observables (as /granagg/observables, docs/model.md
/// section 10).
const std::vector<std::string>& observableColumns() {
  static const std::vector<std::string> c = {
      "step", "t", "T_g", "kinetic_energy", "elastic_energy", "coulomb_energy",
      "contacts_per_particle", "collisions", "mean_overlap", "max_overlap", "total_charge",
      "mean_abs_charge", "max_abs_charge"};
  return c;
}

/// Calls the Python functions between chunks, checks for signals, records the observables.
class PythonReporter : public md::Reporter {
 public:
  PythonReporter(volatile std::sig_atomic_t* stop, std::vector<Callback> callbacks,
                 std::vector<std::vector<double>>* rows, int observable_interval)
      : m_stop(stop), m_callbacks(std::move(callbacks)), m_rows(rows),
        m_every(observable_interval), m_last_check(Clock::now()) {}

  std::int64_t nextStep(const md::Simulation& sim) const override {
    const std::int64_t step = sim.engine().step();
    std::int64_t next = step + m_chunk;
    next = std::min(next, (step / m_every + 1) * m_every);
    for (const auto& c : m_callbacks)
      if (c.every > 0) next = std::min(next, (step / c.every + 1) * c.every);
    return next;
  }
  bool needsObservables(const md::Simulation& sim) const override {
    return sim.engine().step() % m_every == 0;
  }
  void report(const md::Simulation& sim) override {
    const std::int64_t step = sim.engine().step();
    const auto now = Clock::now();
    const double wall = std::chrono::duration<double>(now - m_last_check).count();
    // chunks of about CHECK_SECONDS: the steps per second seen so far
    if (step > m_last_step && wall > 0.0) {
      const double rate = double(step - m_last_step) / wall;
      m_chunk = std::max<std::int64_t>(1, static_cast<std::int64_t>(rate * CHECK_SECONDS));
    }
    m_last_step = step;
    m_last_check = now;
    if (step % m_every == 0 && m_rows) record(sim.lastObservables());
    py::gil_scoped_acquire gil;
    if (PyErr_CheckSignals() != 0) return fail();
    for (auto& c : m_callbacks) {
      const bool due = c.every > 0 ? step % c.every == 0 : sim.frameStep() == step;
      if (!due || c.last == step) continue;
      c.last = step;
      // Python owns the state; once the call returns it no longer refers to the run, so a
      // state kept by the callback raises AttributeError instead of reading freed memory.
      py::object handle = py::cast(std::make_unique<PyState>());
      auto* state = handle.cast<PyState*>();
      state->sim = &sim;
      try {
        c.fn(handle);
      } catch (py::error_already_set& e) {
        state->sim = nullptr;
        m_error = e;
        *m_stop = SIGINT;
        return;
      }
      state->sim = nullptr;
      state->frame.reset();
    }
  }
  /// The error that stopped the run, if any (rethrown by Simulation.run).
  std::optional<py::error_already_set>& error() { return m_error; }

 private:
  using Clock = std::chrono::steady_clock;
  void fail() {
    m_error.emplace();  // takes the pending KeyboardInterrupt (or the handler's exception)
    *m_stop = SIGINT;
  }
  void record(const md::Observables& o) {
    m_rows->push_back({double(o.step), o.time, o.temperature, o.kinetic_energy,
                       o.elastic_energy, o.coulomb_energy, o.contacts_per_particle,
                       double(o.collisions), o.mean_overlap, o.max_overlap, o.total_charge,
                       o.mean_abs_charge, o.max_abs_charge});
  }
  volatile std::sig_atomic_t* m_stop;
  std::vector<Callback> m_callbacks;
  std::vector<std::vector<double>>* m_rows;
  std::int64_t m_every;
  std::int64_t m_chunk = 1, m_last_step = -1;
  Clock::time_point m_last_check;
  std::optional<py::error_already_set> m_error;
};

class PySimulation {
 public:
  PySimulation(py::handle config, py::handle overrides, py::handle out, bool force) {
    md::MdConfig cfg = loadConfig(config, overrides);
    if (out.is_none()) {
      std::string tmpl = (fs::temp_directory_path() / "granagg-py-XXXXXX").string();
      if (!::mkdtemp(tmpl.data())) throw std::runtime_error("cannot create a temporary folder");
      m_temporary = tmpl;
      m_folder = fs::path(tmpl) / "run";
      cfg.output.trajectory = false;
    } else {
      m_folder = pathArg(out, "out");
      common::checkOutputFolder(m_folder.string());
    }
    if (cfg.output.analyze) insitu::analysisOptions(cfg);  // bad [analysis]: before any file
    md::RunOptions o = options(force);
    py::gil_scoped_release unlocked;
    m_sim.emplace(md::Simulation::start(cfg, m_folder, o));
    if (cfg.output.analyze) insitu::InSituAnalysis::removeOutputs(m_folder);
  }
  /// Simulation.restart: continues a run folder from its checkpoint.
  PySimulation(const std::string& folder, py::handle overrides) : m_folder(folder) {
    if (!fs::is_directory(folder))
      throw py::value_error("restart: no run folder '" + folder + "'.");
    std::vector<std::string> sets;
    if (!overrides.is_none())
      for (const auto& [k, v] : overrides.cast<py::dict>()) {
        const std::string key = py::str(k);
        sets.push_back(key + "=" + tomlValue(v, key, false));
      }
    md::RunOptions o = options(false);
    py::gil_scoped_release unlocked;
    m_sim.emplace(md::Simulation::resume(m_folder, sets, o));
  }
  ~PySimulation() { close(); }

  void close() {
    m_sim.reset();
    if (!m_temporary.empty()) {
      std::error_code ec;
      fs::remove_all(m_temporary, ec);
      m_temporary.clear();
    }
  }

  md::Simulation& sim() {
    if (!m_sim)
      throw py::value_error(m_closed.empty() ? "the Simulation is closed." : m_closed);
    return *m_sim;
  }

  py::dict run(py::handle t_end, py::handle callbacks, bool progress) {
    sim();  // a closed Simulation raises here, before the arguments are read
    std::vector<Callback> cbs;
    if (!callbacks.is_none()) {
      for (py::handle item : callbacks) {
        py::tuple pair = py::reinterpret_borrow<py::object>(item).cast<py::tuple>();
        if (pair.size() != 2 || !PyCallable_Check(pair[1].ptr()))
          throw py::type_error("callbacks must be (every, fn) pairs: every an int of steps or "
                               "'frames', fn a callable taking the state.");
        Callback c;
        if (py::isinstance<py::str>(pair[0])) {
          if (pair[0].cast<std::string>() != "frames")
            throw py::value_error("callbacks: every must be an int >= 1 or 'frames' (got '" +
                                  pair[0].cast<std::string>() + "').");
        } else {
          c.every = pair[0].cast<long>();
          if (c.every < 1)
            throw py::value_error("callbacks: every must be an int >= 1 or 'frames' (got " +
                                  std::to_string(c.every) + ").");
        }
        c.fn = py::reinterpret_borrow<py::object>(pair[1]);
        cbs.push_back(std::move(c));
      }
    }
    if (!t_end.is_none()) extendTo(t_end.cast<double>());
    md::Simulation& r = sim();
    if (r.finished()) return summary(md::RunSummary{}, r);
    *m_stop = 0;
    auto reporter = std::make_shared<PythonReporter>(m_stop.get(), std::move(cbs), &m_rows,
                                                     r.config().output.observable_interval);
    r.addReporter(reporter);
    std::shared_ptr<insitu::InSituAnalysis> analysis;
    if (r.config().output.analyze) {
      analysis = std::make_shared<insitu::InSituAnalysis>(r, "granagg.md.Simulation");
      r.addReporter(analysis);
    }
    if (progress) r.addReporter(std::make_shared<md::ProgressReporter>(r));
    md::RunSummary summ;
    try {
      py::gil_scoped_release unlocked;
      summ = r.run();
      if (analysis && !summ.stopped) analysis->writeResults(r);
    } catch (const std::exception& e) {
      m_sim.reset();  // (with the GIL: the reporter holds Python objects)
      m_closed = std::string("the run stopped: ") + e.what();
      throw;
    }
    // A Simulation keeps its reporters; the next run() continues from the checkpoint with its
    // own (run() ended with one), so that callbacks never accumulate.
    reopen();
    if (reporter->error()) {
      const py::error_already_set e = *reporter->error();
      throw e;
    }
    return summary(summ, sim());
  }

  void checkpoint() {
    py::gil_scoped_release unlocked;
    sim().writeCheckpoint();
  }

  py::object observables() const {
    py::object df = dataFrame(observableColumns(), m_rows);
    df["step"] = df["step"].attr("astype")("int64");
    df["collisions"] = df["collisions"].attr("astype")("int64");
    return df;
  }

  const fs::path& folder() const { return m_folder; }
  bool temporary() const { return !m_temporary.empty(); }

 private:
  md::RunOptions options(bool force) {
    md::RunOptions o;
    o.command_line = "granagg.md.Simulation (Python)";
    o.overwrite = force;
    o.stop = m_stop.get();
    return o;
  }
  /// A run to another t_end continues from a checkpoint of the present state (as `granagg md
  /// --restart RUN --set run.t_end=T` does).
  void extendTo(double t_end) {
    md::Simulation& s = sim();
    if (!(t_end > 0.0) || !std::isfinite(t_end))
      throw py::value_error("t_end must be positive and finite (got " +
                            common::formatReal(t_end) + ").");
    if (t_end == s.config().run.t_end) return;
    if (t_end < s.engine().time())
      throw py::value_error("t_end = " + common::formatReal(t_end) +
                            " is before the run's time " + common::formatReal(s.engine().time()) +
                            ".");
    {
      py::gil_scoped_release unlocked;
      s.writeCheckpoint();
    }
    m_sim.reset();
    py::gil_scoped_release unlocked;
    m_sim.emplace(md::Simulation::resume(m_folder, {"run.t_end=" + common::formatReal(t_end)},
                                         options(false)));
  }
  /// The folder's Simulation afresh from the checkpoint that run() ended with. Destroyed with
  /// the GIL held: its reporters hold Python objects.
  void reopen() {
    m_sim.reset();
    py::gil_scoped_release unlocked;
    m_sim.emplace(md::Simulation::resume(m_folder, {}, options(false)));
  }
  py::dict summary(const md::RunSummary& s, const md::Simulation& sim) {
    py::dict d;
    d["steps"] = s.steps;
    d["seconds"] = s.loop_seconds;
    d["stopped"] = s.stopped;
    d["step"] = sim.engine().step();
    d["t"] = sim.engine().time();
    return d;
  }

  std::unique_ptr<volatile std::sig_atomic_t> m_stop{new volatile std::sig_atomic_t(0)};
  fs::path m_folder;
  std::string m_temporary;
  std::optional<md::Simulation> m_sim;
  std::string m_closed;  ///< why m_sim is gone, when a run failed
  std::vector<std::vector<double>> m_rows;
};

}  // namespace

void bindMd(py::module_& top) {
  py::module_ m = top.def_submodule(
      "md", "MD runs driven from Python: granagg md's Simulation with Python callbacks "
            "(docs/python.md).");

  py::class_<PyState>(m, "State",
                      "The run's state during a callback: time, step and box are numbers; "
                      "positions (wrapped into [0, L)), velocities, images (N, 3) and charges "
                      "(N,) are read-only arrays in particle-id order, made when first read.")
      .def_property_readonly("time",
                             [](const PyState& s) { return s.get("time").engine().time(); },
                             "Time, in sqrt(m d^2 / T0).")
      .def_property_readonly("step",
                             [](const PyState& s) { return s.get("step").engine().step(); },
                             "Integration step.")
      .def_property_readonly("box", [](const PyState& s) { return s.get("box").engine().box(); },
                             "Edge L of the cubic periodic box, in d.")
      .def_property_readonly("N", [](const PyState& s) { return s.get("N").engine().size(); },
                             "Number of particles.")
      .def_property_readonly(
          "at_frame",
          [](const PyState& s) {
            const auto& sim = s.get("at_frame");
            return sim.frameStep() == sim.engine().step();
          },
          "True at a frame time of the run's schedule.")
      .def_property_readonly("positions", &PyState::getPositions,
                             "(N, 3) float64, wrapped into [0, L), in d.")
      .def_property_readonly("velocities", &PyState::getVelocities, "(N, 3) float64.")
      .def_property_readonly("images", &PyState::getImages,
                             "(N, 3) int32 image counts: unwrapped = positions + images * box.")
      .def_property_readonly("charges", &PyState::getCharges, "(N,) float64, in q_ref.");

  py::class_<PySimulation>(m, "Simulation",
                           "An MD run (granagg md) driven from Python. config: a TOML file, a "
                           "preset name ('quick', 'paper', 'haff') or a dict of the same tables; "
                           "overrides: dotted keys as --set takes them; out: the run folder (the "
                           "files granagg md writes), or None for a private temporary one.")
      .def(py::init<py::handle, py::handle, py::handle, bool>(), "config"_a = "quick",
           "overrides"_a = py::none(), "out"_a = py::none(), "force"_a = false,
           "Validates the configuration (ValueError with granagg md's message), builds the "
           "initial state and writes t = 0. force: replace the files of a non-empty out.")
      .def_static(
          "restart",
          [](py::handle folder, py::handle overrides) {
            return std::make_unique<PySimulation>(pathArg(folder, "folder"), overrides);
          },
          "folder"_a, "overrides"_a = py::none(),
          "Continues the run in folder from its checkpoint (overrides may set run.t_end).")
      .def("run", &PySimulation::run, "t_end"_a = py::none(), "callbacks"_a = py::none(),
           "progress"_a = false,
           "Runs to t_end (None: the configuration's run.t_end), calling each fn(state) of "
           "callbacks = [(every, fn), ...] every `every` steps or at the frame times "
           "(every='frames'). Ctrl-C or an exception in a callback stops the run with a "
           "checkpoint and is raised here. Returns a dict: steps, seconds, stopped, step, t.")
      .def("checkpoint", &PySimulation::checkpoint, "Writes checkpoint.h5 now.")
      .def("close", &PySimulation::close,
           "Releases the run folder (and removes a temporary one).")
      .def("__enter__", [](PySimulation& s) -> PySimulation& { return s; },
           py::return_value_policy::reference_internal)
      .def("__exit__", [](PySimulation& s, py::args) { s.close(); })
      .def_property_readonly("observables", &PySimulation::observables,
                             "The observables recorded by this object's runs "
                             "(every output.observable_interval steps) as a DataFrame.")
      .def_property_readonly(
          "time", [](PySimulation& s) { return s.sim().engine().time(); }, "The run's time.")
      .def_property_readonly(
          "step", [](PySimulation& s) { return s.sim().engine().step(); }, "The run's step.")
      .def_property_readonly(
          "box", [](PySimulation& s) { return s.sim().engine().box(); }, "Box edge L, in d.")
      .def_property_readonly(
          "N", [](PySimulation& s) { return s.sim().engine().size(); }, "Particles.")
      .def_property_readonly(
          "folder",
          [](const PySimulation& s) -> py::object {
            if (s.temporary()) return py::none();
            return py::str(s.folder().string());
          },
          "The run folder (None for a temporary one).")
      .def_property_readonly(
          "config", [](PySimulation& s) { return md::toToml(s.sim().config()); },
          "The complete configuration as TOML text.")
      .def_property_readonly(
          "frame",
          [](PySimulation& s) {
            const md::Frame f = s.sim().engine().frame();
            py::dict d;
            d["time"] = f.time;
            d["step"] = f.step;
            d["box"] = f.box;
            d["positions"] = PyState::interleave(f.x, f.y, f.z);
            d["velocities"] = PyState::interleave(f.vx, f.vy, f.vz);
            d["images"] = PyState::interleave(f.ix, f.iy, f.iz);
            d["charges"] = readOnlyCopy(f.charge);
            return d;
          },
          "The present state (a copy) as a dict of read-only arrays.");
}

}  // namespace granagg::python
