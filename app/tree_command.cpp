#include "app/tree_command.h"

#include <filesystem>

#include "io/file_util.h"
#include "io/tree_json.h"

namespace csgvox::app {

TreeCommandInput readTreeCommand(CommonOptions& common, const std::string& tree,
                                 const std::string& output) {
  common.subject = tree;
  TreeCommandInput in{readTreeJson(std::filesystem::path(tree)), lowerExtension(output)};
  requireNotInput(output, tree);
  return in;
}

}  // namespace csgvox::app
