#pragma once
/// \file Arrays.h
/// The conversions every binding of the Python package shares (docs/python.md): array-likes in,
/// read-only NumPy arrays out, and the argument checks with the CLI's wording.
///
/// In: `positionsArg` takes any array-like of shape (N, 3). A float64 C-contiguous array inside
/// [0, L) is used in place (read-only arrays too); float32 or strided input is converted once by
/// NumPy; coordinates outside [0, L) are wrapped (common::wrapCoordinate) into a copy.
/// Out: `readOnlyArray` moves a std::vector into the array's owner (a capsule), so a result costs
/// no copy, outlives the compute object that made it and cannot be written through.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace granagg::python {
namespace py = pybind11;

/// float64, C-contiguous; NumPy converts other dtypes and layouts (forcecast).
using DoubleArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

/// Positions in the analysis's layout (x0 y0 z0 x1 ...), wrapped into [0, L).
struct Positions {
  DoubleArray array;            ///< keeps the caller's data alive while `data` points into it
  std::vector<double> wrapped;  ///< the wrapped copy, when some coordinate was outside [0, L)
  const double* data = nullptr;
  std::size_t n = 0;
};

/// ValueError unless L is positive and finite: "L must be a positive finite box edge (got x)".
void checkBox(double L, const char* name = "L");

/// `obj` as an (N, 3) array of finite numbers; TypeError when it is not numeric, ValueError for
/// another shape, N = 0 or a non-finite entry (the row is named). `min_rows`: the fewest rows.
DoubleArray pointsArg(py::handle obj, const char* name, std::size_t min_rows = 1);

/// Positions in a cubic periodic box of edge L (checked), wrapped into [0, L).
Positions positionsArg(py::handle obj, double L, const char* name = "positions");

/// A 1-D array of finite float64 values (TypeError / ValueError naming `name`).
std::vector<double> vectorArg(py::handle obj, const char* name, std::size_t min_size = 0);

/// Non-negative integers (sizes, counts), from any 1-D array-like of integral values.
std::vector<std::uint64_t> countsArg(py::handle obj, const char* name);

/// A read-only NumPy array owning `v` (no copy), of shape `shape` (empty: 1-D of v.size()).
template <class T>
py::array readOnlyArray(std::vector<T>&& v, std::vector<py::ssize_t> shape = {}) {
  auto* owner = new std::vector<T>(std::move(v));
  py::capsule free_when_done(owner, [](void* p) { delete static_cast<std::vector<T>*>(p); });
  if (shape.empty()) shape = {static_cast<py::ssize_t>(owner->size())};
  py::array a(py::dtype::of<T>(), shape, {}, owner->data(), free_when_done);
  py::detail::array_proxy(a.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return a;
}

template <class T>
py::array readOnlyCopy(const std::vector<T>& v, std::vector<py::ssize_t> shape = {}) {
  return readOnlyArray(std::vector<T>(v), std::move(shape));
}

/// A table of named columns (rows of doubles) as a pandas DataFrame, with `attrs` as its .attrs.
py::object dataFrame(const std::vector<std::string>& columns,
                     const std::vector<std::vector<double>>& rows, py::dict attrs = py::dict());

/// A str or os.PathLike argument as a path (TypeError naming `name` otherwise).
std::string pathArg(py::handle obj, const char* name);

/// The AttributeError of a result read before compute(): "GridClusters.S: call compute(L,
/// positions) first".
[[noreturn]] void notComputed(const std::string& owner, const std::string& what,
                              const std::string& call);

}  // namespace granagg::python
