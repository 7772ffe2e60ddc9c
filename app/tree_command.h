#pragma once
/// What the commands that read one tree and write one file (`sample`,
/// `render`) do first.

#include <string>

#include "app/commands.h"
#include "core/csg_tree.h"

namespace csgvox::app {

/// A tree read for a command, and its output file's lower-case extension.
struct TreeCommandInput {
  CsgTree tree;     ///< the tree read
  std::string ext;  ///< extension of the output, lower case, without the dot
};

/// Names the tree as the command's subject (`common.subject`), reads it and
/// checks that the output does not overwrite it.
/// @throw IoError when the tree cannot be read or the output is the tree itself.
TreeCommandInput readTreeCommand(CommonOptions& common, const std::string& tree,
                                 const std::string& output);

}  // namespace csgvox::app
