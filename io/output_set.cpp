#include "io/output_set.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdlib>
#include <system_error>

#include "io/errors.h"
#include "io/file_util.h"

namespace csgvox {

namespace fs = std::filesystem;

namespace {

std::string uniqueSuffix() {
  static std::atomic<unsigned> counter{0};
  return std::to_string(::getpid()) + "-" + std::to_string(counter++);
}

// Removes the staging folders in `dir` whose names start with `prefix`,
// followed by "<pid>-<n>", of runs that no longer exist (killed ones).
void removeStaleStaging(const fs::path& dir, const std::string& prefix) {
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.rfind(prefix, 0) != 0 || !it->is_directory(ec)) continue;
    const std::string rest = name.substr(prefix.size());
    const long pid = std::strtol(rest.c_str(), nullptr, 10);
    if (pid <= 0 || (::kill(pid_t(pid), 0) != 0 && errno == ESRCH)) {
      std::error_code ignored;
      fs::remove_all(it->path(), ignored);
    }
  }
}

}  // namespace

OutputSet::OutputSet(fs::path folder, std::vector<std::string> names,
                     std::span<const fs::path> inputs)
    : folder_(std::move(folder)), names_(std::move(names)) {
  for (const std::string& name : names_) {
    for (const fs::path& input : inputs) requireNotInput(folder_ / name, input);
  }
  std::error_code ec;
  const fs::file_status st = fs::status(folder_, ec);
  if (fs::exists(st) && !fs::is_directory(st)) {
    throw IoError(folder_.string() + ": exists and is not a directory");
  }
  freshFolder_ = !fs::exists(st);
  if (freshFolder_) {
    fs::path target = fs::absolute(folder_, ec).lexically_normal();
    if (target.filename().empty()) target = target.parent_path();  // "out/"
    fs::create_directories(target.parent_path(), ec);
    const std::string prefix = "." + target.filename().string() + ".partial-";
    removeStaleStaging(target.parent_path(), prefix);
    staging_ = target.parent_path() / (prefix + uniqueSuffix());
  } else {
    removeStaleStaging(folder_, ".csgvox-partial-");
    staging_ = folder_ / (".csgvox-partial-" + uniqueSuffix());
  }
  if (!fs::create_directory(staging_, ec) || ec) {
    throw IoError(folder_.string() + ": cannot create the output directory" +
                  (ec ? " (" + ec.message() + ")" : std::string()));
  }
}

OutputSet::~OutputSet() {
  if (committed_) return;
  std::error_code ec;
  fs::remove_all(staging_, ec);
}

fs::path OutputSet::path(const std::string& name) const { return staging_ / name; }

void OutputSet::skip(const std::string& name) {
  const auto it = std::find(names_.begin(), names_.end(), name);
  if (it == names_.end()) return;
  names_.erase(it);
  skipped_.push_back(name);
  std::error_code ec;
  fs::remove(staging_ / name, ec);
}

void OutputSet::commit() {
  std::error_code ec;
  for (const std::string& name : names_) {
    if (!fs::is_regular_file(staging_ / name, ec)) {
      throw IoError((folder_ / name).string() + ": was not written");
    }
  }
  if (freshFolder_) {
    // The whole set appears in one rename, unless the folder appeared
    // meanwhile (another run): then file by file as below.
    fs::rename(staging_, folder_, ec);
    if (!ec) {
      committed_ = true;
      return;
    }
    ec.clear();
  }
  for (const std::string& name : names_) {
    fs::rename(staging_ / name, folder_ / name, ec);
    if (ec) {
      throw IoError((folder_ / name).string() + ": cannot be written (" + ec.message() + ")");
    }
  }
  for (const std::string& name : skipped_) fs::remove(folder_ / name, ec);
  committed_ = true;
  fs::remove_all(staging_, ec);
}

}  // namespace csgvox
