#include "common/PaperValues.h"

#include <fstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

namespace granagg::common {

PaperValues readPaperValues(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read the paper's values from " + path);
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error(path + ": not valid JSON (" + e.what() + ")");
  }
  auto number = [&](const char* key, const char* field) {
    const auto entry = j.find(key);
    if (entry == j.end() || !entry->is_object() || !entry->contains(field) ||
        !(*entry)[field].is_number())
      throw std::runtime_error(path + ": no number at \"" + key + "\"." + field);
    return (*entry)[field].get<double>();
  };
  PaperValues p;
  p.reference = j.value("reference", "");
  p.z_neutral = number("z_neutral", "value");
  p.z_neutral_pm = number("z_neutral", "pm");
  p.z_charged = number("z_charged", "value");
  p.z_charged_pm = number("z_charged", "pm");
  p.z_meanfield_beta2 = number("z_meanfield_beta2", "value");
  p.S_beta2 = number("z_meanfield_beta2", "S");
  p.z_meanfield_beta3 = number("z_meanfield_beta3", "value");
  p.S_beta3 = number("z_meanfield_beta3", "S");
  return p;
}

}  // namespace granagg::common
