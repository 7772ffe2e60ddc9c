#pragma once
/// tree.json: the csgvox tree format (documented in README.md, "File formats").

#include <filesystem>
#include <iosfwd>
#include <nlohmann/json_fwd.hpp>
#include <string>

#include "core/csg_tree.h"

namespace csgvox {

/// Reads a tree from JSON text. `source` names the input in error messages.
/// @throw ParseError "<source>: <problem>" for malformed JSON or an invalid tree.
CsgTree readTreeJson(std::istream& in, const std::string& source = "<stream>");
/// Reads a tree from a tree.json file.
/// @throw IoError if the file cannot be read; ParseError if it is not a valid tree.
CsgTree readTreeJson(const std::filesystem::path& path);

/// Writes a tree as indented JSON; numbers round-trip exactly.
/// @throw std::invalid_argument for an empty tree.
void writeTreeJson(std::ostream& out, const CsgTree& tree);
/// The JSON text of the tree's root node alone (a primitive object or an
/// operation object, as inside "root"), for embedding in other documents.
/// @throw std::invalid_argument for an empty tree.
std::string treeNodeJson(const CsgTree& tree);
/// The tree's root node as a JSON value, for embedding in other documents.
/// @throw std::invalid_argument for an empty tree.
nlohmann::ordered_json treeNodeToJson(const CsgTree& tree);

/// Writes a tree.json file atomically. @throw IoError.
void writeTreeJson(const std::filesystem::path& path, const CsgTree& tree);

}  // namespace csgvox
