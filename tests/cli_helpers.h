#pragma once
// Running the csgvox executable from tests: the command, its exit code and
// output, and the Cli fixture with its one-line-error check.

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "part_list.h"
#include "test_helpers.h"

namespace csgvox {

namespace fs = std::filesystem;

struct RunResult {
  int code = -1;
  std::string out, err;
};

inline std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Runs csgvox with `args` (shell words) in `dir`; with `timeoutSeconds`,
// under timeout(1), so that a hang ends with exit code 124.
inline RunResult run(const std::string& args, const fs::path& dir, int timeoutSeconds = 0) {
  const std::string prefix =
      timeoutSeconds > 0 ? "timeout " + std::to_string(timeoutSeconds) + " " : "";
  const std::string cmd = prefix + std::string(CSGVOX_BINARY) + " " + args + " > '" +
                          (dir / "stdout.txt").string() + "' 2> '" + (dir / "stderr.txt").string() +
                          "' < /dev/null";
  const int status = std::system(cmd.c_str());
  RunResult r;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = slurp(dir / "stdout.txt");
  r.err = slurp(dir / "stderr.txt");
  return r;
}

inline void write(const fs::path& p, const std::string& text) {
  std::ofstream(p, std::ios::binary) << text;
}

inline std::string asciiPly(int n, const std::string& extraLine = "", bool normals = true) {
  std::ostringstream s;
  s << "ply\nformat ascii 1.0\nelement vertex " << n
    << "\nproperty float x\nproperty float y\nproperty float z\n";
  if (normals) s << "property float nx\nproperty float ny\nproperty float nz\n";
  s << "end_header\n";
  for (int i = 0; i < n; ++i) {
    const double a = 0.1 * i, z = 0.01 * i;
    s << std::cos(a) << " " << std::sin(a) << " " << z;
    if (normals) s << " " << std::cos(a) << " " << std::sin(a) << " 0";
    s << "\n";
  }
  return s.str() + extraLine;
}

class Cli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = test::freshTempDir(::testing::UnitTest::GetInstance()->current_test_info()->name());
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Expects exit code 1 and exactly one stderr line that names `file`.
  void expectCleanError(const std::string& args, const std::string& file) {
    const RunResult r = run(args, dir_);
    EXPECT_EQ(r.code, 1) << args << "\n" << r.err;
    EXPECT_NE(r.err.find(file), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_EQ(r.err.rfind("csgvox: error: ", 0), 0u) << r.err;
  }

  fs::path dir_;
};

// An ASCII PLY of the given points and normals.
inline std::string pointsPly(const std::vector<std::array<double, 6>>& points) {
  std::ostringstream s;
  s << "ply\nformat ascii 1.0\nelement vertex " << points.size()
    << "\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty "
       "float ny\nproperty float nz\nend_header\n";
  for (const auto& p : points) {
    s << p[0] << " " << p[1] << " " << p[2] << " " << p[3] << " " << p[4] << " " << p[5] << "\n";
  }
  return s.str();
}

}  // namespace csgvox
