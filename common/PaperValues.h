#pragma once
/// \file PaperValues.h
/// The published values of the paper granagg reproduces (C. Singh and M. G. Mazza, Phys.
/// Rev. E 97, 022904 (2018)), read from data/reference/paper.json: the one place they are typed.
/// The C++ code reads them here; the Python scripts read the same file with json.load.
#include <string>

namespace granagg::common {

struct PaperValues {
  std::string reference;   ///< the citation
  double z_neutral = 0.0;  ///< S(t) ~ t^z, neutral gas
  double z_neutral_pm = 0.0;
  double z_charged = 0.0;  ///< S(t) ~ t^z, charged gas (independent of K = 0.25, 1, 5)
  double z_charged_pm = 0.0;
  double z_meanfield_beta2 = 0.0;  ///< local slope of the Smoluchowski S(t) for beta = 2 ...
  double S_beta2 = 0.0;            ///< ... near S = S_beta2
  double z_meanfield_beta3 = 0.0;  ///< the same for beta = 3
  double S_beta3 = 0.0;
};

/// Reads the values from `path` (data/reference/paper.json). Throws std::runtime_error naming
/// the file and, for a missing or non-numeric entry, the key.
PaperValues readPaperValues(const std::string& path);

}  // namespace granagg::common
