// common/OutputPath.h: the checks made before a command computes anything. The probe leaves
// nothing behind and creates no missing folder; each refusal names the option and the path.
#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "common/OutputPath.h"

#include "TestUtil.h"

using granagg::common::checkOutputFile;
using granagg::common::checkOutputFolder;
using granagg::test::tempDir;

namespace fs = std::filesystem;

TEST_CASE("output checks accept writable places and leave nothing behind", "[common][output]") {
  const fs::path dir = tempDir("outpath");
  CHECK_NOTHROW(checkOutputFile(dir / "t.csv"));
  CHECK_NOTHROW(checkOutputFolder(dir / "new" / "deeper"));  // created later, with parents
  CHECK_NOTHROW(checkOutputFolder(dir));                     // an existing folder
  CHECK_FALSE(fs::exists(dir / "new"));
  CHECK(fs::is_empty(dir));  // no probe left
  fs::remove_all(dir);
}

TEST_CASE("output checks refuse files for folders, folders for files and missing folders",
          "[common][output]") {
  const fs::path dir = tempDir("outpath-bad");
  const fs::path file = dir / "a.csv";
  std::ofstream(file) << "x\n";
  CHECK_THROWS_AS(checkOutputFolder(file, "--out"), std::invalid_argument);
  CHECK_THROWS_WITH(checkOutputFolder(file, "--out"),
                    "--out '" + file.string() + "' is a file, not a folder; give a folder");
  CHECK_THROWS_WITH(checkOutputFolder(file / "sub", "--out"),
                    "--out '" + (file / "sub").string() +
                        "': cannot create the folder (Not a directory)");
  CHECK_THROWS_WITH(checkOutputFile(dir, "-o"),
                    "-o '" + dir.string() + "' is a folder; give a file name");
  CHECK_THROWS_WITH(checkOutputFile(dir / "no" / "t.csv", "--out"),
                    "--out '" + (dir / "no" / "t.csv").string() + "': the folder '" +
                        (dir / "no").string() + "' does not exist");
  CHECK_THROWS_WITH(checkOutputFile(file / "t.csv", "--out"),
                    Catch::Contains("'" + file.string() + "' is not a folder"));
  CHECK_FALSE(fs::exists(dir / "no"));
  fs::remove_all(dir);
}
