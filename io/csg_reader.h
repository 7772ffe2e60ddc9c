#pragma once
/// Reads OpenSCAD's flattened CSG format back into a tree: the subset that
/// writeCsg() produces and OpenSCAD's own .csg export uses for these solids
/// (`group`, `union`, `difference`, `intersection`, `multmatrix` with a
/// rotation and a translation, `cube`, `cylinder`, `sphere`, and
/// `rotate_extrude` of one `circle` moved off the axis, i.e. a torus;
/// `render` and `color` pass their children through). Curved solids are read
/// as exact, whatever their $fn.

#include <filesystem>
#include <iosfwd>
#include <string>

#include "core/csg_tree.h"

namespace csgvox {

/// Parses CSG text; `name` is used in error messages.
/// @throw ParseError naming `name` and the line: a syntax error, an
///        unsupported statement, a missing or non-finite parameter, a
///        multmatrix that is not a rotation and a translation.
CsgTree readCsg(std::istream& in, const std::string& name = "<csg>");
/// Reads a .csg file. @throw IoError when it cannot be read; ParseError.
CsgTree readCsg(const std::filesystem::path& path);

}  // namespace csgvox
