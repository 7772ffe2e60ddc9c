#pragma once
/// Stable, unique, identifier-safe names for the leaves of a tree, shared by
/// the text and OpenSCAD exports.

#include <string>
#include <unordered_map>

#include "core/csg_tree.h"

namespace csgvox {

/// Maps each leaf node to a unique identifier: its own name when it is a valid
/// identifier (made unique with a suffix when repeated or when it is one of
/// OpenSCAD's keywords or built-in names, e.g. "difference" -> "difference_1"),
/// else "<type><n>".
std::unordered_map<const Node*, std::string> leafNames(const CsgTree& tree);

/// True for OpenSCAD's keywords, constants and built-in module and function
/// names ("module", "difference", "cube", "for", ...).
bool isOpenScadReserved(const std::string& name);

/// Shortest decimal text that reads back to exactly `value`.
std::string formatNumber(double value);
/// "[x, y, z]" with formatNumber for each coordinate.
std::string formatVector(const Vec3& v);

}  // namespace csgvox
