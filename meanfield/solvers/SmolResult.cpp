#include "meanfield/solvers/SmolResult.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "common/Csv.h"

namespace granagg::meanfield {

std::vector<double> logSpacedTimes(double t_min, double t_max, int count) {
  if (!(t_min > 0.0) || !std::isfinite(t_min))
    throw std::invalid_argument("logSpacedTimes requires t_min > 0 (got " +
                                common::formatReal(t_min) + ").");
  if (!(t_max > t_min) || !std::isfinite(t_max))
    throw std::invalid_argument(
        "logSpacedTimes requires a finite t_max > t_min (got t_max = " + common::formatReal(t_max) +
        ", t_min = " + common::formatReal(t_min) + ").");
  if (count < 2)
    throw std::invalid_argument("logSpacedTimes requires count >= 2 (got " + std::to_string(count) +
                                ").");
  std::vector<double> t(static_cast<size_t>(count));
  const double a = std::log(t_min), b = std::log(t_max);
  for (int i = 0; i < count; ++i)
    t[static_cast<size_t>(i)] = std::exp(a + (b - a) * i / (count - 1));
  // exact end points (exp(log(x)) may differ from x in the last bit)
  t.front() = t_min;
  t.back() = t_max;
  return t;
}

}  // namespace granagg::meanfield
