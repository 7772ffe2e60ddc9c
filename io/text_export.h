#pragma once
/// tree.txt: the tree as one expression followed by one line per primitive,
/// e.g.
///   difference(union(base, boss), hole1)
///   base = box(center=[0, 0, 5], half_size=[40, 30, 5], axes=identity)

#include <filesystem>
#include <iosfwd>
#include <string>

#include "core/csg_tree.h"
#include "design/designed_tree.h"

namespace csgvox {

/// The expression alone, e.g. "difference(union(base, boss), hole1)".
std::string treeExpression(const CsgTree& tree);
/// Writes the expression and the primitive definitions.
void writeTreeText(std::ostream& out, const CsgTree& tree);
/// Writes tree.txt atomically. @throw IoError.
void writeTreeText(const std::filesystem::path& path, const CsgTree& tree);

/// The designed tree's text: the expression and primitives of its world
/// tree, then one line per pattern naming its members, e.g.
///   bolt_circle = circular(hole_1, ..., hole_6; count = 6, radius = 38, phase = 30)
void writeTreeText(std::ostream& out, const DesignedTree& design);
/// Writes it atomically. @throw IoError.
void writeTreeText(const std::filesystem::path& path, const DesignedTree& design);

}  // namespace csgvox
