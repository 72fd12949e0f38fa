/// granagg: one executable, subcommands over the md / analysis / meanfield libraries.
#include <csignal>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <iostream>
#include <stdexcept>
#include <string>

#include <CLI/CLI.hpp>

#include "cli/CliContext.h"
#include "common/Csv.h"
#include "common/Strings.h"
#include "common/Version.h"

namespace {

/// CLI11 reports an unknown word where a subcommand is expected as "A subcommand is required"
/// (top level, `kinetic`) or "The following argument was not expected": this names the word and
/// the subcommands available there, the same at every level. "" when the words are known (or the
/// level takes positional arguments, whose checks are CLI11's).
std::string unknownSubcommand(const CLI::App& app, int argc, const char* const* argv) {
  const CLI::App* level = &app;
  std::string path = "granagg";
  for (int k = 1; k < argc && argv[k][0] != '-'; ++k) {
    const auto subs = level->get_subcommands({});
    if (subs.empty()) break;
    const CLI::App* next = nullptr;
    std::string names;
    for (const CLI::App* sub : subs) {
      if (sub->check_name(argv[k])) next = sub;
      names += (names.empty() ? "" : ", ") + sub->get_name();
    }
    if (!next) {
      const bool positionals =
          !level->get_options([](const CLI::Option* o) { return o->get_positional(); }).empty();
      if (positionals) break;
      return "unknown subcommand '" + std::string(argv[k]) + "' of '" + path +
             "' (available: " + names + "; see " + path + " --help)";
    }
    level = next;
    path += " " + next->get_name();
  }
  return "";
}

}  // namespace

int main(int argc, char** argv) {
  using namespace granagg;
  // A file-size limit (ulimit -f) fails a write with EFBIG, as a full disk does with ENOSPC,
  // instead of killing the command without a word (every command: md, analyze, smol...).
  ::signal(SIGXFSZ, SIG_IGN);
  cli::CliContext ctx{common::commandLine(argc, argv)};

  CLI::App app{
      "granagg: aggregation in charged granular gases -- MD engine, trajectory analysis and "
      "mean-field\n"
      "(Smoluchowski, kinetic theory) solver. Reduced units: particle diameter d = 1, mass m = 1,\n"
      "initial granular temperature T0 = 1 (docs/model.md section 2).",
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

  if (const std::string unknown = unknownSubcommand(app, argc, argv); !unknown.empty()) {
    std::fprintf(stderr, "%s%s\n", common::ERROR_PREFIX, unknown.c_str());
    return 2;
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
    std::fprintf(stderr, "%s%s (see --help)\n", common::ERROR_PREFIX,
                 common::terminalSafe(e.what()).c_str());
    return 2;
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "%s%s\n", common::ERROR_PREFIX, common::terminalSafe(e.what()).c_str());
    return 2;
  } catch (const std::filesystem::filesystem_error& e) {
    // Outputs are checked before the work (common/OutputPath.h); this is a write that failed
    // later (a disk that filled, a folder removed meanwhile): the path and the system's reason.
    std::fprintf(stderr, "granagg: failed: '%s': %s\n", e.path1().string().c_str(),
                 e.code().message().c_str());
    return 1;
  } catch (const cli::Interrupted& e) {
    std::fprintf(stderr, "granagg: stopped: %s\n", common::terminalSafe(e.what()).c_str());
    return e.status();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "granagg: failed: %s\n", common::terminalSafe(e.what()).c_str());
    return 1;
  }
  return 0;
}
