/// \file BindIo.cpp
/// granagg.io: the trajectory readers of `granagg analyze` (H5MD files, run folders, LAMMPS text
/// dumps) as a Python iterator, and granagg's CSV tables as pandas DataFrames, read by
/// common::readCsv (docs/python.md).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <filesystem>
#include <memory>
#include <string>

#include "analysis/io/TrajectoryReader.h"
#include "cli/python/Arrays.h"
#include "common/Csv.h"

namespace granagg::python {
namespace an = granagg::analysis;
using namespace pybind11::literals;

namespace {

/// One frame as read; absent elements are None.
struct PyFrame {
  std::size_t index = 0;
  std::int64_t step = 0;
  double time = 0.0, box = 0.0;
  py::array positions, ids;
  py::object velocities = py::none(), charges = py::none(), images = py::none();
};

PyFrame toPython(an::Frame&& f) {
  const py::ssize_t n = static_cast<py::ssize_t>(f.size());
  PyFrame p;
  p.index = f.index;
  p.step = f.step;
  p.time = f.time;
  p.box = f.box;
  p.positions = readOnlyArray(std::move(f.position), {n, 3});
  p.ids = readOnlyArray(std::move(f.id));
  if (f.hasVelocities()) p.velocities = readOnlyArray(std::move(f.velocity), {n, 3});
  if (f.hasCharges()) p.charges = readOnlyArray(std::move(f.charge));
  if (f.hasImages()) p.images = readOnlyArray(std::move(f.image), {n, 3});
  return p;
}

struct PyTrajectory {
  std::unique_ptr<an::TrajectoryReader> reader;
  explicit PyTrajectory(const std::string& path, double lammps_dt) {
    if (!std::filesystem::exists(path))
      throw py::value_error("read_trajectory: no file or folder '" + path + "'.");
    reader = an::openTrajectory(path, lammps_dt);
  }
  PyFrame next() {
    an::Frame f;
    bool more;
    {
      py::gil_scoped_release unlocked;
      more = reader->next(f);
    }
    if (!more) throw py::stop_iteration();
    return toPython(std::move(f));
  }
};

py::object readTable(const std::string& path) {
  if (!std::filesystem::is_regular_file(path))
    throw py::value_error("read_table: no file '" + path + "'.");
  const common::CsvTable t = common::readCsv(path);
  py::dict attrs;
  for (const auto& [k, v] : t.meta) attrs[py::str(k)] = v;
  attrs["source"] = path;
  py::object df = dataFrame(t.columns, t.rows, attrs);
  return df;
}

}  // namespace

void bindIo(py::module_& top) {
  py::module_ m = top.def_submodule(
      "io", "Trajectories (H5MD, run folders, LAMMPS dumps) and granagg's CSV tables, read by "
            "the readers `granagg analyze` uses (docs/python.md).");

  py::class_<PyFrame>(m, "Frame",
                      "One frame: positions wrapped into [0, L)^3 in particle-id order "
                      "(unwrapped = positions + images * box); absent elements are None.")
      .def_readonly("index", &PyFrame::index, "0-based frame number in its file.")
      .def_readonly("step", &PyFrame::step, "Integration step.")
      .def_readonly("time", &PyFrame::time, "Time, in sqrt(m d^2 / T0).")
      .def_readonly("box", &PyFrame::box, "Edge L of the cubic periodic box, in d.")
      .def_readonly("positions", &PyFrame::positions, "(N, 3) float64, in d.")
      .def_readonly("velocities", &PyFrame::velocities, "(N, 3) float64 or None.")
      .def_readonly("charges", &PyFrame::charges, "(N,) float64 or None.")
      .def_readonly("images", &PyFrame::images, "(N, 3) int32 image counts or None.")
      .def_readonly("ids", &PyFrame::ids, "(N,) int64 particle ids.")
      .def("__repr__", [](const PyFrame& f) {
        return "<Frame " + std::to_string(f.index) + ": t = " + common::formatReal(f.time) +
               ", N = " + std::to_string(py::len(f.positions)) + ">";
      });

  py::class_<PyTrajectory>(m, "Trajectory", "An iterator over the frames of a trajectory.")
      .def("__iter__", [](PyTrajectory& t) -> PyTrajectory& { return t; },
           py::return_value_policy::reference_internal, "The iterator itself.")
      .def("__next__", &PyTrajectory::next, "The next Frame (StopIteration at the end).")
      .def_property_readonly("path", [](const PyTrajectory& t) { return t.reader->path(); },
                             "The file being read.")
      .def_property_readonly("format", [](const PyTrajectory& t) { return t.reader->format(); },
                             "'h5md' or 'lammps-dump'.")
      .def_property_readonly(
          "frames_hint", [](const PyTrajectory& t) { return t.reader->frameCountHint(); },
          "Number of frames when the format tells in advance (H5MD), else 0.")
      .def_property_readonly(
          "parameters", [](const PyTrajectory& t) { return t.reader->parameters(); },
          "The run's parameters stored in the file (H5MD /parameters), as strings.");

  m.def(
      "read_trajectory",
      [](py::handle path, double lammps_dt) {
        return PyTrajectory(pathArg(path, "path"), lammps_dt);
      },
      "path"_a, "lammps_dt"_a = 0.0,
      "Iterates the frames of an H5MD file, a run folder (its traj.h5) or a LAMMPS text dump "
      "(lammps_dt: the time step, to give its frames times). Errors name the file and frame.");
  m.def(
      "read_table", [](py::handle path) { return readTable(pathArg(path, "path")); }, "path"_a,
        "A granagg CSV table as a pandas DataFrame; its '# key = value' lines (the provenance: "
        "command, version, parameters) are in .attrs.");
}

}  // namespace granagg::python
