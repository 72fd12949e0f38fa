/// \file BindAnalysis.cpp
/// granagg.analysis: the per-frame compute objects of `granagg analyze` in freud's style
/// (docs/python.md). Each is configured in its constructor, compute(...) returns self, and the
/// results are read-only NumPy arrays owned by the object (Arrays.h). Every computation is the
/// C++ of analysis/ that `granagg analyze` runs; this file only converts arguments and results.
/// The GIL is released while the C++ computes, so that its OpenMP threads and other Python
/// threads run.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "analysis/clusters/GridClusters.h"
#include "analysis/clusters/ParticleClusters.h"
#include "analysis/stats/GrowthMarkers.h"
#include "analysis/stats/Msd.h"
#include "analysis/stats/PowerLawFit.h"
#include "analysis/stats/PowerLawMle.h"
#include "analysis/stats/StructureFactor.h"
#include "analysis/stats/VelocityStats.h"
#include "cli/python/Arrays.h"
#include "common/Csv.h"

namespace granagg::python {
namespace an = granagg::analysis;
using namespace pybind11::literals;

namespace {

const double NaN = std::numeric_limits<double>::quiet_NaN();

/// The scalars and the size distribution shared by both cluster definitions.
struct ClusterResult {
  py::array labels, cluster_sizes, sizes, counts;
  double S = NaN, S_without_largest = NaN, largest_share = NaN;
  std::size_t clusters = 0;
  std::uint64_t largest = 0;
};

ClusterResult clusterResult(const an::ClusterSizes& cs, const std::vector<std::int32_t>& labels,
                            std::vector<py::ssize_t> label_shape) {
  ClusterResult r;
  std::vector<std::uint64_t> per_label(cs.clusters, 0);
  for (std::int32_t l : labels)
    if (l >= 0) ++per_label[static_cast<std::size_t>(l)];
  std::vector<std::uint64_t> s, n;
  for (const auto& [size, count] : cs.n_s) {
    s.push_back(size);
    n.push_back(count);
  }
  r.labels = readOnlyCopy(labels, std::move(label_shape));
  r.cluster_sizes = readOnlyArray(std::move(per_label));
  r.sizes = readOnlyArray(std::move(s));
  r.counts = readOnlyArray(std::move(n));
  r.S = cs.S;
  r.S_without_largest = cs.S_without_largest;
  r.largest_share = cs.largest_share;
  r.clusters = cs.clusters;
  r.largest = cs.largest;
  return r;
}

/// Properties of a compute object: raise AttributeError before the first compute.
template <class Owner>
const ClusterResult& computed(const Owner& o, const char* what) {
  if (!o.result) notComputed(Owner::NAME, what, "compute(L, positions)");
  return *o.result;
}

struct PyGridClusters {
  static constexpr const char* NAME = "GridClusters";
  an::GridClusters impl;
  std::optional<ClusterResult> result;
  double occupied = NaN, cell_size = NaN, min_count = NaN;
  int cells = 0;

  static an::GridClustersParams params(double spacing, double min_fill, const std::string& assign,
                                       int min_count) {
    if (!(spacing > 0.0) || !std::isfinite(spacing))
      throw py::value_error("spacing must be a positive cell edge in d (got " +
                            common::formatReal(spacing) + ").");
    if (!(min_fill > 0.0 && min_fill <= 1.0))
      throw py::value_error("min_fill must lie in (0, 1] (got " + common::formatReal(min_fill) +
                            ").");
    if (min_count < 0)
      throw py::value_error("min_count must be >= 0 (0: use min_fill), got " +
                            std::to_string(min_count) + ".");
    an::GridClustersParams p;
    p.spacing = spacing;
    p.min_fill = min_fill;
    p.min_count = min_count;
    if (assign == "ngp")
      p.assignment = an::GridAssignment::Nearest;
    else if (assign == "cic")
      p.assignment = an::GridAssignment::CloudInCell;
    else
      throw py::value_error("assign must be 'ngp' or 'cic' (got '" + assign + "').");
    return p;
  }
  PyGridClusters(double spacing, double min_fill, const std::string& assign, int min_count)
      : impl(params(spacing, min_fill, assign, min_count)) {}

  void compute(double L, py::handle positions) {
    Positions p = positionsArg(positions, L);
    {
      py::gil_scoped_release unlocked;
      impl.compute(p.data, p.n, L);
    }
    const py::ssize_t n = impl.cellsPerSide();
    result = clusterResult(impl.result(), impl.labels(), {n, n, n});
    occupied = impl.occupiedFraction();
    cell_size = impl.cellSize();
    min_count = impl.minCount();
    cells = impl.cellsPerSide();
  }
};

struct PyParticleClusters {
  static constexpr const char* NAME = "ParticleClusters";
  an::ParticleClusters impl;
  std::optional<ClusterResult> result;
  py::array contacts;
  std::size_t bonds = 0;

  static an::ParticleClustersParams params(double tolerance) {
    if (!(tolerance >= 0.0) || !std::isfinite(tolerance))
      throw py::value_error("tolerance must be >= 0 and finite, in d (got " +
                            common::formatReal(tolerance) + ").");
    an::ParticleClustersParams p;
    p.tolerance = tolerance;
    return p;
  }
  explicit PyParticleClusters(double tolerance) : impl(params(tolerance)) {}

  void compute(double L, py::handle positions) {
    Positions p = positionsArg(positions, L);
    {
      py::gil_scoped_release unlocked;
      impl.compute(p.data, p.n, L);
    }
    result = clusterResult(impl.result(), impl.labels(), {});
    contacts = readOnlyCopy(impl.contacts());
    bonds = impl.bonds();
  }
};

struct SkResult {
  py::array k, S_k, counts;
  double length = NaN, k1 = NaN, k_cut = NaN;
  std::size_t mesh = 0;
  std::optional<an::VelocityStructure> velocity;
  py::array S_par, S_perp;
};

struct PyStructureFactor {
  an::StructureFactorOptions options;
  an::StructureFactorMesh mesh;
  std::optional<SkResult> result;

  PyStructureFactor(double k_cut, double h_max, std::size_t max_mesh) {
    if (!(k_cut > 0.0) || !std::isfinite(k_cut))
      throw py::value_error("k_cut must be a positive wavenumber in 1/d (got " +
                            common::formatReal(k_cut) + ").");
    if (!(h_max > 0.0) || !std::isfinite(h_max))
      throw py::value_error("h_max must be a positive mesh spacing in d (got " +
                            common::formatReal(h_max) + ").");
    if (max_mesh < 2 || max_mesh > 2048)
      throw py::value_error("max_mesh must lie in [2, 2048] (got " + std::to_string(max_mesh) +
                            ").");
    options.k_cut = k_cut;
    options.h_max = h_max;
    options.max_mesh = max_mesh;
  }

  void compute(double L, py::handle positions, py::handle velocities) {
    Positions p = positionsArg(positions, L);
    an::Frame f;
    f.box = L;
    f.position.assign(p.data, p.data + 3 * p.n);
    if (!velocities.is_none()) {
      DoubleArray v = pointsArg(velocities, "velocities", 2);
      if (static_cast<std::size_t>(v.shape(0)) != p.n)
        throw py::value_error("velocities must have as many rows as positions (" +
                              std::to_string(p.n) + "), got " + std::to_string(v.shape(0)) + ".");
      f.velocity.assign(v.data(), v.data() + 3 * p.n);
    }
    an::StructureFactor sk;
    std::optional<an::VelocityStructure> vs;
    {
      py::gil_scoped_release unlocked;
      sk = an::structureFactor(f, options, mesh);
      if (f.hasVelocities()) vs = an::velocityStructure(f, options, mesh);
    }
    SkResult r;
    std::vector<double> counts(sk.modes.begin(), sk.modes.end());
    r.k = readOnlyArray(std::move(sk.k));
    r.S_k = readOnlyArray(std::move(sk.S));
    r.counts = readOnlyArray(std::vector<std::uint64_t>(sk.modes.begin(), sk.modes.end()));
    r.length = sk.length;
    r.k1 = sk.k1;
    r.k_cut = sk.k_cut;
    r.mesh = sk.mesh;
    if (vs) {
      r.S_par = readOnlyCopy(vs->S_long);
      r.S_perp = readOnlyCopy(vs->S_trans);
      r.velocity = std::move(vs);
    }
    result = std::move(r);
  }
  const SkResult& get(const char* what) const {
    if (!result) notComputed("StructureFactor", what, "compute(L, positions)");
    return *result;
  }
  const an::VelocityStructure& velocity(const char* what) const {
    const SkResult& r = get(what);
    if (!r.velocity)
      throw py::attribute_error(std::string("StructureFactor.") + what +
                                ": needs velocities; call compute(L, positions, velocities).");
    return *r.velocity;
  }
};

struct PyPowerLawMle {
  std::size_t min_tail;
  std::optional<an::PowerLawMleResult> result;
  explicit PyPowerLawMle(long long min_tail_) {
    if (min_tail_ < 2)
      throw py::value_error("min_tail must be >= 2 (got " + std::to_string(min_tail_) + ").");
    min_tail = static_cast<std::size_t>(min_tail_);
  }
  void fit(py::handle sizes, py::handle counts) {
    const std::vector<std::uint64_t> s = countsArg(sizes, "sizes");
    for (std::size_t i = 0; i < s.size(); ++i)
      if (s[i] < 1) throw py::value_error("sizes must be >= 1: entry " + std::to_string(i) +
                                          " is 0.");
    an::PowerLawMleResult r;
    if (counts.is_none()) {
      py::gil_scoped_release unlocked;
      r = an::fitDiscretePowerLawKs(s, min_tail);
    } else {
      const std::vector<std::uint64_t> c = countsArg(counts, "counts");
      if (c.size() != s.size())
        throw py::value_error("counts must have the length of sizes (" +
                              std::to_string(s.size()) + "), got " + std::to_string(c.size()) +
                              ".");
      std::map<std::uint64_t, std::uint64_t> hist;
      for (std::size_t i = 0; i < s.size(); ++i)
        if (c[i] > 0) hist[s[i]] += c[i];
      py::gil_scoped_release unlocked;
      r = an::fitDiscretePowerLawKs(hist, min_tail);
    }
    result = r;
  }
  const an::PowerLawMleResult& get(const char* what) const {
    if (!result) notComputed("PowerLawMle", what, "fit(sizes, counts)");
    return *result;
  }
};

struct PyMsd {
  std::string origins;
  std::size_t max_bytes;
  py::array t, msd;
  bool done = false;
  PyMsd(const std::string& o, double max_gib) : origins(o) {
    if (o != "first" && o != "all")
      throw py::value_error("origins must be 'first' or 'all' (got '" + o + "').");
    if (!(max_gib > 0.0)) throw py::value_error("max_gib must be positive.");
    max_bytes = static_cast<std::size_t>(max_gib * 1073741824.0);
  }
  void compute(py::handle times, py::handle positions) {
    const std::vector<double> tv = vectorArg(times, "times", 1);
    DoubleArray a = DoubleArray::ensure(positions);
    if (!a || a.ndim() != 3 || a.shape(2) != 3)
      throw py::value_error("positions must be unwrapped positions of shape (F, N, 3).");
    if (static_cast<std::size_t>(a.shape(0)) != tv.size())
      throw py::value_error("positions must hold one frame per time (" +
                            std::to_string(tv.size()) + "), got " + std::to_string(a.shape(0)) +
                            ".");
    const auto n = static_cast<std::size_t>(a.shape(1));
    for (std::size_t i = 0; i + 1 < tv.size(); ++i)
      if (!(tv[i + 1] > tv[i])) throw py::value_error("times must increase.");
    // Unwrapped positions as a frame with zero image counts in a box that never wraps them.
    an::Frame f;
    f.box = 1.0;
    f.image.assign(3 * n, 0);
    an::MsdFromOrigin first;
    an::MsdAllOrigins all(max_bytes);
    for (std::size_t k = 0; k < tv.size(); ++k) {
      f.index = k;
      f.time = tv[k];
      f.position.assign(a.data() + 3 * n * k, a.data() + 3 * n * (k + 1));
      for (double x : f.position)
        if (!std::isfinite(x)) throw py::value_error("positions must be finite.");
      if (origins == "first")
        first.accumulate(f);
      else
        all.accumulate(f);
    }
    if (origins == "first") {
      t = readOnlyCopy(first.times());
      msd = readOnlyCopy(first.msd());
    } else {
      if (!all.available())
        throw py::value_error("origins='all' needs at least 2 evenly spaced frames within "
                              "max_gib: " + (all.reason().empty() ? std::string("too few frames")
                                                                  : all.reason()));
      std::vector<double> lag;
      std::vector<double> m = all.compute(lag);
      t = readOnlyArray(std::move(lag));
      msd = readOnlyArray(std::move(m));
    }
    done = true;
  }
};

struct PySpeedDistribution {
  an::SpeedHistogram hist;
  std::optional<an::VelocityMoments> moments;
  py::array v, density, maxwellian;
  PySpeedDistribution(double v_max, int bins) : hist(checked(v_max, bins), bins) {}
  static double checked(double v_max, int bins) {
    if (!(v_max > 0.0) || !std::isfinite(v_max))
      throw py::value_error("v_max must be positive (got " + common::formatReal(v_max) + ").");
    if (bins < 1) throw py::value_error("bins must be >= 1 (got " + std::to_string(bins) + ").");
    return v_max;
  }
  void compute(py::handle velocities) {
    DoubleArray a = pointsArg(velocities, "velocities", 2);
    const std::vector<double> vel(a.data(), a.data() + a.size());
    hist.reset();
    hist.add(vel);
    moments = an::velocityMoments(vel);
    std::vector<double> centre(hist.bins()), mw(hist.bins());
    for (int k = 0; k < hist.bins(); ++k) {
      centre[k] = hist.binLow(k) + 0.5 * hist.binWidth();
      mw[k] = an::maxwellianScaledSpeedDensity(centre[k]);
    }
    v = readOnlyArray(std::move(centre));
    density = readOnlyArray(hist.density());
    maxwellian = readOnlyArray(std::move(mw));
  }
  const an::VelocityMoments& get(const char* what) const {
    if (!moments) notComputed("SpeedDistribution", what, "compute(velocities)");
    return *moments;
  }
};

struct PyGrowthExponent {
  double t_min, t_max, p, confidence;
  int replicates;
  std::uint64_t seed;
  std::optional<an::PowerLawFitResult> fit_result;
  std::optional<an::GrowthRegime> regime;
  py::array local_slope;

  PyGrowthExponent(py::handle window, double p_, double confidence_, int replicates_,
                   std::uint64_t seed_)
      : p(p_), confidence(confidence_), replicates(replicates_), seed(seed_) {
    const std::vector<double> w = vectorArg(window, "window");
    if (w.size() != 2 || !(w[0] > 0.0) || !(w[1] > w[0]))
      throw py::value_error("window must be (t_min, t_max) with 0 < t_min < t_max.");
    t_min = w[0];
    t_max = w[1];
    if (!(p > 1.0)) throw py::value_error("p must be > 1 (got " + common::formatReal(p) + ").");
    if (!(confidence > 0.0 && confidence < 1.0))
      throw py::value_error("confidence must lie in (0, 1).");
    if (replicates < 10) throw py::value_error("replicates must be >= 10.");
  }

  void fit(py::handle times, py::handle values) {
    const std::vector<double> t = vectorArg(times, "t", 3);
    for (std::size_t i = 0; i + 1 < t.size(); ++i)
      if (!(t[i + 1] > t[i])) throw py::value_error("t must increase.");
    DoubleArray y = DoubleArray::ensure(values);
    if (!y || (y.ndim() != 1 && y.ndim() != 2) || y.shape(y.ndim() - 1) != py::ssize_t(t.size()))
      throw py::value_error("y must have the length of t (" + std::to_string(t.size()) +
                            "), or shape (runs, " + std::to_string(t.size()) + ").");
    std::vector<std::vector<double>> runs;
    const std::size_t R = y.ndim() == 1 ? 1 : static_cast<std::size_t>(y.shape(0));
    for (std::size_t r = 0; r < R; ++r)
      runs.emplace_back(y.data() + r * t.size(), y.data() + (r + 1) * t.size());
    std::vector<double> mean(t.size(), 0.0);
    for (const auto& run : runs)
      for (std::size_t k = 0; k < t.size(); ++k) mean[k] += run[k] / double(R);
    an::PowerLawFitResult f =
        R == 1 ? an::fitPowerLaw(t, mean, t_min, t_max, confidence)
               : an::bootstrapPowerLaw(t, runs, t_min, t_max, replicates, seed, confidence);
    std::vector<double> z = an::localSlope(t, mean, p);
    regime = an::classifyGrowth(t, mean, z);
    fit_result = f;
    local_slope = readOnlyArray(std::move(z));
  }
  const an::PowerLawFitResult& get(const char* what) const {
    if (!fit_result) notComputed("GrowthExponent", what, "fit(t, y)");
    return *fit_result;
  }
};

double validOrNaN(bool valid, double x) { return valid ? x : NaN; }

/// Wall seconds of `repeats` calls of the C++ compute alone, on positions converted once: the
/// reference of the package's call overhead (scripts/bench_python.py, docs/benchmarks.md).
std::vector<double> timeCpp(const std::string& what, double L, py::handle positions,
                            int repeats) {
  Positions p = positionsArg(positions, L);
  an::Frame f;
  f.box = L;
  f.position.assign(p.data, p.data + 3 * p.n);
  an::ParticleClusters pc;
  an::GridClusters gc;
  an::StructureFactorMesh mesh;
  std::vector<double> seconds;
  py::gil_scoped_release unlocked;
  for (int r = 0; r < repeats; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    if (what == "ParticleClusters")
      pc.compute(f);
    else if (what == "GridClusters")
      gc.compute(f);
    else if (what == "StructureFactor")
      an::structureFactor(f, an::StructureFactorOptions{}, mesh);
    else
      throw std::invalid_argument("_time_cpp: unknown compute '" + what + "'");
    seconds.push_back(
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  return seconds;
}

}  // namespace

void bindAnalysis(py::module_& top) {
  py::module_ m = top.def_submodule(
      "analysis",
      "Per-frame compute objects of `granagg analyze` (clusters, S(k), power laws, MSD, speeds, "
      "growth exponents), in freud's style: configure in the constructor, compute(...) returns "
      "self, results are read-only NumPy arrays (docs/python.md).");

  m.def("_time_cpp", &timeCpp, "what"_a, "L"_a, "positions"_a, "repeats"_a = 5,
        "Benchmarks only: wall seconds of each of `repeats` calls of the C++ compute of "
        "'ParticleClusters', 'GridClusters' or 'StructureFactor', without the binding.");

  using G = PyGridClusters;
  py::class_<G>(m, "GridClusters",
                "Clusters on a grid, the paper's method (docs/model.md section 10): cells of "
                "edge h = L / floor(L / spacing) holding a filling fraction >= min_fill are "
                "occupied; face-sharing occupied cells form a cluster across the periodic "
                "boundary. Sizes count sites.")
      .def(py::init<double, double, const std::string&, int>(), "spacing"_a = 2.0,
           "min_fill"_a = 0.25, "assign"_a = "ngp", "min_count"_a = 0,
           "spacing: target cell edge in d; min_fill: occupied filling fraction in (0, 1]; "
           "assign: 'ngp' (a centre counts in its cell) or 'cic'; min_count > 0 replaces "
           "min_fill by a count per cell.")
      .def(
          "compute",
          [](G& g, double L, py::handle positions) -> G& {
            g.compute(L, positions);
            return g;
          },
          "L"_a, "positions"_a, py::return_value_policy::reference_internal,
          "Labels the clusters of positions (N, 3) in the cubic periodic box of edge L "
          "(coordinates outside [0, L) are wrapped). Returns self.")
      .def_property_readonly(
          "labels", [](const G& g) { return computed(g, "labels").labels; },
          "Cluster label per cell, shape (n, n, n) indexed [ix, iy, iz]; -1 for an empty cell.")
      .def_property_readonly(
          "cluster_sizes", [](const G& g) { return computed(g, "cluster_sizes").cluster_sizes; },
          "Sites of each cluster, indexed by label.")
      .def_property_readonly(
          "S", [](const G& g) { return computed(g, "S").S; },
          "Mean cluster size sum s^2 N_s / sum s N_s (NaN without a cluster).")
      .def_property_readonly(
          "S_without_largest",
          [](const G& g) { return computed(g, "S_without_largest").S_without_largest; },
          "S of all clusters but the largest (NaN with fewer than two).")
      .def_property_readonly(
          "largest_share", [](const G& g) { return computed(g, "largest_share").largest_share; },
          "The largest cluster's share of the occupied sites.")
      .def_property_readonly(
          "occupied_fraction",
          [](const G& g) {
            computed(g, "occupied_fraction");
            return g.occupied;
          },
          "Fraction of occupied cells.")
      .def_property_readonly(
          "size_distribution",
          [](const G& g) {
            const auto& r = computed(g, "size_distribution");
            return py::make_tuple(r.sizes, r.counts);
          },
          "(s, N_s): the sizes present and the number of clusters of each size.")
      .def_property_readonly(
          "cells_per_side",
          [](const G& g) {
            computed(g, "cells_per_side");
            return g.cells;
          },
          "n, the cells per side of the last compute.")
      .def_property_readonly(
          "cell_size",
          [](const G& g) {
            computed(g, "cell_size");
            return g.cell_size;
          },
          "h = L / n, in d.")
      .def_property_readonly(
          "min_count",
          [](const G& g) {
            computed(g, "min_count");
            return g.min_count;
          },
          "Centres per cell from which a cell is occupied.");

  using P = PyParticleClusters;
  py::class_<P>(m, "ParticleClusters",
                "Contact clusters (docs/model.md section 10): particles within 1 + tolerance "
                "(minimum image) are bonded; clusters are the connected components across the "
                "periodic boundary. Sizes count particles; a monomer is a cluster of size 1.")
      .def(py::init<double>(), "tolerance"_a = 0.05, "tolerance: bond when |r_ij| <= 1 + "
           "tolerance, in d.")
      .def(
          "compute",
          [](P& p, double L, py::handle positions) -> P& {
            p.compute(L, positions);
            return p;
          },
          "L"_a, "positions"_a, py::return_value_policy::reference_internal,
          "Finds the clusters of positions (N, 3) in the cubic periodic box of edge L "
          "(coordinates outside [0, L) are wrapped). Returns self.")
      .def_property_readonly(
          "labels", [](const P& p) { return computed(p, "labels").labels; },
          "Cluster label per particle, clusters numbered 0.. in order of their first particle.")
      .def_property_readonly(
          "cluster_sizes", [](const P& p) { return computed(p, "cluster_sizes").cluster_sizes; },
          "Particles of each cluster, indexed by label.")
      .def_property_readonly("S", [](const P& p) { return computed(p, "S").S; },
                             "Mean cluster size sum s^2 N_s / sum s N_s.")
      .def_property_readonly(
          "S_without_largest",
          [](const P& p) { return computed(p, "S_without_largest").S_without_largest; },
          "S of all clusters but the largest (NaN with fewer than two).")
      .def_property_readonly(
          "largest_share", [](const P& p) { return computed(p, "largest_share").largest_share; },
          "The largest cluster's share of the particles.")
      .def_property_readonly(
          "size_distribution",
          [](const P& p) {
            const auto& r = computed(p, "size_distribution");
            return py::make_tuple(r.sizes, r.counts);
          },
          "(s, N_s): the sizes present and the number of clusters of each size.")
      .def_property_readonly(
          "contacts",
          [](const P& p) {
            computed(p, "contacts");
            return p.contacts;
          },
          "Partners within 1 + tolerance of each particle.")
      .def_property_readonly(
          "bonds",
          [](const P& p) {
            computed(p, "bonds");
            return p.bonds;
          },
          "Bonded pairs.");

  using SF = PyStructureFactor;
  py::class_<SF>(m, "StructureFactor",
                 "S(k) = <|rho_k|^2> / N, rho_k = sum_j exp(-i k.r_j), in shells |k| in "
                 "[k_m - dk/2, k_m + dk/2), k_m = m 2 pi / L (an ideal gas gives 1), and the "
                 "density length l = 2 pi / k_1, k_1 the first moment over k_m <= k_cut "
                 "(docs/model.md section 10). With velocities also S_par, S_perp and their "
                 "lengths l_par, l_perp.")
      .def(py::init<double, double, std::size_t>(), "k_cut"_a = M_PI, "h_max"_a = 0.5,
           "max_mesh"_a = 512,
           "k_cut: cut-off of the first moment in 1/d; h_max: largest mesh spacing in d; "
           "max_mesh: largest mesh per side.")
      .def(
          "compute",
          [](SF& s, double L, py::handle positions, py::handle velocities) -> SF& {
            s.compute(L, positions, velocities);
            return s;
          },
          "L"_a, "positions"_a, "velocities"_a = py::none(),
          py::return_value_policy::reference_internal,
          "S(k) and l of positions (N, 3) in the periodic box of edge L; with velocities "
          "(N, 3), the velocity field's structure as well. Returns self.")
      .def_property_readonly("k", [](const SF& s) { return s.get("k").k; },
                             "Shell centres k_m, in 1/d.")
      .def_property_readonly("S_k", [](const SF& s) { return s.get("S_k").S_k; },
                             "S(k_m): mean over the shell's independent wave vectors.")
      .def_property_readonly("counts", [](const SF& s) { return s.get("counts").counts; },
                             "Independent wave vectors (one of each +-k) per shell.")
      .def_property_readonly("length", [](const SF& s) { return s.get("length").length; },
                             "l_density = 2 pi / k_1, in d.")
      .def_property_readonly("k1", [](const SF& s) { return s.get("k1").k1; },
                             "First moment k_1 over k_m <= k_cut.")
      .def_property_readonly("mesh", [](const SF& s) { return s.get("mesh").mesh; },
                             "Mesh points per side M.")
      .def_property_readonly("S_par", [](const SF& s) {
        s.velocity("S_par");
        return s.result->S_par;
      }, "S_par(k_m) = <|k^.u|^2> / (N T_g) (needs velocities).")
      .def_property_readonly("S_perp", [](const SF& s) {
        s.velocity("S_perp");
        return s.result->S_perp;
      }, "S_perp(k_m) = <|u - k^(k^.u)|^2> / (2 N T_g) (needs velocities).")
      .def_property_readonly("l_par", [](const SF& s) { return s.velocity("l_par").length_long; },
                             "Longitudinal length 2 pi / k_1 of S_par, in d.")
      .def_property_readonly("l_perp",
                             [](const SF& s) { return s.velocity("l_perp").length_trans; },
                             "Vortex length 2 pi / k_1 of S_perp, in d.")
      .def_property_readonly("T_g", [](const SF& s) { return s.velocity("T_g").T_g; },
                             "Granular temperature of the velocities, in T0.");

  using PL = PyPowerLawMle;
  py::class_<PL>(m, "PowerLawMle",
                 "Discrete power law N_s ~ s^-tau by maximum likelihood, s_min by the smallest "
                 "Kolmogorov-Smirnov distance (Clauset, Shalizi & Newman 2009).")
      .def(py::init<long long>(), "min_tail"_a = 10,
           "min_tail: fewest samples an s_min may leave in the tail.")
      .def(
          "fit",
          [](PL& p, py::handle sizes, py::handle counts) -> PL& {
            p.fit(sizes, counts);
            return p;
          },
          "sizes"_a, "counts"_a = py::none(), py::return_value_policy::reference_internal,
          "Fits the sizes (one per cluster), or a histogram: sizes with their counts. Returns "
          "self; tau is NaN (valid False) when the tail is too small.")
      .def_property_readonly("valid", [](const PL& p) { return p.get("valid").valid; },
                             "False when the tail is too small or the likelihood has no maximum.")
      .def_property_readonly("tau", [](const PL& p) {
        const auto& r = p.get("tau");
        return validOrNaN(r.valid, r.tau);
      }, "MLE of tau.")
      .def_property_readonly("tau_err", [](const PL& p) {
        const auto& r = p.get("tau_err");
        return validOrNaN(r.valid, r.tau_err);
      }, "Standard error of tau (Fisher information).")
      .def_property_readonly("s_min", [](const PL& p) { return p.get("s_min").xmin; },
                             "Lower bound of the tail.")
      .def_property_readonly("n_tail", [](const PL& p) { return p.get("n_tail").n_tail; },
                             "Samples >= s_min.")
      .def_property_readonly("ks", [](const PL& p) { return p.get("ks").ks; },
                             "KS distance of the tail from the fitted law.");

  py::class_<PyMsd>(m, "Msd",
                    "Mean-squared displacement of unwrapped positions: from the first frame "
                    "(origins='first', the aging gas's primary MSD) or averaged over all time "
                    "origins of evenly spaced frames by FFT (origins='all').")
      .def(py::init<const std::string&, double>(), "origins"_a = "first", "max_gib"_a = 1.0,
           "origins: 'first' or 'all'; max_gib: memory allowed for the stored frames.")
      .def(
          "compute",
          [](PyMsd& s, py::handle times, py::handle positions) -> PyMsd& {
            s.compute(times, positions);
            return s;
          },
          "times"_a, "positions"_a, py::return_value_policy::reference_internal,
          "times (F,), unwrapped positions (F, N, 3) (wrapped + image * L). Returns self.")
      .def_property_readonly("t", [](const PyMsd& s) {
        if (!s.done) notComputed("Msd", "t", "compute(times, positions)");
        return s.t;
      }, "Times (origins='first') or lags (origins='all').")
      .def_property_readonly("msd", [](const PyMsd& s) {
        if (!s.done) notComputed("Msd", "msd", "compute(times, positions)");
        return s.msd;
      }, "MSD in d^2.");

  using SD = PySpeedDistribution;
  py::class_<SD>(m, "SpeedDistribution",
                 "Granular temperature, Sonine coefficient a2 and the distribution of the scaled "
                 "speed v~ = |c| / <|c|^2>^(1/2) beside the Maxwellian, from peculiar velocities.")
      .def(py::init<double, int>(), "v_max"_a = 4.0, "bins"_a = 80,
           "Histogram of v~ on [0, v_max) with `bins` equal bins.")
      .def(
          "compute",
          [](SD& s, py::handle v) -> SD& {
            s.compute(v);
            return s;
          },
          "velocities"_a, py::return_value_policy::reference_internal,
          "velocities (N, 3). Returns self.")
      .def_property_readonly("T_g", [](const SD& s) { return s.get("T_g").T_g; },
                             "(1/3) <|c|^2>, in T0.")
      .def_property_readonly("a2", [](const SD& s) { return s.get("a2").a2; },
                             "(3/5) <c^4>/<c^2>^2 - 1 (0 for a Maxwellian).")
      .def_property_readonly("a2_err", [](const SD& s) { return s.get("a2_err").a2_err; },
                             "Standard error of a2 (delta method).")
      .def_property_readonly("v", [](const SD& s) {
        s.get("v");
        return s.v;
      }, "Bin centres of v~.")
      .def_property_readonly("density", [](const SD& s) {
        s.get("density");
        return s.density;
      }, "Probability density per bin (overflow counted in the total).")
      .def_property_readonly("maxwellian", [](const SD& s) {
        s.get("maxwellian");
        return s.maxwellian;
      }, "The Maxwellian density sqrt(54/pi) v~^2 exp(-3 v~^2 / 2) at the bin centres.");

  using GE = PyGrowthExponent;
  py::class_<GE>(m, "GrowthExponent",
                 "y = A t^z by least squares of ln y on ln t over a window, with a Student-t "
                 "interval (one series) or a bootstrap over runs (several), the local slope "
                 "z(t) = ln[y(t)/y(t/p)] / ln p and the growth regime (none, onset, scaling).")
      .def(py::init<py::handle, double, double, int, std::uint64_t>(), "window"_a, "p"_a = 2.0,
           "confidence"_a = 0.95, "replicates"_a = 2000, "seed"_a = 20091,
           "window: (t_min, t_max) of the fit; p: ratio of the local slope; replicates and "
           "seed: the bootstrap over runs.")
      .def(
          "fit",
          [](GE& g, py::handle t, py::handle y) -> GE& {
            g.fit(t, y);
            return g;
          },
          "t"_a, "y"_a, py::return_value_policy::reference_internal,
          "t (T,), y (T,) or (runs, T). Returns self.")
      .def_property_readonly("valid", [](const GE& g) { return g.get("valid").valid; },
                             "False with fewer than 3 usable points or a constant y.")
      .def_property_readonly("z", [](const GE& g) {
        const auto& r = g.get("z");
        return validOrNaN(r.valid, r.exponent);
      }, "The exponent z.")
      .def_property_readonly("z_err", [](const GE& g) {
        const auto& r = g.get("z_err");
        return validOrNaN(r.valid, r.stderr_z);
      }, "Its standard error.")
      .def_property_readonly("interval", [](const GE& g) {
        const auto& r = g.get("interval");
        return py::make_tuple(validOrNaN(r.valid, r.low), validOrNaN(r.valid, r.high));
      }, "(low, high) of the confidence interval of z.")
      .def_property_readonly("amplitude", [](const GE& g) {
        const auto& r = g.get("amplitude");
        return validOrNaN(r.valid, r.amplitude);
      }, "A.")
      .def_property_readonly("points", [](const GE& g) { return g.get("points").points; },
                             "Samples inside the window.")
      .def_property_readonly("local_slope", [](const GE& g) {
        g.get("local_slope");
        return g.local_slope;
      }, "z(t) at every t (NaN where t/p precedes the data).")
      .def_property_readonly("regime", [](const GE& g) {
        g.get("regime");
        return g.regime->regime;
      }, "'none', 'onset' or 'scaling' at the end of the series (classifyGrowth).")
      .def_property_readonly("reason", [](const GE& g) {
        g.get("reason");
        return g.regime->reason;
      }, "The sentence with the numbers behind the regime.");
}

}  // namespace granagg::python
