#include "app/batch_inputs.h"

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "io/errors.h"
#include "io/file_util.h"

namespace csgvox::app {

namespace fs = std::filesystem;

namespace {

std::vector<std::string> words(const std::string& line) {
  std::istringstream in(line);
  std::vector<std::string> w;
  for (std::string s; in >> s;) w.push_back(s);
  return w;
}

bool isNumber(const std::string& word) {
  char* end = nullptr;
  std::strtod(word.c_str(), &end);
  return end != word.c_str() && *end == '\0';
}

// A .txt file is a point cloud when its first data line holds 3 or 6
// numbers (after an optional point count alone on the first line).
bool textHoldsPoints(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::string line;
  for (int lineNumber = 1; lineNumber <= 1000 && std::getline(in, line); ++lineNumber) {
    const std::vector<std::string> w = words(line);
    if (w.empty() || w[0][0] == '#') continue;
    if (lineNumber == 1 && w.size() == 1 && isNumber(w[0])) continue;
    return (w.size() == 3 || w.size() == 6) && std::all_of(w.begin(), w.end(), isNumber);
  }
  return false;
}

// `path` made relative: lexically normal, without root or leading "..".
fs::path relativeName(const fs::path& path) {
  fs::path out;
  bool leading = true;
  for (const fs::path& part : path.lexically_normal().relative_path()) {
    if (leading && (part == ".." || part == ".")) continue;
    leading = false;
    out /= part;
  }
  return out;
}

fs::path withoutExtension(fs::path p) { return p.replace_extension(); }

class Collector {
 public:
  explicit Collector(const fs::path& outDir) : outDir_(outDir) {}

  void input(const fs::path& path, const std::string& label, int depth) {
    std::error_code ec;
    const fs::file_status st = fs::status(path, ec);
    if (ec || !fs::exists(st)) throw IoError(label + ": no such file or folder");
    if (fs::is_directory(st)) {
      folder(path, label);
    } else if (looksLikeScan(path)) {
      add(path, label, relativeName(withoutExtension(fs::path(label))));
    } else {
      list(path, label, depth);
    }
  }

  std::vector<BatchScan> take() { return std::move(scans_); }

 private:
  void folder(const fs::path& root, const std::string& label) {
    std::vector<fs::path> found;
    std::error_code ec;
    fs::recursive_directory_iterator it(root, fs::directory_options::skip_permission_denied, ec);
    if (ec) throw IoError(label + ": cannot be read: " + ec.message());
    for (const fs::recursive_directory_iterator end; it != end; it.increment(ec)) {
      if (ec) throw IoError(label + ": cannot be read: " + ec.message());
      const fs::path& p = it->path();
      const bool hidden = p.filename().string().starts_with(".");
      if (it->is_directory(ec)) {
        if (hidden || fs::equivalent(p, outDir_, ec) || fs::exists(p / "report.json", ec)) {
          it.disable_recursion_pending();
        }
        continue;
      }
      if (!hidden && it->is_regular_file(ec) && looksLikeScan(p)) found.push_back(p);
    }
    std::sort(found.begin(), found.end());
    for (const fs::path& p : found) {
      add(p, (fs::path(label) / p.lexically_relative(root)).string(),
          withoutExtension(p.lexically_relative(root)));
    }
  }

  void list(const fs::path& path, const std::string& label, int depth) {
    if (depth > 8) throw IoError(label + ": lists nest more than 8 deep");
    requireReadableFile(path);
    std::ifstream in(path, std::ios::binary);
    if (!in) throw IoError(label + ": cannot be opened for reading");
    std::string line;
    for (int lineNumber = 1; std::getline(in, line); ++lineNumber) {
      const auto first = line.find_first_not_of(" \t\r");
      if (first == std::string::npos || line[first] == '#') continue;
      const auto last = line.find_last_not_of(" \t\r");
      const fs::path entry(line.substr(first, last - first + 1));
      const fs::path resolved = entry.is_absolute() ? entry : path.parent_path() / entry;
      try {
        input(resolved, resolved.string(), depth + 1);
      } catch (const IoError& e) {
        throw IoError(label + ": line " + std::to_string(lineNumber) + ": " + e.what());
      }
    }
  }

  void add(const fs::path& file, const std::string& label, const fs::path& output) {
    std::error_code ec;
    const fs::path key = fs::weakly_canonical(file, ec);
    if (!seen_.insert(ec ? file : key).second) return;
    const auto [at, fresh] = outputs_.emplace(output.string(), label);
    if (!fresh) {
      throw IoError(label + ": its outputs would go to the same folder as those of " + at->second +
                    " (" + output.string() + ")");
    }
    scans_.push_back({file, label, output});
  }

  fs::path outDir_;
  std::vector<BatchScan> scans_;
  std::set<fs::path> seen_;
  std::map<std::string, std::string> outputs_;
};

}  // namespace

bool looksLikeScan(const fs::path& path) {
  const std::string ext = lowerExtension(path);
  for (const char* known : {"ply", "xyz", "xyzn", "pts", "off", "obj", "stl"}) {
    if (ext == known) return true;
  }
  return ext == "txt" && textHoldsPoints(path);
}

std::vector<BatchScan> collectScans(std::span<const std::string> inputs, const fs::path& outDir) {
  Collector collector(outDir);
  for (const std::string& in : inputs) collector.input(fs::path(in), in, 0);
  return collector.take();
}

}  // namespace csgvox::app
