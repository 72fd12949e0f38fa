/// \file module.cpp
/// The extension module `granagg._granagg` (docs/python.md): its four submodules are defined in
/// BindAnalysis.cpp, BindMeanfield.cpp, BindIo.cpp and BindMd.cpp; the package's __init__.py
/// re-exports them as granagg.analysis, granagg.meanfield, granagg.io and granagg.md.
#include <pybind11/pybind11.h>

#include "common/Version.h"
#include "md/config/ConfigParser.h"

namespace granagg::python {
namespace py = pybind11;
void bindAnalysis(py::module_& m);
void bindMeanfield(py::module_& m);
void bindIo(py::module_& m);
void bindMd(py::module_& m);
}  // namespace granagg::python

PYBIND11_MODULE(_granagg, m) {
  namespace py = pybind11;
  m.doc() = "granagg: aggregation in charged granular gases (MD, analysis, mean field).";
  m.attr("__version__") = granagg::common::versionString();
  // A configuration error is a ValueError whose .key names the offending key ("system.phi").
  static py::exception<granagg::md::ConfigError> config_error(m, "ConfigError",
                                                              PyExc_ValueError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const granagg::md::ConfigError& e) {
      py::object instance =
          py::reinterpret_borrow<py::object>(config_error.ptr())(e.what());
      instance.attr("key") = e.key();
      PyErr_SetObject(config_error.ptr(), instance.ptr());
    }
  });
  granagg::python::bindAnalysis(m);
  granagg::python::bindMeanfield(m);
  granagg::python::bindIo(m);
  granagg::python::bindMd(m);
}
