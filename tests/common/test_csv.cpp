// CSV tables with provenance: round trip, refusal to overwrite, clear errors on malformed input.
#include <catch2/catch.hpp>

#include <unistd.h>
#include <cstdio>
#include <fstream>
#include <string>

#include "common/Csv.h"
#include "common/Version.h"

#include "TestUtil.h"

using granagg::test::tempPath;

using namespace granagg::common;

namespace {}  // namespace

TEST_CASE("CSV round trip keeps provenance, columns and exact values", "[common][csv]") {
  const std::string path = tempPath("roundtrip.csv");
  std::remove(path.c_str());
  Provenance prov("granagg smol --beta 3");
  prov.add("beta", 3.0);
  prov.add("M", 1024);
  {
    CsvWriter w(path, prov, {"t", "S"});
    w.row({0.1, 1.0 / 3.0});
    w.row({1e300, -2.5e-310});
    w.close();
  }
  const CsvTable t = readCsv(path);
  REQUIRE(t.columns == std::vector<std::string>{"t", "S"});
  REQUIRE(t.rows.size() == 2);
  CHECK(t.rows[0][1] == 1.0 / 3.0);  // shortest round-trip formatting is exact
  CHECK(t.rows[1][0] == 1e300);
  CHECK(t.rows[1][1] == -2.5e-310);
  bool has_beta = false, has_cmd = false;
  for (const auto& [k, v] : t.meta) {
    has_beta |= (k == "beta" && v == "3");
    has_cmd |= (k == "command" && v == "granagg smol --beta 3");
  }
  CHECK(has_beta);
  CHECK(has_cmd);
  CHECK(t.column("S") == 1);
  CHECK_THROWS_WITH(t.column("z"), Catch::Contains("no column named 'z'"));

  // never overwrite silently
  CHECK_THROWS_WITH(CsvWriter(path, prov, {"t"}), Catch::Contains("already exists"));
  CHECK_NOTHROW(CsvWriter(path, prov, {"t"}, /*overwrite=*/true));
  // a writer abandoned without close() (its command failed) leaves the old table as it was
  // and no new one: nothing half-written blocks or misleads the rerun
  CHECK(readCsv(path).rows.size() == 2);
  const std::string fresh = tempPath("abandoned.csv");
  std::remove(fresh.c_str());
  {
    CsvWriter w(fresh, prov, {"t", "S"});
    w.row({1.0, 2.0});
  }
  CHECK_THROWS_WITH(readCsv(fresh), Catch::Contains("abandoned.csv"));
  CHECK_THROWS(readCsv(fresh + ".partial"));
  std::remove(path.c_str());
}

TEST_CASE("malformed CSV input names the file and line", "[common][csv]") {
  const std::string path = tempPath("bad.csv");
  {
    std::ofstream f(path);
    f << "# comment\nt,S\n1,2\n2,abc\n";
  }
  CHECK_THROWS_WITH(readCsv(path),
                    Catch::Contains(path + ":4") && Catch::Contains("'abc' is not a number"));
  {
    std::ofstream f(path);
    f << "t,S\n1,2,3\n";
  }
  CHECK_THROWS_WITH(readCsv(path),
                    Catch::Contains(path + ":2") && Catch::Contains("expected 2 fields"));
  std::remove(path.c_str());
  CHECK_THROWS_WITH(readCsv(path), Catch::Contains("cannot open"));
}

TEST_CASE("version string names the version and a commit", "[common]") {
  const std::string v = versionString();
  CHECK(v.find("granagg ") == 0);
  CHECK(v.find('(') != std::string::npos);
}
