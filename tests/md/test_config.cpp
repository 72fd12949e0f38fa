// Tests of md/config/ConfigParser: defaults, the "bad config" table with its expected messages
// (STYLE.md, "Config and CLI"), unknown keys with file:line:col, --set overrides, the toToml
// round trip, the presets in data/presets/ and the key list of docs/config.md.
#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>
#include <functional>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "md/config/ConfigParser.h"

using namespace granagg::md;

namespace {

// The source tree: GRANAGG_TEST_DATA is <root>/tests/data (which need not exist, so no "/../..").
std::string sourceRoot() {
  std::string d = GRANAGG_TEST_DATA;
  const std::string tail = "/tests/data";
  REQUIRE(d.size() > tail.size());
  REQUIRE(d.compare(d.size() - tail.size(), tail.size(), tail) == 0);
  return d.substr(0, d.size() - tail.size());
}

// The message of the ConfigError thrown by f ("" if none was thrown; fails on other exceptions).
template <class F>
std::string errorOf(F&& f) {
  try {
    f();
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

// Every field compared exactly (== on doubles: the round trip must be bit-exact).
void requireSame(const MdConfig& a, const MdConfig& b) {
  CHECK(a.input_version == b.input_version);
  CHECK(a.system.N == b.system.N);
  CHECK(a.system.phi == b.system.phi);
  CHECK(a.system.seed == b.system.seed);
  CHECK(a.system.temperature == b.system.temperature);
  CHECK(a.system.initial == b.system.initial);
  CHECK(a.system.initial_max_overlap == b.system.initial_max_overlap);
  CHECK(a.contact.model == b.contact.model);
  CHECK(a.contact.E == b.contact.E);
  CHECK(a.contact.D == b.contact.D);
  CHECK(a.contact.clamp == b.contact.clamp);
  CHECK(a.contact.stiffness == b.contact.stiffness);
  CHECK(a.contact.restitution == b.contact.restitution);
  CHECK(a.integrator.dt == b.integrator.dt);
  CHECK(a.integrator.adaptive == b.integrator.adaptive);
  CHECK(a.integrator.steps_per_contact == b.integrator.steps_per_contact);
  CHECK(a.integrator.impact_speed_max == b.integrator.impact_speed_max);
  CHECK(a.neighbor.skin == b.neighbor.skin);
  CHECK(a.run.t_end == b.run.t_end);
  CHECK(a.run.max_overlap == b.run.max_overlap);
  CHECK(a.output.frames_per_decade == b.output.frames_per_decade);
  CHECK(a.output.frame_interval == b.output.frame_interval);
  CHECK(a.output.observable_interval == b.output.observable_interval);
  CHECK(a.output.checkpoint_interval == b.output.checkpoint_interval);
  CHECK(a.output.checkpoint_wall_seconds == b.output.checkpoint_wall_seconds);
  CHECK(a.output.write_velocities == b.output.write_velocities);
  CHECK(flatten(a) == flatten(b));
}

std::string readText(const std::string& path) {
  std::ifstream in(path);
  REQUIRE(in.good());
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace

TEST_CASE("defaults are the paper's values", "[md][config]") {
  const MdConfig c;
  // docs/model.md sections 3-6: Singh & Mazza 2018 (silica), phi = 0.076, T0 = 1, clamped contacts,
  // 50 steps per contact of the fastest impact.
  CHECK(c.input_version == 1);
  CHECK(c.system.phi == 0.076);
  CHECK(c.system.temperature == 1.0);
  CHECK(c.system.initial == "random");
  CHECK(c.contact.model == "hertz");
  CHECK(c.contact.E == 278.6);
  CHECK(c.contact.D == 27.7);
  CHECK(c.contact.clamp);
  CHECK(c.integrator.dt == 0.0);  // auto
  CHECK(c.integrator.steps_per_contact == 50.0);
  CHECK(c.integrator.impact_speed_max == 0.0);  // auto
  CHECK_NOTHROW(validateConfig(c));

  // An empty file and one with only [input] give exactly the defaults.
  requireSame(parseConfigString("", "empty.toml"), c);
  requireSame(parseConfigString("[input]\nversion = 1\n", "v1.toml"), c);
}

TEST_CASE("boxLength gives phi = N pi / (6 L^3)", "[md][config]") {
  SystemConfig s;
  s.N = 50016;
  s.phi = 0.076;
  const double L = boxLength(s);
  CHECK(L == Approx(70.10752929426128).epsilon(1e-13));
  CHECK(s.N * M_PI / (6.0 * L * L * L) == Approx(0.076).epsilon(1e-14));
  s.phi = 0.0;
  CHECK_THROWS_AS(boxLength(s), std::invalid_argument);
}

// One row per rule of validateConfig: the key, a TOML value for it, the same change made on the
// struct, and the expected message. Each row is checked three ways: in a file (message prefixed
// with file:line:col of the value), as a --set override (prefixed with "--set key=value"), and on
// the struct through validateConfig (rows with a null `mutate` are parse-time rules only).
struct BadCase {
  std::string key;    // "section.name"
  std::string value;  // TOML literal
  std::function<void(MdConfig&)> mutate;
  std::string message;
};

TEST_CASE("bad configs are rejected with the key and the allowed range", "[md][config]") {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<BadCase> cases = {
      {"input.version", "2", [](MdConfig& c) { c.input_version = 2; },
       "input.version = 2 is not supported: this granagg reads version 1"},
      {"system.N", "1", [](MdConfig& c) { c.system.N = 1; },
       "system.N = 1 is invalid: must be >= 2"},
      {"system.N", "-5", [](MdConfig& c) { c.system.N = -5; },
       "system.N = -5 is invalid: must be >= 2"},
      {"system.phi", "0", [](MdConfig& c) { c.system.phi = 0; },
       "system.phi = 0 is invalid: must lie in (0, 0.6)"},
      {"system.phi", "-0.1", [](MdConfig& c) { c.system.phi = -0.1; },
       "system.phi = -0.1 is invalid: must lie in (0, 0.6)"},
      {"system.phi", "0.6", [](MdConfig& c) { c.system.phi = 0.6; },
       "system.phi = 0.6 is invalid: must lie in (0, 0.6)"},
      {"system.phi", "nan", [=](MdConfig& c) { c.system.phi = nan; },
       "system.phi = nan is invalid: must lie in (0, 0.6)"},
      {"system.temperature", "0", [](MdConfig& c) { c.system.temperature = 0; },
       "system.temperature = 0 is invalid: must be > 0 and finite"},
      {"system.temperature", "-1.0", [](MdConfig& c) { c.system.temperature = -1; },
       "system.temperature = -1 is invalid: must be > 0 and finite"},
      {"system.temperature", "inf", [](MdConfig& c) { c.system.temperature = HUGE_VAL; },
       "system.temperature = inf is invalid: must be > 0 and finite"},
      {"system.initial", "\"\"", [](MdConfig& c) { c.system.initial = ""; },
       "system.initial = \"\" is invalid: must be \"random\" or a file path"},
      {"system.initial_max_overlap", "1", [](MdConfig& c) { c.system.initial_max_overlap = 1; },
       "system.initial_max_overlap = 1 is invalid: must lie in (0, 1) or be \"auto\" "
       "(run.max_overlap)"},
      {"contact.model", "\"hooke\"", [](MdConfig& c) { c.contact.model = "hooke"; },
       "contact.model = \"hooke\" is invalid: must be one of \"hertz\", \"spring_dashpot\" "
       "(unknown contact "
       "model)"},
      {"contact.E", "-1", [](MdConfig& c) { c.contact.E = -1; },
       "contact.E = -1 is invalid: must be >= 0 and finite"},
      {"contact.D", "-0.5", [](MdConfig& c) { c.contact.D = -0.5; },
       "contact.D = -0.5 is invalid: must be >= 0 and finite"},
      {"contact.stiffness", "0", [](MdConfig& c) { c.contact.stiffness = 0; },
       "contact.stiffness = 0 is invalid: must be > 0 and finite"},
      {"contact.restitution", "0", [](MdConfig& c) { c.contact.restitution = 0; },
       "contact.restitution = 0 is invalid: must lie in (0, 1]"},
      {"contact.restitution", "1.1", [](MdConfig& c) { c.contact.restitution = 1.1; },
       "contact.restitution = 1.1 is invalid: must lie in (0, 1]"},
      {"integrator.dt", "-0.001", [](MdConfig& c) { c.integrator.dt = -0.001; },
       "integrator.dt = -0.001 is invalid: must be > 0, \"auto\" or \"adaptive\""},
      // 0 is how "auto" is stored: fine on the struct, an error when written explicitly.
      {"integrator.dt", "0", nullptr,
       "integrator.dt = 0 is invalid: must be > 0, \"auto\" or \"adaptive\""},
      {"integrator.impact_speed_max", "0.0", nullptr,
       "integrator.impact_speed_max = 0 is invalid: must be > 0 or \"auto\""},
      {"integrator.impact_speed_max", "-2", [](MdConfig& c) { c.integrator.impact_speed_max = -2; },
       "integrator.impact_speed_max = -2 is invalid: must be > 0 or \"auto\""},
      {"integrator.steps_per_contact", "4.9",
       [](MdConfig& c) { c.integrator.steps_per_contact = 4.9; },
       "integrator.steps_per_contact = 4.9 is invalid: must be >= 5 and finite"},
      {"neighbor.skin", "-0.1", nullptr,
       "neighbor.skin = -0.1 is invalid: must be > 0 or \"auto\""},
      {"neighbor.skin", "0", nullptr, "neighbor.skin = 0 is invalid: must be > 0 or \"auto\""},
      {"neighbor.skin", "2.5", [](MdConfig& c) { c.neighbor.skin = 2.5; },
       "neighbor.skin = 2.5 is invalid: must lie in (0, 2] or be \"auto\""},
      {"run.t_end", "0", [](MdConfig& c) { c.run.t_end = 0; },
       "run.t_end = 0 is invalid: must be > 0 and finite"},
      {"run.max_overlap", "0", [](MdConfig& c) { c.run.max_overlap = 0; },
       "run.max_overlap = 0 is invalid: must lie in (0, 1)"},
      {"run.max_overlap", "1", [](MdConfig& c) { c.run.max_overlap = 1.0; },
       "run.max_overlap = 1 is invalid: must lie in (0, 1)"},
      {"output.frames_per_decade", "-1", [](MdConfig& c) { c.output.frames_per_decade = -1; },
       "output.frames_per_decade = -1 is invalid: must be >= 0"},
      {"output.frame_interval", "-0.5", [](MdConfig& c) { c.output.frame_interval = -0.5; },
       "output.frame_interval = -0.5 is invalid: must be >= 0 and finite"},
      {"output.observable_interval", "0", [](MdConfig& c) { c.output.observable_interval = 0; },
       "output.observable_interval = 0 is invalid: must be >= 1"},
      {"output.checkpoint_interval", "-1", [](MdConfig& c) { c.output.checkpoint_interval = -1; },
       "output.checkpoint_interval = -1 is invalid: must be >= 0"},
      {"output.checkpoint_wall_seconds", "-1",
       [](MdConfig& c) { c.output.checkpoint_wall_seconds = -1; },
       "output.checkpoint_wall_seconds = -1 is invalid: must be >= 0 and finite"},
  };
  for (const auto& bad : cases) {
    const auto dot = bad.key.find('.');
    const std::string section = bad.key.substr(0, dot), name = bad.key.substr(dot + 1);
    INFO(bad.key << " = " << bad.value);

    // In a file: line 2, the value starts after "name = ".
    const std::string text = "[" + section + "]\n" + name + " = " + bad.value + "\n";
    const std::string where = "bad.toml:2:" + std::to_string(name.size() + 4) + ": ";
    CHECK(errorOf([&] { parseConfigString(text, "bad.toml"); }) == where + bad.message);

    // As an override of a good file.
    const std::string set = bad.key + "=" + bad.value;
    CHECK(errorOf([&] { parseConfigString("", "good.toml", {set}); }) ==
          "--set " + set + ": " + bad.message);

    // On the struct; the exception is an std::invalid_argument and knows its key.
    if (bad.mutate) {
      MdConfig c;
      bad.mutate(c);
      CHECK(errorOf([&] { validateConfig(c); }) == bad.message);
      CHECK_THROWS_AS(validateConfig(c), std::invalid_argument);
      try {
        validateConfig(c);
      } catch (const ConfigError& e) {
        CHECK(e.key() == bad.key);
      }
    }
  }
}

TEST_CASE("values of the wrong type name the key and the expected type", "[md][config]") {
  struct Case {
    std::string text;
    std::string message;
  };
  const std::vector<Case> cases = {
      {"[system]\nN = 2000.5\n", "t.toml:2:5: system.N must be an integer, got float 2000.5"},
      {"[system]\nN = \"many\"\n", "t.toml:2:5: system.N must be an integer, got string \"many\""},
      {"[system]\nN = 3000000000\n",
       "t.toml:2:5: system.N = 3000000000 is out of range for a 32-bit integer"},
      {"[system]\nphi = \"dense\"\n",
       "t.toml:2:7: system.phi must be a number, got string \"dense\""},
      {"[system]\nseed = -1\n",
       "t.toml:2:8: system.seed must be a non-negative integer, got integer -1"},
      {"[system]\nseed = \"0x10\"\n",
       "t.toml:2:8: system.seed must be a non-negative integer (below 2^64), got string \"0x10\""},
      {"[system]\ninitial = 3\n", "t.toml:2:11: system.initial must be a string, got integer 3"},
      {"[contact]\nclamp = 1\n",
       "t.toml:2:9: contact.clamp must be a boolean (true or false), got integer 1"},
      {"[contact]\nE = [1, 2]\n", "t.toml:2:5: contact.E must be a number, got an array"},
      {"[integrator]\ndt = \"fast\"\n",
       "t.toml:2:6: integrator.dt must be a number, \"auto\" or \"adaptive\", got string \"fast\""},
      {"[input]\nversion = \"1\"\n",
       "t.toml:2:11: input.version must be an integer, got string \"1\""},
      {"system = 3\n", "t.toml:1:1: 'system' must be a table ([system]), got integer 3"},
      {"[system]\nN = \n", "t.toml:2:5: invalid TOML"},
  };
  for (const auto& c : cases) {
    INFO(c.text);
    const std::string e = errorOf([&] { parseConfigString(c.text, "t.toml"); });
    CHECK(e.substr(0, c.message.size()) == c.message);
  }
}

TEST_CASE("unknown keys and sections are reported with file:line:col", "[md][config]") {
  const std::string text =
      "[input]\n"
      "version = 1\n"
      "\n"
      "[system]\n"
      "N = 2000\n"
      "Nn = 2\n";
  CHECK(errorOf([&] { parseConfigString(text, "run.toml"); }) ==
        "run.toml:6:1: unknown key 'system.Nn' (known keys in [system]: N, phi, seed, temperature, "
        "initial, initial_max_overlap); "
        "did you mean 'system.N'?");

  CHECK(
      errorOf([&] { parseConfigString("[sytem]\nN = 2\n", "run.toml"); }) ==
      "run.toml:1:2: unknown section 'sytem' (known sections: input, system, contact, integrator, "
      "neighbor, charging, coulomb, run, "
      "output, analysis); did you mean 'system'?");
  CHECK(errorOf([&] { parseConfigString("N = 2\n", "run.toml"); }) ==
        "run.toml:1:1: unknown key 'N' at top level (keys belong in a section; known sections: "
        "input, system, "
        "contact, integrator, neighbor, charging, coulomb, run, output, analysis); did you mean "
        "'system.N'?");
  // A nested table is an unknown key of its section.
  CHECK(errorOf([&] {
          parseConfigString("[system.extra]\nx = 1\n", "run.toml");
        }).find("unknown key 'system.extra' (known keys in [system]:") != std::string::npos);

  // All problems of a file at once, in file order (toml::table iterates keys alphabetically).
  const std::string several = errorOf(
      [&] { parseConfigString("[run]\nzzz = 1\n[contact]\naaa = 2\nE = \"x\"\n", "run.toml"); });
  const auto a = several.find("run.toml:2:1: unknown key 'run.zzz'");
  const auto b = several.find("run.toml:4:1: unknown key 'contact.aaa'");
  const auto c = several.find("run.toml:5:5: contact.E must be a number");
  CHECK(a == 0);
  CHECK(b != std::string::npos);
  CHECK(c != std::string::npos);
  CHECK(a < b);
  CHECK(b < c);

  // From a real file: the path appears in the message.
  const std::string path = "test_config_unknown_key.toml";
  {
    std::ofstream out(path);
    out << "[contact]\nmodel = \"hertz\"\nclmap = false\n";
  }
  CHECK(errorOf([&] { parseConfigFile(path); }) ==
        path +
            ":3:1: unknown key 'contact.clmap' (known keys in [contact]: model, E, D, clamp, "
            "stiffness, "
            "restitution); did you mean 'contact.clamp'?");
  std::remove(path.c_str());
  CHECK(errorOf([&] { parseConfigFile("no/such/file.toml"); }) ==
        "cannot open config file 'no/such/file.toml'");
}

TEST_CASE("overrides (--set key=value) apply after the file and are validated", "[md][config]") {
  const std::string file =
      "[system]\nN = 1000\n[integrator]\ndt = 0.001\n[contact]\nclamp = true\n";
  const MdConfig c = parseConfigString(
      file, "run.toml",
      {"system.N=2000", "integrator.dt=auto", "contact.clamp=false", "contact.model=spring_dashpot",
       " system.phi = 0.1 ", "system.initial=data/start 1.csv", "system.seed=18446744073709551615",
       "contact.E=300", "run.t_end=1e3", "output.write_velocities=false",
       "integrator.impact_speed_max=2.5", "system.N=3000"});
  CHECK(c.system.N == 3000);  // later overrides win
  CHECK(c.integrator.dt == 0.0);
  CHECK_FALSE(c.contact.clamp);
  CHECK(c.contact.model == "spring_dashpot");
  CHECK(c.system.phi == 0.1);
  CHECK(c.system.initial == "data/start 1.csv");
  CHECK(c.system.seed == std::numeric_limits<std::uint64_t>::max());
  CHECK(c.contact.E == 300.0);
  CHECK(c.run.t_end == 1000.0);
  CHECK_FALSE(c.output.write_velocities);
  CHECK(c.integrator.impact_speed_max == 2.5);

  // String keys: quoted TOML strings, and unquoted text taken literally even if it looks like a
  // number or date.
  CHECK(parseConfigString("", "r", {"system.initial=\"a \\\"q\\\".csv\""}).system.initial ==
        "a \"q\".csv");
  CHECK(parseConfigString("", "r", {"system.initial=2024-01-01.h5"}).system.initial ==
        "2024-01-01.h5");
  CHECK(parseConfigString("", "r", {"system.initial=2000"}).system.initial == "2000");

  const std::vector<std::pair<std::string, std::string>> bad = {
      {"system.Nn=2",
       "--set system.Nn=2: unknown key 'system.Nn' (known keys in [system]: N, phi, seed, "
       "temperature, "
       "initial, initial_max_overlap); "
       "did you mean 'system.N'?"},
      {"sytem.N=2",
       "--set sytem.N=2: unknown section 'sytem' (known sections: input, system, contact, "
       "integrator, "
       "neighbor, charging, coulomb, run, output, analysis); did you mean 'system'?"},
      {"N=2", "--set N=2: unknown key 'N' at top level"},
      {"system.N", "--set system.N: expected section.key=value"},
      {"system.N=abc", "--set system.N=abc: system.N must be an integer, got string \"abc\""},
      {"system.N=2e3", "--set system.N=2e3: system.N must be an integer, got float 2000"},
      {"system.phi=1.0e",
       "--set system.phi=1.0e: system.phi must be a number, got string \"1.0e\""},
      {"contact.clamp=yes",
       "--set contact.clamp=yes: contact.clamp must be a boolean (true or false), got string "
       "\"yes\""},
      {"integrator.dt=0",
       "--set integrator.dt=0: integrator.dt = 0 is invalid: must be > 0, \"auto\" or "
       "\"adaptive\""},
      {"integrator.dt=Auto",
       "--set integrator.dt=Auto: integrator.dt must be a number, \"auto\" or \"adaptive\", "
       "got string \"Auto\""},
      {"system.phi=0.7", "--set system.phi=0.7: system.phi = 0.7 is invalid: must lie in (0, 0.6)"},
      {"contact.model=hooke", "--set contact.model=hooke: contact.model = \"hooke\" is invalid"},
      {"charging.mode=static", "--set charging.mode=static: charging.mode = \"static\" is invalid"},
      {"charging.initial=file",
       "--set charging.initial=file: charging.initial = \"file\" is invalid: must be used with"},
      {"charging.kappa=0", "--set charging.kappa=0: charging.kappa = 0 is invalid: must be > 0"},
      {"coulomb.K=-1", "--set coulomb.K=-1: coulomb.K = -1 is invalid: must be >= 0"},
      {"coulomb.accuracy=0.5", "--set coulomb.accuracy=0.5: coulomb.accuracy = 0.5 is invalid"},
      {"coulomb.method=p3m", "--set coulomb.method=p3m: coulomb.method = \"p3m\" is invalid"},
      {"coulomb.mesh=0",
       "--set coulomb.mesh=0: coulomb.mesh = 0 is invalid: must be > 0 or \"auto\""},
      {"coulomb.order=9", "--set coulomb.order=9: coulomb.order = 9 is invalid: must lie in 2..7"},
      {"coulomb.every_max=2000",
       "--set coulomb.every_max=2000: coulomb.every_max = 2000 is invalid: must lie in 1..1000"},
      {"coulomb.every_max=-1",
       "--set coulomb.every_max=-1: coulomb.every_max = -1 is invalid: must be > 0 or \"auto\""},
  };
  for (const auto& [set, message] : bad) {
    INFO(set);
    const std::string e = errorOf([&] { parseConfigString("", "run.toml", {set}); });
    CHECK(e.substr(0, message.size()) == message);
  }

  // A bad value in the file fixed by an override is fine; a good file value broken by one is not.
  CHECK(parseConfigString("[system]\nphi = 0.7\n", "r", {"system.phi=0.1"}).system.phi == 0.1);
  CHECK(errorOf([] { parseConfigString("[system]\nphi = 0.1\n", "r", {"system.N=1"}); }) ==
        "--set system.N=1: system.N = 1 is invalid: must be >= 2");
}

TEST_CASE("toToml round-trips exactly through parseConfigString", "[md][config]") {
  SECTION("defaults") {
    const MdConfig c;
    const std::string text = toToml(c);
    CHECK(text.find("dt = \"auto\"\n") != std::string::npos);
    CHECK(text.find("impact_speed_max = \"auto\"\n") != std::string::npos);
    CHECK(text.find("stiffness = 20000.0\n") != std::string::npos);  // a float, not an integer
    const MdConfig back = parseConfigString(text, "stored");
    requireSame(back, c);
    CHECK(toToml(back) == text);
  }
  SECTION("integrator.dt = \"adaptive\", and a later value that replaces it") {
    const MdConfig c = parseConfigString("[integrator]\ndt = \"adaptive\"\n", "a.toml");
    CHECK(c.integrator.adaptive);
    CHECK(c.integrator.dt == 0.0);  // it starts at the "auto" step
    const std::string text = toToml(c);
    CHECK(text.find("dt = \"adaptive\"\n") != std::string::npos);
    requireSame(parseConfigString(text, "stored"), c);
    const MdConfig fixed = parseConfigString(text, "stored", {"integrator.dt=0.001"});
    CHECK_FALSE(fixed.integrator.adaptive);
    CHECK(fixed.integrator.dt == 0.001);
    CHECK_FALSE(parseConfigString(text, "stored", {"integrator.dt=auto"}).integrator.adaptive);
  }
  SECTION("every key changed, awkward values") {
    MdConfig c;
    c.system.N = 123457;
    c.system.phi = 0.1 + 0.2;  // 0.30000000000000004 needs 17 digits
    c.system.seed = std::numeric_limits<std::uint64_t>::max();  // beyond TOML's int64
    c.system.temperature = 1.0 / 3.0;
    c.system.initial = "dir with space/\"quoted\"\\x\ttab\u00e9.csv";
    c.system.initial_max_overlap = 0.1 + 0.2;
    c.contact.model = "spring_dashpot";
    c.contact.E = 1e-300;
    c.contact.D = 0.0;
    c.contact.clamp = false;
    c.contact.stiffness = 1e22;
    c.contact.restitution = 1.0;
    c.integrator.dt = 2.0 / 3.0 * 1e-3;
    c.integrator.steps_per_contact = 5.0;
    c.integrator.impact_speed_max = 4.9406564584124654e-324;  // smallest subnormal
    c.neighbor.skin = 2.0;
    c.run.t_end = 12345.678901234567;
    c.run.max_overlap = 0.99999999999999989;
    c.output.frames_per_decade = 0;
    c.output.frame_interval = 0.1;
    c.output.observable_interval = 1;
    c.output.checkpoint_interval = 9000000000L;
    c.output.checkpoint_wall_seconds = 0.0;
    c.output.write_velocities = false;
    REQUIRE_NOTHROW(validateConfig(c));
    const std::string text = toToml(c);
    INFO(text);
    const MdConfig back = parseConfigString(text, "stored");
    requireSame(back, c);
    CHECK(toToml(back) == text);
  }
}

TEST_CASE("flatten lists every key with round-trip numbers", "[md][config]") {
  MdConfig c;
  c.system.phi = 0.1 + 0.2;
  const auto f = flatten(c);
  REQUIRE(f.size() == 46);
  CHECK(f.front() == std::make_pair(std::string("input.version"), std::string("1")));
  CHECK(f[1] == std::make_pair(std::string("system.N"), std::string("1000")));
  CHECK(f[2] == std::make_pair(std::string("system.phi"), std::string("0.30000000000000004")));
  CHECK(f[5] == std::make_pair(std::string("system.initial"), std::string("random")));
  CHECK(f[6] == std::make_pair(std::string("system.initial_max_overlap"), std::string("auto")));
  CHECK(f[10] == std::make_pair(std::string("contact.clamp"), std::string("true")));
  CHECK(f[13] == std::make_pair(std::string("integrator.dt"), std::string("auto")));
  CHECK(f[14] == std::make_pair(std::string("integrator.steps_per_contact"), std::string("50")));
  CHECK(f[17] == std::make_pair(std::string("charging.mode"), std::string("exchange")));
  CHECK(f[25] == std::make_pair(std::string("coulomb.K"), std::string("0")));
  CHECK(f[28] == std::make_pair(std::string("coulomb.r_cut"), std::string("auto")));
  CHECK(f[29] == std::make_pair(std::string("coulomb.mesh"), std::string("auto")));
  // toToml has exactly these keys in this order.
  const std::string text = toToml(c);
  std::size_t pos = 0;
  for (const auto& [key, value] : f) {
    const std::string name = key.substr(key.find('.') + 1);
    const auto at = text.find("\n" + name + " = ", pos);
    INFO(key);
    REQUIRE(at != std::string::npos);
    pos = at + 1;
  }
}

TEST_CASE("the presets in data/presets parse and validate", "[md][config]") {
  const std::string dir = sourceRoot() + "/data/presets/";
  const MdConfig quick = parseConfigFile(dir + "quick.toml");
  CHECK(quick.system.N == 2000);
  CHECK(quick.system.phi == 0.076);
  CHECK(quick.run.t_end == 50.0);
  CHECK(quick.contact.model == "hertz");
  // quick.toml lists (and comments) every key.
  const std::string quick_text = readText(dir + "quick.toml");
  for (const auto& [key, value] : flatten(quick)) {
    INFO(key);
    CHECK(quick_text.find("\n" + key.substr(key.find('.') + 1) + " = ") != std::string::npos);
  }

  const MdConfig paper = parseConfigFile(dir + "paper.toml");
  CHECK(paper.system.N == 50016);
  CHECK(paper.system.phi == 0.076);
  CHECK(paper.run.t_end == 1000.0);
  CHECK(paper.contact.model == "hertz");
  CHECK(paper.contact.E == 278.6);
  CHECK(paper.contact.D == 27.7);
  CHECK(paper.contact.clamp);

  const MdConfig haff = parseConfigFile(dir + "haff.toml");
  CHECK(haff.contact.model == "spring_dashpot");
  CHECK(haff.contact.restitution == 0.9);
  CHECK(haff.system.N == 2000);

  // Overrides work on presets too.
  CHECK(parseConfigFile(dir + "quick.toml", {"system.N=500"}).system.N == 500);
}

TEST_CASE("docs/config.md documents every key", "[md][config]") {
  const std::string doc = readText(sourceRoot() + "/docs/config.md");
  for (const auto& [key, value] : flatten(MdConfig{})) {
    INFO(key);
    CHECK(doc.find("`" + key + "`") != std::string::npos);
  }
}
