#pragma once
/// Running a Python script of tests/ with FreeCAD's command-line interpreter
/// (freecadcmd) in a test's folder, for the tests that let FreeCAD judge our
/// files. The script finds the folder in CSGVOX_FREECAD_DIR and writes one
/// line per part to results.txt there.

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace csgvox::test {

/// True when freecadcmd is on the PATH.
inline bool haveFreecad() {
  return std::system("command -v freecadcmd > /dev/null 2>&1") == 0;
}

/// Runs tests/<script> with freecadcmd in `dir` (10 minutes at most) and
/// reads the lines of its results.txt into `lines`. Fails, with the
/// interpreter's output, when the script wrote no results.
inline ::testing::AssertionResult runFreecadScript(const std::filesystem::path& dir,
                                                   const std::string& script,
                                                   std::vector<std::string>& lines) {
  const std::string cmd = "cd '" + dir.string() + "' && CSGVOX_FREECAD_DIR='" + dir.string() +
                          "' timeout 600 freecadcmd '" + CSGVOX_TESTS_DIR + "/" + script +
                          "' > freecad.log 2>&1";
  const int status = std::system(cmd.c_str());
  if (!WIFEXITED(status)) return ::testing::AssertionFailure() << cmd << " did not exit";
  std::ifstream results(dir / "results.txt");
  if (!results) {
    std::ostringstream log;
    log << std::ifstream(dir / "freecad.log").rdbuf();
    return ::testing::AssertionFailure() << "freecadcmd did not finish; its output:\n"
                                         << log.str();
  }
  lines.clear();
  for (std::string line; std::getline(results, line);) lines.push_back(line);
  return ::testing::AssertionSuccess();
}

}  // namespace csgvox::test
