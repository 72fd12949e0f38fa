// The `granagg` executable: exit statuses, one-line errors naming the option, provenance headers,
// refusal to overwrite. Runs the real binary (GRANAGG_BINARY, set by CMake).
#include <catch2/catch.hpp>

#include "RunCommand.h"

#include <sys/wait.h>
#include <unistd.h>
#include <array>
#include <cstdio>
#include <cctype>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "TestUtil.h"

using granagg::test::tempPath;

namespace {
int countLines(const std::string& s) {
  int n = 0;
  for (char c : s) n += (c == '\n');
  return n;
}
}  // namespace

TEST_CASE("version and help work on every level", "[cli]") {
  const Run v = runGranagg("--version");
  CHECK(v.status == 0);
  CHECK_THAT(v.output, Catch::StartsWith("granagg 0."));
  for (const char* cmd : {"--help", "smol --help", "smol zbeta --help", "kinetic --help"}) {
    INFO(cmd);
    const Run h = runGranagg(cmd);
    CHECK(h.status == 0);
    CHECK_THAT(h.output, Catch::Contains("Usage") || Catch::Contains("usage"));
  }
}

TEST_CASE("bad input gives one line naming the option and exit status 2", "[cli]") {
  struct Case {
    const char* args;
    const char* says;
  };
  for (const Case& c :
       {Case{"smol --beta -1", "--beta"}, Case{"smol --beta 0", "--beta"},
        Case{"smol --t-min -1", "--t-min"}, Case{"smol --t-end -5", "--t-end"},
        Case{"smol --method discrete --M 1", "--M"},
        Case{"smol --method discrete --M 4000000000", "--M must lie in [2, 2147483647]"},
        Case{"smol --kernel gaussian", "unknown kernel"}, Case{"smol --method euler", "--method"},
        Case{"smol --ratio 1", "--ratio"},
        Case{"smol --kernel multiplicative --t-end 2", "gel time"},
        Case{"smol zbeta --count 0", "--count"}, Case{"smol zbeta --beta-min -2", "--beta-min"},
        Case{"smol --no-such-option", "no-such-option"},
        // an unknown subcommand is named the same way at every level, with what is available
        Case{"frobnicate", "unknown subcommand 'frobnicate' of 'granagg' (available: md,"},
        Case{"kinetic foo",
             "unknown subcommand 'foo' of 'granagg kinetic' (available: "
             "restitution, haff"},
        Case{"smol foo", "unknown subcommand 'foo' of 'granagg smol' (available: zbeta"},
        Case{"kinetic restitution --v 1,,2", "--v"}, Case{"kinetic restitution --v 1,", "--v"},
        Case{"kinetic restitution --v 0", "--v"},
        Case{"smol --method mono --t-end 1e300 --per-decade 10000", "--per-decade"}}) {
    INFO(c.args);
    const Run r = runGranagg(c.args);
    CHECK(r.status == 2);
    CHECK_THAT(r.output, Catch::Contains(c.says));
    CHECK(countLines(r.output) == 1);
  }
}

TEST_CASE("smol writes a table with provenance and refuses to overwrite it", "[cli]") {
  const std::string out = tempPath("mono.csv");
  std::remove(out.c_str());
  const Run r = runGranagg("smol --beta 3 --method mono --t-end 100 --out " + out);
  REQUIRE(r.status == 0);
  CHECK_THAT(r.output, Catch::Contains("scaling prediction z = 1/(1 - lambda) = 1.5"));
  std::ifstream f(out);
  std::stringstream ss;
  ss << f.rdbuf();
  const std::string text = ss.str();
  CHECK_THAT(text, Catch::StartsWith("# granagg "));
  CHECK_THAT(text, Catch::Contains("# command = "));
  CHECK_THAT(text, Catch::Contains("# beta = 3"));
  CHECK_THAT(text, Catch::Contains("\nt,S,M0,M1,M2,z_local,mass_loss,valid,max_size\n"));

  const Run again = runGranagg("smol --beta 3 --method mono --t-end 100 --out " + out);
  CHECK(again.status == 2);
  CHECK_THAT(again.output, Catch::Contains("already exists"));
  CHECK(runGranagg("smol --beta 3 --method mono --t-end 100 --force --out " + out).status == 0);
  std::remove(out.c_str());
}

namespace {

/// The options a piece of advice names ("--ratio", ...), in order.
std::vector<std::string> optionsNamed(const std::string& text) {
  std::vector<std::string> names;
  const std::regex option("--[a-z][a-z-]*");
  for (auto it = std::sregex_iterator(text.begin(), text.end(), option);
       it != std::sregex_iterator(); ++it)
    names.push_back(it->str());
  return names;
}

/// True when `option` is listed by `smol --help` without being reserved for another method
/// (help texts start with "discrete:" or "sectional:" for options of one method only).
bool smolOptionServes(const std::string& option, const std::string& method) {
  std::istringstream help(runGranagg("smol --help").output);
  for (std::string line; std::getline(help, line);) {
    const std::size_t at = line.find(option);
    if (at == std::string::npos) continue;
    const std::size_t end = at + option.size();
    if (end < line.size() && (std::isalnum(static_cast<unsigned char>(line[end])) ||
                              line[end] == '-'))
      continue;  // a longer option name
    for (const char* other : {"discrete:", "sectional:", "mono:"})
      if (line.find(other) != std::string::npos && std::string(other) != method + ":")
        return false;
    return true;
  }
  return false;
}

}  // namespace

TEST_CASE("the README's sectional smol example reaches its t_end", "[cli][smol]") {
  // README, CLI tour: "$G smol --beta 3 --method sectional --t-end 1e7 --out S.csv". S reaches
  // 2e11 there, beyond the sectional grid's first last pivot (1e12 holds S up to ~7e10).
  const std::string readme = granagg::test::slurp(std::string(GRANAGG_SOURCE_DIR) + "/README.md");
  const std::string example = "$G smol --beta 3 --method sectional --t-end 1e7 --out S.csv";
  REQUIRE_THAT(readme, Catch::Contains(example));
  const std::string out = tempPath("readme_S.csv");
  std::remove(out.c_str());
  const Run r = runGranagg("smol --beta 3 --method sectional --t-end 1e7 --out " + out);
  INFO(r.output);
  REQUIRE(r.status == 0);
  CHECK_THAT(r.output, !Catch::Contains("stopped early"));
  // the last row: t = t_end, valid, and the local slope at 3 beta / (beta + 3) = 1.5
  std::istringstream table(granagg::test::slurp(out));
  std::string line, last;
  while (std::getline(table, line))
    if (!line.empty() && line[0] != '#') last = line;
  std::vector<std::string> cells;
  std::istringstream row(last);
  for (std::string c; std::getline(row, c, ',');) cells.push_back(c);
  REQUIRE(cells.size() == 9);  // t,S,M0,M1,M2,z_local,mass_loss,valid,max_size
  CHECK(std::stod(cells[0]) == Approx(1e7).epsilon(1e-12));
  CHECK(std::stod(cells[5]) == Approx(1.5).margin(1e-4));
  CHECK(cells[7] == "1");
  std::remove(out.c_str());
  // --M, the discrete method's bound, is said to be unused here, whatever its value
  const Run m = runGranagg("smol --beta 3 --method sectional --t-end 10 --M 4000000000 --out -");
  CHECK(m.status == 0);
  CHECK_THAT(m.output, Catch::Contains("--M applies to --method discrete only"));
}

TEST_CASE("a smol that stops early advises options of its own method", "[cli][smol]") {
  struct Case {
    std::string method, args;
  };
  // discrete: the size range M is too small; sectional: S beyond what any grid holds; mono: the
  // mean size overflows (that one is an error, exit 1, and names --t-end).
  for (const Case& c : {Case{"discrete", "--beta 3 --method discrete --M 100 --t-end 1e4"},
                        Case{"sectional", "--beta 3 --method sectional --ratio 1.5 --t-end 1e80 "
                                          "--per-decade 1"},
                        Case{"mono", "--beta 3 --method mono --t-end 1e300"}}) {
    INFO(c.args);
    const Run r = runGranagg("smol " + c.args + " --out -");
    INFO(r.output);
    std::string advice;
    for (std::istringstream in(r.output); std::getline(in, advice);)
      if (advice.find("stopped early") != std::string::npos ||
          advice.find("granagg: failed") != std::string::npos)
        break;
    REQUIRE_FALSE(advice.empty());
    const std::vector<std::string> named = optionsNamed(advice);
    CHECK_FALSE(named.empty());
    for (const std::string& option : named) {
      INFO(option);
      CHECK(smolOptionServes(option, c.method));
    }
  }
}

TEST_CASE("kinetic restitution warns where the overlap exceeds a diameter", "[cli]") {
  const Run r = runGranagg("kinetic restitution --v 0.1,1e10");
  CHECK(r.status == 0);
  CHECK_THAT(r.output, Catch::Contains("restitution: warning: v = 1e+10: max_overlap 4.18e+05"));
  CHECK_THAT(r.output, Catch::Contains("# warning: v = 1e+10"));  // in the table too
}

TEST_CASE("a failed smol or kinetic leaves no table behind", "[cli]") {
  // They used to leave header-only CSVs that blocked the rerun ("already exists").
  const std::string zb = tempPath("zb.csv"), rs = tempPath("r.csv");
  std::remove(zb.c_str());
  std::remove(rs.c_str());
  const Run z = runGranagg("smol zbeta --ratio 1 --out " + zb);
  CHECK(z.status != 0);
  std::ifstream fz(zb);
  CHECK_FALSE(fz.good());
  const Run k = runGranagg("kinetic restitution --D 1e6 --out " + rs);
  CHECK(k.status != 0);
  std::ifstream fk(rs);
  CHECK_FALSE(fk.good());
  std::ifstream partial(zb + ".partial");
  CHECK_FALSE(partial.good());
  // a solution that overflows fails (exit 1) instead of writing NaN rows
  const std::string mono = tempPath("mono_overflow.csv");
  std::remove(mono.c_str());
  const Run m = runGranagg("smol --beta 3 --method mono --t-end 1e300 --out " + mono);
  CHECK(m.status == 1);
  CHECK_THAT(m.output, Catch::Contains("--t-end"));
  std::ifstream fm(mono);
  CHECK_FALSE(fm.good());
}
