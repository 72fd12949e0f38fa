// Outputs that cannot be written are refused before any work, in one line of one style naming
// --out, with exit status 2 (common/OutputPath.h): smol, smol zbeta, kinetic, fit-beta, analyze
// and md: a missing or read-only folder shows before the solve or fit, never as raw
// "filesystem error" text.
#include <catch2/catch.hpp>

#include "RunCommand.h"

#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "TestUtil.h"

using granagg::test::tempDir;

namespace fs = std::filesystem;

namespace {

int countLines(const std::string& s) {
  int n = 0;
  for (char c : s) n += (c == '\n');
  return n;
}

/// A folder no new entry can be made in: one without write permission, or, for root (whom
/// permissions do not stop), sysfs. Empty when neither is available here.
fs::path unwritableFolder(const fs::path& scratch) {
  fs::path dir;
  if (::geteuid() == 0) {
    dir = "/sys";
    if (!fs::is_directory(dir)) return {};
  } else {
    dir = scratch / "read-only";
    fs::create_directories(dir);
    ::chmod(dir.c_str(), 0555);
  }
  const fs::path probe = dir / "granagg-test-probe";
  std::ofstream(probe.string()) << "x";
  if (fs::exists(probe)) {
    fs::remove(probe);
    return {};
  }
  return dir;
}

/// The one line every refusal prints.
void checkRefused(const Run& r, const std::string& says) {
  INFO(r.output);
  CHECK(r.status == 2);
  CHECK(countLines(r.output) == 1);
  CHECK_THAT(r.output, Catch::StartsWith("granagg: error: --out '"));
  CHECK_THAT(r.output, Catch::Contains(says));
  CHECK_THAT(r.output, !Catch::Contains("filesystem error"));
}

}  // namespace

TEST_CASE("an --out that cannot be written is refused before the work", "[cli][output]") {
  const fs::path dir = tempDir("outputs");
  const fs::path ro = unwritableFolder(dir);
  if (ro.empty()) {
    WARN("no unwritable folder here (every folder takes new files): check skipped");
    return;
  }
  const std::string in_ro = ro.string();
  // the README's sectional solve (about 1 s): refused at once, no solver line printed
  const Run smol = runGranagg("smol --beta 3 --method sectional --t-end 1e7 --out " + in_ro +
                              "/S.csv");
  checkRefused(smol, "--out '" + in_ro + "/S.csv': cannot create a file in '" + in_ro + "' (");
  CHECK_THAT(smol.output, !Catch::Contains("smol: kernel"));
  checkRefused(runGranagg("smol zbeta --out " + in_ro + "/z.csv"), "cannot create a file in");
  checkRefused(runGranagg("kinetic haff --eps 0.9 --out " + in_ro + "/h.csv"),
               "cannot create a file in");

  std::ofstream(dir / "S.csv") << "t,S\n1,1\n2,2.4\n3,4.1\n4,6\n5,8.1\n6,10.5\n7,13\n";
  const std::string input = (dir / "S.csv").string();
  checkRefused(runGranagg("fit-beta " + input + " -q --out " + in_ro + "/fit"),
               "--out '" + in_ro + "/fit': cannot create the folder (");
  checkRefused(runGranagg("fit-beta " + input + " -q --out " + in_ro),
               "--out '" + in_ro + "': cannot write in it (");
  checkRefused(runGranagg("fit-beta " + input + " -q --out " + input),
               "is a file, not a folder");

  const fs::path dump = dir / "two.dump";
  {
    std::ofstream out(dump);
    for (int k = 0; k < 2; ++k)
      out << "ITEM: TIMESTEP\n"
          << k << "\nITEM: NUMBER OF ATOMS\n1\nITEM: BOX BOUNDS pp pp pp\n0 6\n0 6\n0 6\n"
          << "ITEM: ATOMS id x y z\n1 1 1 1\n";
  }
  checkRefused(runGranagg("analyze " + dump.string() + " -q --out " + in_ro + "/a"),
               "--out '" + in_ro + "/a': cannot create the folder (");

  // md: refused before the initial state and the engine are built (no start-up lines)
  const Run md = runGranagg("md --preset quick --out " + in_ro + "/run");
  checkRefused(md, "--out '" + in_ro + "/run': cannot create the folder (");
  CHECK_THAT(md.output, !Catch::Contains("md: "));
  checkRefused(runGranagg("md --preset quick -q --out " + input + "/run"),
               "cannot create the folder (Not a directory)");
  fs::remove_all(dir);
}

TEST_CASE("smol refuses an --out in a missing folder before solving", "[cli][output]") {
  const fs::path dir = tempDir("missing");
  const std::string out = (dir / "no" / "such" / "S.csv").string();
  const Run r = runGranagg("smol --beta 3 --method sectional --t-end 1e7 --out " + out);
  checkRefused(r, "--out '" + out + "': the folder '" + (dir / "no" / "such").string() +
                      "' does not exist");
  CHECK_FALSE(fs::exists(dir / "no"));  // nothing created
  const Run folder = runGranagg("smol --beta 3 --method mono --t-end 10 --out " + dir.string());
  checkRefused(folder, "is a folder; give a file name");
  fs::remove_all(dir);
}
