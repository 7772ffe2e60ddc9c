#include "io/batch_summary.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <type_traits>

#include "io/errors.h"

namespace csgvox {

namespace fs = std::filesystem;

const char* rowStatusName(RowStatus status) {
  switch (status) {
    case RowStatus::Ok:
      return "ok";
    case RowStatus::Error:
      return "error";
    case RowStatus::Crashed:
      return "crashed";
  }
  return "?";
}

SummaryRow rowFromReport(const fs::path& reportFile, const std::string& scanPath,
                         const std::string& output, double seconds) {
  std::ifstream in(reportFile, std::ios::binary);
  if (!in) throw IoError(reportFile.string() + ": cannot be opened for reading");
  nlohmann::json report;
  try {
    in >> report;
  } catch (const nlohmann::json::exception&) {
    throw ParseError(reportFile.string() + ": is not valid JSON");
  }
  if (!report.is_object() || report.value("status", "") != "ok" || !report.contains("tree") ||
      !report.contains("metrics")) {
    throw ParseError(reportFile.string() + ": is not the report of a finished job");
  }
  SummaryRow row;
  row.path = scanPath;
  row.output = output;
  row.status = RowStatus::Ok;
  try {
    const auto& tree = report.at("tree");
    row.primitives = tree.at("primitives").get<int>();
    row.operations = tree.at("operations").get<int>();
    const auto& metrics = report.at("metrics");
    if (metrics.contains("chamfer")) row.chamfer = metrics.at("chamfer").get<double>();
    if (metrics.contains("chamfer_relative")) {
      row.chamferRelative = metrics.at("chamfer_relative").get<double>();
    }
    if (metrics.contains("voxel_iou")) row.voxelIou = metrics.at("voxel_iou").get<double>();
    if (seconds < 0.0) {
      seconds = 0.0;
      const nlohmann::json timings = report.value("timings_s", nlohmann::json::object());
      for (const auto& [stage, s] : timings.items()) {
        if (s.is_number()) seconds += s.get<double>();
      }
    }
  } catch (const nlohmann::json::exception&) {
    throw ParseError(reportFile.string() + ": is not the report of a finished job");
  }
  row.seconds = seconds;
  return row;
}

const std::vector<std::string>& summaryColumns() {
  static const std::vector<std::string> columns = {
      "path",       "output",  "status",           "error",    "seconds", "primitives",
      "operations", "chamfer", "chamfer_relative", "voxel_iou"};
  return columns;
}

namespace {

template <typename T>
nlohmann::ordered_json orNull(const std::optional<T>& v) {
  return v ? nlohmann::ordered_json(*v) : nlohmann::ordered_json(nullptr);
}

std::string csvCell(const std::string& text) {
  if (text.find_first_of(",\"\r\n") == std::string::npos) return text;
  std::string quoted = "\"";
  for (const char c : text) {
    if (c == '"') quoted += '"';
    quoted += c;
  }
  return quoted + "\"";
}

// The shortest text that reads back as `v`.
std::string number(double v) {
  char buf[32];
  const auto [end, ec] = std::to_chars(buf, buf + sizeof(buf), v);
  return std::string(buf, ec == std::errc() ? end : buf);
}

template <typename T>
std::string numberOrEmpty(const std::optional<T>& v) {
  if (!v) return {};
  if constexpr (std::is_integral_v<T>) return std::to_string(*v);
  return number(*v);
}

void writeAll(int fd, const std::string& text, const fs::path& path) {
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) throw IoError(path.string() + ": cannot be written: " + std::strerror(errno));
    done += std::size_t(n);
  }
  ::fsync(fd);
}

// Opens `path` for appending; with `keep`, cuts a torn last line (no
// newline at the end) left by a killed run, otherwise empties the file.
int openForAppend(const fs::path& path, bool keep) {
  const int fd =
      ::open(path.c_str(), O_RDWR | O_CREAT | O_APPEND | O_CLOEXEC | (keep ? 0 : O_TRUNC), 0644);
  if (fd < 0) {
    throw IoError(path.string() + ": cannot be opened for writing: " + std::strerror(errno));
  }
  if (keep) {
    const off_t size = ::lseek(fd, 0, SEEK_END);
    off_t end = size;
    char c = 0;
    while (end > 0 && ::pread(fd, &c, 1, end - 1) == 1 && c != '\n') --end;
    if (end != size && ::ftruncate(fd, end) != 0) {
      ::close(fd);
      throw IoError(path.string() + ": cannot be truncated: " + std::strerror(errno));
    }
  }
  return fd;
}

}  // namespace

nlohmann::ordered_json rowJson(const SummaryRow& row) {
  nlohmann::ordered_json j;
  j["path"] = row.path;
  j["output"] = row.output;
  j["status"] = rowStatusName(row.status);
  j["error"] =
      row.error.empty() ? nlohmann::ordered_json(nullptr) : nlohmann::ordered_json(row.error);
  j["seconds"] = row.seconds;
  j["primitives"] = orNull(row.primitives);
  j["operations"] = orNull(row.operations);
  j["chamfer"] = orNull(row.chamfer);
  j["chamfer_relative"] = orNull(row.chamferRelative);
  j["voxel_iou"] = orNull(row.voxelIou);
  return j;
}

std::string rowCsv(const SummaryRow& row) {
  const std::string cells[] = {csvCell(row.path),
                               csvCell(row.output),
                               rowStatusName(row.status),
                               csvCell(row.error),
                               number(row.seconds),
                               numberOrEmpty(row.primitives),
                               numberOrEmpty(row.operations),
                               numberOrEmpty(row.chamfer),
                               numberOrEmpty(row.chamferRelative),
                               numberOrEmpty(row.voxelIou)};
  std::string line;
  for (std::size_t i = 0; i < std::size(cells); ++i) {
    if (i > 0) line += ',';
    line += cells[i];
  }
  return line;
}

SummaryWriter::SummaryWriter(const fs::path& folder, bool keep)
    : jsonlPath_(folder / "summary.jsonl"), csvPath_(folder / "summary.csv") {
  std::error_code ec;
  fs::create_directories(folder, ec);
  jsonl_ = openForAppend(jsonlPath_, keep);
  try {
    csv_ = openForAppend(csvPath_, keep);
    if (::lseek(csv_, 0, SEEK_END) == 0) {
      std::string header;
      for (const std::string& c : summaryColumns()) header += (header.empty() ? "" : ",") + c;
      writeAll(csv_, header + "\n", csvPath_);
    }
  } catch (...) {
    if (csv_ >= 0) ::close(csv_);
    ::close(jsonl_);
    throw;
  }
}

SummaryWriter::~SummaryWriter() {
  ::close(jsonl_);
  ::close(csv_);
}

void SummaryWriter::append(const SummaryRow& row) {
  writeAll(jsonl_, rowJson(row).dump() + "\n", jsonlPath_);
  writeAll(csv_, rowCsv(row) + "\n", csvPath_);
}

std::map<std::string, nlohmann::json> readSummaryRows(const fs::path& jsonl) {
  std::map<std::string, nlohmann::json> rows;
  std::error_code ec;
  if (!fs::exists(jsonl, ec)) return rows;
  std::ifstream in(jsonl, std::ios::binary);
  if (!in) throw IoError(jsonl.string() + ": cannot be opened for reading");
  std::string line;
  while (std::getline(in, line)) {
    const nlohmann::json j = nlohmann::json::parse(line, nullptr, false);
    if (!j.is_object() || !j.contains("path") || !j["path"].is_string()) continue;
    rows[j["path"].get<std::string>()] = j;
  }
  return rows;
}

}  // namespace csgvox
