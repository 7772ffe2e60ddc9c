#pragma once
/// The bundled ground-truth parts (data/<part>/tree.json), for tests that
/// loop over every part.

#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

namespace csgvox::test {

/// Folder holding the bundled parts.
inline std::filesystem::path dataDir() { return CSGVOX_DATA_DIR; }

/// Names of the bundled parts, sorted.
inline std::vector<std::string> partNames() {
  std::vector<std::string> names;
  for (const auto& e : std::filesystem::directory_iterator(dataDir())) {
    if (e.is_directory() && std::filesystem::exists(e.path() / "tree.json")) {
      names.push_back(e.path().filename().string());
    }
  }
  std::sort(names.begin(), names.end());
  return names;
}

/// A fresh empty temporary directory for one test, private to this process
/// (two checkouts running the same test at once do not share it).
inline std::filesystem::path freshTempDir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("csgvox-test-" + name + "-" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

}  // namespace csgvox::test
