// The paper's published values (common/PaperValues.h) as read from data/reference/paper.json,
// against the numbers printed in Singh & Mazza, Phys. Rev. E 97, 022904 (2018): the file is the
// one place they are typed, so a slip there would otherwise reach every report unnoticed.
#include <catch2/catch.hpp>

#include <cstdio>
#include <stdexcept>
#include <string>

#include "common/PaperValues.h"

#include "TestUtil.h"

using namespace granagg;

TEST_CASE("the paper's values are read from data/reference/paper.json", "[common][paper]") {
  const common::PaperValues p =
      common::readPaperValues(std::string(GRANAGG_SOURCE_DIR) + "/data/reference/paper.json");
  CHECK_THAT(p.reference, Catch::Contains("Singh") && Catch::Contains("022904"));
  CHECK(p.z_neutral == 1.21);  // S(t) ~ t^z: 1.21 +- 0.04 neutral, 1.49 +- 0.012 charged
  CHECK(p.z_neutral_pm == 0.04);
  CHECK(p.z_charged == 1.49);
  CHECK(p.z_charged_pm == 0.012);
  CHECK(p.z_meanfield_beta2 == 1.19);  // mean-field local slopes near S ~ 250 and ~ 1650
  CHECK(p.S_beta2 == 250);
  CHECK(p.z_meanfield_beta3 == 1.49);
  CHECK(p.S_beta3 == 1650);
}

TEST_CASE("a paper.json without an entry names the file and the key", "[common][paper]") {
  const std::string path = granagg::test::tempPath("paper.json");
  granagg::test::spit(path, R"({"z_neutral": {"value": 1.21, "pm": 0.04}})");
  try {
    common::readPaperValues(path);
    FAIL("no exception");
  } catch (const std::runtime_error& e) {
    CHECK_THAT(e.what(), Catch::Contains(path) && Catch::Contains("z_charged"));
  }
  granagg::test::spit(path, "{not json");
  CHECK_THROWS_WITH(common::readPaperValues(path), Catch::Contains("not valid JSON"));
  CHECK_THROWS_WITH(common::readPaperValues(path + ".missing"), Catch::Contains("cannot read"));
  std::remove(path.c_str());
}
