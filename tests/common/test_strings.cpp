/// common/Strings.h's helpers for messages and time stamps, against fixed references.
#include <catch2/catch.hpp>

#include <cerrno>
#include <regex>
#include <string>

#include "common/Strings.h"

using namespace granagg::common;

TEST_CASE("utcTimestamp writes ISO 8601 UTC to the second", "[common]") {
  CHECK(utcTimestamp(0) == "1970-01-01T00:00:00Z");
  CHECK(utcTimestamp(951782400) == "2000-02-29T00:00:00Z");       // a leap day
  CHECK(utcTimestamp(1796697599) == "2026-12-08T02:39:59Z");      // (date -u -d @1796697599)
  CHECK(std::regex_match(utcTimestamp(), std::regex(R"(\d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ)")));
}

TEST_CASE("terminalSafe escapes control bytes and keeps text, newlines and tabs", "[common]") {
  CHECK(terminalSafe("plain text, UTF-8: \xc3\xa9") == "plain text, UTF-8: \xc3\xa9");
  CHECK(terminalSafe("a\tb\nc") == "a\tb\nc");
  CHECK(terminalSafe(std::string("x\x1b[31my\x01\x7f", 9)) == "x\\x1b[31my\\x01\\x7f");
  CHECK(terminalSafe(std::string("\0", 1)) == "\\x00");
}

TEST_CASE("writeErrorReason names a full disk and a file-size limit", "[common]") {
  CHECK(writeErrorReason(ENOSPC) == "the disk is full (No space left on device)");
  CHECK(writeErrorReason(EDQUOT).rfind("the disk is full (", 0) == 0);
  CHECK(writeErrorReason(EFBIG) == "the file-size limit is reached (File too large)");
  CHECK(writeErrorReason(EACCES) == "Permission denied");
}
