#pragma once
/// \file CliContext.h
/// What every subcommand of `granagg` gets: the command line (for provenance headers) and the
/// conventions shared by all subcommands.
///
/// Error convention (README, "Errors"): bad user input throws std::invalid_argument with one
/// sentence naming the option and the allowed range; main() prints it on one line and exits 2.
/// Other failures (I/O, a solver that cannot continue) throw std::runtime_error: exit 1.
#include <csignal>
#include <stdexcept>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "common/Interrupted.h"
#include "common/PaperValues.h"

namespace granagg::cli {

struct CliContext {
  std::string command_line;  ///< argv joined, recorded in every output's provenance header
};

using common::Interrupted;  // (common/Interrupted.h)

/// From now on SIGINT and SIGTERM (Ctrl-C, Slurm's time limit, kill) only set stopSignal(); the
/// running command polls it and stops cleanly within a chunk of steps. Further signals change
/// nothing (SIGKILL still kills).
void catchStopSignals();
/// The signal caught by catchStopSignals(), 0 if none; a pointer for md::RunOptions::stop.
const volatile std::sig_atomic_t* stopSignal();

/// Where data/ is looked for: $GRANAGG_DATA first (if set), then the source tree's data/.
std::vector<std::string> dataDirs();

/// The file `<data>/<sub>/<name>.toml` from the first of dataDirs() that has it (presets of md
/// runs and of pair studies). An unknown name throws std::invalid_argument naming `what` (the
/// option or key) and listing the names available.
std::string findPreset(const std::string& sub, const std::string& name, const std::string& what);

/// The paper's published values, from data/reference/paper.json (read once).
const common::PaperValues& paperValues();

/// Registers `granagg smol ...` (cli/SmolCommand.cpp).
void registerSmolCommand(CLI::App& app, const CliContext& ctx);
/// Registers `granagg md ...` (cli/MdCommand.cpp).
void registerMdCommand(CLI::App& app, const CliContext& ctx);
/// Registers `granagg kinetic ...` (cli/KineticCommand.cpp).
void registerKineticCommand(CLI::App& app, const CliContext& ctx);
/// Registers `granagg fit-beta ...` (cli/FitBetaCommand.cpp).
void registerFitBetaCommand(CLI::App& app, const CliContext& ctx);
/// Registers `granagg analyze ...` (cli/AnalyzeCommand.cpp).
void registerAnalyzeCommand(CLI::App& app, const CliContext& ctx);
/// Registers `granagg pair ...` (cli/PairCommand.cpp).
void registerPairCommand(CLI::App& app, const CliContext& ctx);

}  // namespace granagg::cli
