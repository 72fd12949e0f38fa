// The one Catch2 main, compiled once for all test executables. Besides Catch2's own options it
// takes --write-reference: the golden-value tests then write their reference files instead of
// comparing against them (tests/md/test_backend.cpp; scripts/write_reference_states.sh).
#define CATCH_CONFIG_RUNNER
#include <catch2/catch.hpp>

#include "TestUtil.h"

namespace granagg::test {
namespace {
bool g_write_reference = false;
}
bool writeReference() { return g_write_reference; }
}  // namespace granagg::test

int main(int argc, char* argv[]) {
  Catch::Session session;
  using Catch::clara::Opt;
  session.cli(session.cli() |
              Opt(granagg::test::g_write_reference)["--write-reference"](
                  "rewrite the golden values (tests/data/backend) from this build instead of "
                  "checking them; CPU build only, after an intended change of the trajectory"));
  if (const int rc = session.applyCommandLine(argc, argv)) return rc;
  return session.run();
}
