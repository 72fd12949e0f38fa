#pragma once
/// \file Process.h
/// What a study needs of the operating system: child processes with their output in a log,
/// command lines a shell can repeat, and files written whole or not at all (POSIX; Linux's
/// PR_SET_PDEATHSIG so that no child outlives an interrupted study).
#include <sys/types.h>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace granagg::study {

/// fork + exec of argv (argv[0] looked up in PATH) with stdout and stderr appended to `log` and
/// stdin from /dev/null. The child gets SIGTERM when its parent dies. Status 127: could not run.
/// The child leads a process group of its own, so that a terminal's Ctrl-C reaches the study
/// alone, which stops its children in the way each needs (PairStudy): an MPI launcher that got
/// the SIGINT itself would kill its ranks before they write their checkpoint.
pid_t spawn(const std::vector<std::string>& argv, const std::filesystem::path& log);

/// The processes under `root` (its children, their children, ...) whose name is `name`
/// (/proc/PID/comm: the executed file's name, cut at 15 characters), found in /proc (Linux).
/// Only the outermost: the search does not go below a process it found. A process that forks
/// (a rank starting a helper) has a child of its own name until the child's exec, and that
/// child is not a rank.
std::vector<pid_t> descendantsNamed(pid_t root, const std::string& name);

/// `a` quoted for a POSIX shell where it needs to be ('...' with ' escaped).
std::string shellQuote(const std::string& a);
/// argv as one line a shell runs as the same command.
std::string joinCommand(const std::vector<std::string>& argv);

/// The last non-empty line of a log ("" if none), after its last carriage return (progress).
std::string lastLine(const std::filesystem::path& log);
/// The last line of a log that starts with `prefix` (after its last carriage return), else
/// lastLine(log): what a program said last, where a launcher (mpirun) writes after it.
std::string lastLine(const std::filesystem::path& log, const std::string& prefix);

/// The path of the running executable (/proc/self/exe), "granagg" if unknown.
std::string selfExe();
/// Whether `program` can be executed: a path to an executable file, or a name found so in PATH.
bool findProgram(const std::string& program);
/// Cores this process may run on (its affinity mask).
int availableCores();

/// The whole file ("" when it does not exist).
std::string readText(const std::filesystem::path& p);
/// Writes p.tmp and renames it to p: a marker or record is either complete or absent. Creates
/// p's folder if needed.
void writeText(const std::filesystem::path& p, const std::string& text);
void appendText(const std::filesystem::path& p, const std::string& text);

/// The FNV-1a 64-bit offset basis (Fowler, Noll, Vo; draft-eastlake-fnv).
constexpr std::uint64_t FNV1A_BASIS = 14695981039346656037ULL;
/// The basis short of its last digit (1469598103934665603): not FNV-1a, though as good a hash.
/// Older run records carry it (docs/pair.md); PairStudy still accepts them (RunJob).
constexpr std::uint64_t LEGACY_HASH_BASIS = 1469598103934665603ULL;

/// FNV-1a 64-bit hash as 16 hex digits: identifies a resolved configuration in a run's spec.
std::string fnv1a(const std::string& s, std::uint64_t basis = FNV1A_BASIS);

}  // namespace granagg::study
