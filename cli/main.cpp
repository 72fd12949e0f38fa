/// granagg: one executable, subcommands over the md / analysis / meanfield libraries.
#include <cstdio>
#include <exception>
#include <iostream>
#include <stdexcept>
#include <string>

#include <CLI/CLI.hpp>

#include "cli/CliContext.h"
#include "common/Csv.h"
#include "common/Version.h"

int main(int argc, char** argv) {
  using namespace granagg;
  cli::CliContext ctx{common::commandLine(argc, argv)};

  CLI::App app{
      "granagg: aggregation in charged granular gases -- MD engine, trajectory analysis and "
      "mean-field\n"
      "(Smoluchowski, kinetic theory) solver. Reduced units: particle diameter d = 1, mass m = 1,\n"
      "initial granular temperature T0 = 1 (design.md section 2).",
      "granagg"};
  app.set_version_flag("--version", common::versionString());
  app.require_subcommand(1);
  app.fallthrough(false);

  cli::registerMdCommand(app, ctx);
  cli::registerSmolCommand(app, ctx);
  cli::registerKineticCommand(app, ctx);
  cli::registerFitBetaCommand(app, ctx);
  cli::registerAnalyzeCommand(app, ctx);
  cli::registerPairCommand(app, ctx);

  // CLI11 reports an unknown first word only as "A subcommand is required": name it instead.
  if (argc >= 2 && argv[1][0] != '-') {
    bool known = false;
    std::string names;
    for (const CLI::App* sub : app.get_subcommands({})) {
      known |= sub->check_name(argv[1]);
      names += (names.empty() ? "" : ", ") + sub->get_name();
    }
    if (!known) {
      std::fprintf(stderr, "granagg: error: unknown subcommand '%s' (available: %s; see --help)\n",
                   argv[1], names.c_str());
      return 2;
    }
  }

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    // One line, naming the option; exit status 2 for every kind of bad input.
    std::fprintf(stderr, "granagg: error: %s (see --help)\n", e.what());
    return 2;
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "granagg: error: %s\n", e.what());
    return 2;
  } catch (const cli::Interrupted& e) {
    std::fprintf(stderr, "granagg: stopped: %s\n", e.what());
    return e.status();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "granagg: failed: %s\n", e.what());
    return 1;
  }
  return 0;
}
