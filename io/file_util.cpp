#include "io/file_util.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <fstream>
#include <system_error>

#include "io/errors.h"

namespace csgvox {

namespace fs = std::filesystem;

void requireReadableFile(const fs::path& path) {
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (ec || !fs::exists(st)) throw IoError(path.string() + ": no such file");
  if (fs::is_directory(st)) throw IoError(path.string() + ": is a directory, not a file");
  // A FIFO, socket or device could block the reader or never end.
  if (!fs::is_regular_file(st)) {
    throw IoError(path.string() + ": is not a regular file (a pipe, socket or device)");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path.string() + ": cannot be opened for reading");
}

void writeFileAtomically(const fs::path& path, const std::function<void(std::ostream&)>& write,
                         bool binary) {
  static std::atomic<unsigned> counter{0};
  if (fs::is_directory(path)) throw IoError(path.string() + ": is a directory, cannot write it");
  const fs::path parent = path.has_parent_path() ? path.parent_path() : fs::path(".");
  std::error_code ec;
  if (!fs::is_directory(parent, ec)) {
    throw IoError(path.string() + ": directory " + parent.string() + " does not exist");
  }
  std::string tmpName = ".";
  tmpName += path.filename().string();
  tmpName += ".tmp" + std::to_string(::getpid()) + "-" + std::to_string(counter++);
  const fs::path tmp = parent / tmpName;
  try {
    {
      std::ofstream out(tmp, binary ? std::ios::binary | std::ios::trunc : std::ios::trunc);
      if (!out) throw IoError(path.string() + ": cannot be created for writing");
      write(out);
      out.flush();
      if (!out) throw IoError(path.string() + ": write failed (disk full?)");
    }
    fs::rename(tmp, path, ec);
    if (ec) throw IoError(path.string() + ": cannot be written (" + ec.message() + ")");
  } catch (...) {
    fs::remove(tmp, ec);
    throw;
  }
}

void requireNotInput(const fs::path& output, const fs::path& input) {
  std::error_code ec;
  if (fs::exists(output, ec) && fs::equivalent(output, input, ec)) {
    throw IoError(output.string() + ": is the input file; refusing to overwrite it");
  }
}

std::string lowerExtension(const fs::path& path) {
  std::string ext = path.extension().string();
  if (!ext.empty() && ext[0] == '.') ext.erase(0, 1);
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

}  // namespace csgvox
