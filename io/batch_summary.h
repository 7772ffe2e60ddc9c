#pragma once
/// The summary of a batch of reconstructions: one row per scan, written as a
/// line of summary.jsonl (one JSON object) and a line of summary.csv (the
/// same columns), each appended and flushed to disk as its scan finishes, so
/// that a killed run keeps every row it wrote.

#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace csgvox {

/// How one scan of a batch ended.
enum class RowStatus {
  Ok,       ///< the job wrote its outputs
  Error,    ///< the job refused the scan or failed (exit code 1, one-line message)
  Crashed,  ///< the job died (a signal, an unexpected exit code); worth running again
};

/// "ok", "error" or "crashed".
const char* rowStatusName(RowStatus status);

/// One scan's row. Figures that do not exist (a failed scan) are empty.
struct SummaryRow {
  std::string path;    ///< the scan as it was given (or found in a folder or list)
  std::string output;  ///< folder of the scan's outputs
  RowStatus status = RowStatus::Ok;
  std::string error;                      ///< the job's one-line message (empty when ok)
  double seconds = 0.0;                   ///< wall-clock time of the job (s)
  std::optional<int> primitives;          ///< leaves of the tree (count)
  std::optional<int> operations;          ///< operations of the tree (count)
  std::optional<double> chamfer;          ///< Chamfer distance to the scan, scan units
  std::optional<double> chamferRelative;  ///< the same, fraction of the scan's diagonal
  std::optional<double> voxelIou;         ///< IoU of the tree's voxels and the inside labels
};

/// The row of a finished job read from its report.json (status "ok"): the
/// figures from the report, `seconds` as given (the report's timings when
/// negative).
/// @throw IoError when report.json cannot be read; ParseError when it is not
///        a job report.
SummaryRow rowFromReport(const std::filesystem::path& reportFile, const std::string& scanPath,
                         const std::string& output, double seconds = -1.0);

/// The row as one JSON object (keys in column order).
nlohmann::ordered_json rowJson(const SummaryRow& row);
/// The column names of summary.csv, in order (also the keys of rowJson).
const std::vector<std::string>& summaryColumns();
/// The row as one CSV line (no newline): RFC 4180 quoting, empty cells for
/// missing figures, numbers with full precision.
std::string rowCsv(const SummaryRow& row);

/// Appends rows to summary.jsonl and summary.csv in one folder. Each row is
/// written with one write() and synced before append() returns.
class SummaryWriter {
 public:
  /// Opens (creating) `folder`/summary.jsonl and `folder`/summary.csv. With
  /// `keep`, existing rows stay (a torn last line of a killed run is cut
  /// off); otherwise both files start empty. The CSV gets its header line
  /// when it is empty.
  /// @throw IoError when a file cannot be opened or written.
  SummaryWriter(const std::filesystem::path& folder, bool keep);
  SummaryWriter(const SummaryWriter&) = delete;
  SummaryWriter& operator=(const SummaryWriter&) = delete;
  ~SummaryWriter();

  /// Appends one row to both files. @throw IoError when a write fails.
  void append(const SummaryRow& row);

  /// summary.jsonl's path.
  const std::filesystem::path& jsonlPath() const { return jsonlPath_; }

 private:
  std::filesystem::path jsonlPath_, csvPath_;
  int jsonl_ = -1, csv_ = -1;
};

/// The rows of a summary.jsonl by scan path (the last row of a path wins).
/// A missing file gives no rows; a line that is not a JSON object (a torn
/// last line) is skipped.
/// @throw IoError when the file exists but cannot be read.
std::map<std::string, nlohmann::json> readSummaryRows(const std::filesystem::path& jsonl);

}  // namespace csgvox
