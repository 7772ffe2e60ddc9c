#pragma once
/// The scans of `csgvox batch`: its INPUT arguments (scan files, folders,
/// text files listing paths) expanded into one entry per scan, each with the
/// folder its outputs go to.

#include <filesystem>
#include <span>
#include <string>
#include <vector>

namespace csgvox::app {

/// One scan of a batch.
struct BatchScan {
  std::filesystem::path file;    ///< the scan file to read
  std::string label;             ///< the scan's path as given or found: the summary's `path`
  std::filesystem::path output;  ///< folder of its outputs, relative to the batch's output folder
};

/// Whether `path` has the extension of a scan format the reader knows, and
/// for `.txt` (also a list's extension) whether its first data line is a
/// point ("x y z" or "x y z nx ny nz", after an optional count line).
bool looksLikeScan(const std::filesystem::path& path);

/// Expands the inputs, in the order given; a folder's scans sorted by path.
///  * a scan file (looksLikeScan): itself; its outputs go to its path as
///    given without the extension (root and leading `..` dropped);
///  * a folder: every scan file under it, recursively, skipping hidden
///    entries, `outDir` and folders holding a job's report.json; outputs go
///    to the path under the folder without the extension;
///  * any other file: a list, one path per line (blank lines and `#`
///    comments skipped), relative to the list's folder, each expanded as an
///    input.
/// A file reached twice is kept once.
/// @throw IoError "<input>: no such file or folder" for a missing input, when
///        a list cannot be read, or when two scans would share an output
///        folder (naming both).
std::vector<BatchScan> collectScans(std::span<const std::string> inputs,
                                    const std::filesystem::path& outDir);

}  // namespace csgvox::app
