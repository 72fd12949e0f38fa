/// \file Arrays.cpp
/// The package's argument conversions (Arrays.h).
#include "cli/python/Arrays.h"

#include <pybind11/stl.h>

#include <cmath>
#include <limits>

#include "common/Box.h"
#include "common/Csv.h"

namespace granagg::python {

void checkBox(double L, const char* name) {
  if (!(L > 0.0) || !std::isfinite(L))
    throw py::value_error(std::string(name) + " must be a positive finite box edge (got " +
                          common::formatReal(L) + ").");
}

namespace {

std::string shapeText(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t d = 0; d < a.ndim(); ++d)
    s += (d ? ", " : "") + std::to_string(a.shape(d));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

DoubleArray asDoubles(py::handle obj, const char* name) {
  if (obj.is_none()) throw py::type_error(std::string(name) + " must be an array of numbers, "
                                          "got None.");
  // Refuse what NumPy would only read as objects or text: strings, lists of strings.
  py::array probe = py::array::ensure(obj);
  if (!probe) throw py::type_error(std::string(name) + " must be an array-like of numbers.");
  const char kind = probe.dtype().kind();
  if (kind != 'f' && kind != 'i' && kind != 'u' && kind != 'b')
    throw py::type_error(std::string(name) + " must hold numbers (got dtype " +
                         std::string(py::str(probe.dtype())) + ").");
  DoubleArray a = DoubleArray::ensure(probe);
  if (!a) throw py::type_error(std::string(name) + " must be an array-like of numbers.");
  return a;
}

}  // namespace

DoubleArray pointsArg(py::handle obj, const char* name, std::size_t min_rows) {
  DoubleArray a = asDoubles(obj, name);
  if (a.ndim() != 2 || a.shape(1) != 3)
    throw py::value_error(std::string(name) + " must have shape (N, 3), got " + shapeText(a) +
                          ".");
  const auto n = static_cast<std::size_t>(a.shape(0));
  if (n < min_rows)
    throw py::value_error(std::string(name) + " must hold at least " + std::to_string(min_rows) +
                          " rows, got " + std::to_string(n) + ".");
  const double* p = a.data();
  for (std::size_t i = 0; i < 3 * n; ++i)
    if (!std::isfinite(p[i]))
      throw py::value_error(std::string(name) + " must be finite: row " + std::to_string(i / 3) +
                            " holds " + common::formatReal(p[i]) + ".");
  return a;
}

Positions positionsArg(py::handle obj, double L, const char* name) {
  checkBox(L);
  Positions r;
  r.array = pointsArg(obj, name);
  r.n = static_cast<std::size_t>(r.array.shape(0));
  r.data = r.array.data();
  bool inside = true;
  for (std::size_t i = 0; i < 3 * r.n && inside; ++i) inside = r.data[i] >= 0.0 && r.data[i] < L;
  if (!inside) {  // periodic images of the box: wrapped, not refused
    r.wrapped.assign(r.data, r.data + 3 * r.n);
    for (double& x : r.wrapped) {
      std::int32_t image = 0;
      if (!common::wrapCoordinate(x, image, L))
        throw py::value_error(std::string(name) + " holds a coordinate too far outside the box "
                              "to wrap (" + common::formatReal(x) + " for L = " +
                              common::formatReal(L) + ").");
    }
    r.data = r.wrapped.data();
  }
  return r;
}

std::vector<double> vectorArg(py::handle obj, const char* name, std::size_t min_size) {
  DoubleArray a = asDoubles(obj, name);
  if (a.ndim() != 1)
    throw py::value_error(std::string(name) + " must be one-dimensional, got shape " +
                          shapeText(a) + ".");
  std::vector<double> v(a.data(), a.data() + a.size());
  if (v.size() < min_size)
    throw py::value_error(std::string(name) + " must hold at least " + std::to_string(min_size) +
                          " values, got " + std::to_string(v.size()) + ".");
  for (std::size_t i = 0; i < v.size(); ++i)
    if (!std::isfinite(v[i]))
      throw py::value_error(std::string(name) + " must be finite: entry " + std::to_string(i) +
                            " is " + common::formatReal(v[i]) + ".");
  return v;
}

std::vector<std::uint64_t> countsArg(py::handle obj, const char* name) {
  const std::vector<double> v = vectorArg(obj, name);
  std::vector<std::uint64_t> out(v.size());
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (v[i] < 0.0 || v[i] != std::floor(v[i]) || v[i] > 9.007199254740992e15)
      throw py::value_error(std::string(name) + " must hold non-negative integers: entry " +
                            std::to_string(i) + " is " + common::formatReal(v[i]) + ".");
    out[i] = static_cast<std::uint64_t>(v[i]);
  }
  return out;
}

py::object dataFrame(const std::vector<std::string>& columns,
                     const std::vector<std::vector<double>>& rows, py::dict attrs) {
  using namespace pybind11::literals;
  py::dict data;
  for (std::size_t j = 0; j < columns.size(); ++j) {
    std::vector<double> col;
    col.reserve(rows.size());
    for (const auto& row : rows) col.push_back(row[j]);
    data[py::str(columns[j])] = py::array(py::cast(col));
  }
  py::object df =
      py::module_::import("pandas").attr("DataFrame")(data, "columns"_a = py::cast(columns));
  df.attr("attrs") = attrs;
  return df;
}

std::string pathArg(py::handle obj, const char* name) {
  if (py::isinstance<py::str>(obj)) return obj.cast<std::string>();
  if (py::isinstance(obj, py::module_::import("os").attr("PathLike")))
    return py::str(py::module_::import("os").attr("fspath")(obj));
  throw py::type_error(std::string(name) + " must be a path (str or os.PathLike).");
}

void notComputed(const std::string& owner, const std::string& what, const std::string& call) {
  throw py::attribute_error(owner + "." + what + ": no result yet; call " + call + " first.");
}

}  // namespace granagg::python
