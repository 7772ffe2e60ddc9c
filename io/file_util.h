#pragma once
/// File helpers shared by the readers and writers.

#include <filesystem>
#include <functional>
#include <iosfwd>
#include <string>

namespace csgvox {

/// Checks that `path` names an existing, readable regular file.
/// Pipes, sockets and devices are refused without being opened, so a FIFO
/// with no writer cannot block the caller.
/// @throw IoError "<path>: no such file" / "is a directory" / "is not a
///        regular file" / "cannot be opened for reading".
void requireReadableFile(const std::filesystem::path& path);

/// Writes a file atomically: `write` fills a temporary file next to `path`,
/// which replaces `path` only when `write` returns and the stream is good.
/// On any failure the temporary file is removed and `path` is left untouched.
/// @throw IoError when the file cannot be created or written; rethrows what
///        `write` throws.
void writeFileAtomically(const std::filesystem::path& path,
                         const std::function<void(std::ostream&)>& write, bool binary = false);

/// Refuses to write `output` when it is the same file as `input`.
/// @throw IoError "<output>: is the input file; refusing to overwrite it".
void requireNotInput(const std::filesystem::path& output, const std::filesystem::path& input);

/// Lower-case extension of path without the dot ("ply", "xyz", ...).
std::string lowerExtension(const std::filesystem::path& path);

}  // namespace csgvox
