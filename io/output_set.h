#pragma once
/// A command's output files, which appear together or not at all.

#include <filesystem>
#include <span>
#include <string>
#include <vector>

namespace csgvox {

/// The files a command writes into one folder, staged in a hidden folder
/// and moved into place only by commit(). Until then nothing in the target
/// folder changes; a failure (an exception, or the object destroyed without
/// commit()) removes the staging folder, so a failed run leaves the folder
/// as it was. When the folder does not exist yet, the staging folder is its
/// sibling and commit() renames it in one step; otherwise the staging folder
/// is inside it and commit() renames the files one by one (renames within
/// one file system, which cannot run out of space). A killed run leaves at
/// most the hidden staging folder (`.NAME.partial-*` beside the folder or
/// `.csgvox-partial-*` inside it), never a partial set under the real names;
/// the next run into the same folder removes the staging folders of runs
/// that no longer exist.
class OutputSet {
 public:
  /// Prepares to write `names` (plain file names) into `folder`.
  /// @throw IoError when an output would replace one of `inputs` (even
  ///        through a link), when `folder` exists but is not a folder, or
  ///        when the staging folder cannot be created.
  OutputSet(std::filesystem::path folder, std::vector<std::string> names,
            std::span<const std::filesystem::path> inputs);
  OutputSet(const OutputSet&) = delete;
  OutputSet& operator=(const OutputSet&) = delete;
  /// Removes the staging folder unless commit() succeeded.
  ~OutputSet();

  /// The folder the files end up in.
  const std::filesystem::path& folder() const { return folder_; }
  /// Where to write the output `name` (one of the names given) now.
  std::filesystem::path path(const std::string& name) const;
  /// The output `name` is not written this time (an optional output, or one
  /// whose step failed): commit() neither expects it nor leaves an older
  /// file of that name in the folder beside the new ones.
  void skip(const std::string& name);
  /// Moves every staged file into the folder.
  /// @throw IoError when a file named at construction was not written or
  ///        cannot be moved.
  void commit();

 private:
  std::filesystem::path folder_;
  std::vector<std::string> names_;
  std::vector<std::string> skipped_;
  std::filesystem::path staging_;
  bool freshFolder_ = false;  ///< the folder did not exist: staging_ becomes it
  bool committed_ = false;
};

}  // namespace csgvox
