#pragma once
/// \file Strings.h
/// Small string helpers shared by the CLI and the readers.
#include <ctime>
#include <string>
#include <vector>

namespace granagg::common {
std::string trim(const std::string& s);
std::vector<std::string> split(const std::string& s, char sep);
std::string join(const std::vector<std::string>& parts, const std::string& sep);
/// `text` safe to print on a terminal: control bytes other than newline and tab (and DEL) as
/// "\xNN". Error messages quote the offending token of an input file, which may be binary; the
/// CLIs print every error through this.
std::string terminalSafe(const std::string& text);
/// A UTC time stamp, ISO 8601 to the second ("2026-12-08T02:45:10Z"): of `t`, or of now. The one
/// format of every time stamp granagg writes (H5MD run records, folder locks, study logs).
std::string utcTimestamp(std::time_t t);
std::string utcTimestamp();
/// Why a write failed, for its one-line message: "the disk is full (No space left on device)"
/// for ENOSPC and EDQUOT, "the file-size limit is reached (File too large)" for EFBIG, else
/// strerror(err).
std::string writeErrorReason(int err);
/// Parses a whole string as a double (also "nan", "inf"); false if anything is left over.
bool parseReal(const std::string& s, double& out);
/// printf into a std::string, of any length (the compiler checks the arguments against fmt).
std::string printfString(const char* fmt, ...) __attribute__((format(printf, 1, 2)));
/// A number for people: 4 significant digits ("%.4g"; formatReal's round-trip digits are for
/// tables and for input values echoed in errors).
std::string formatShort(double x);
}  // namespace granagg::common
