#pragma once
/// tree.scad for editing: the designed tree (design/designed_tree.h) as an
/// OpenSCAD program. A parameter block at the top (each designed value with
/// its fitted value and uncertainty in a comment), one module per primitive
/// named by its role, patterns as `for` loops, and the placement of the
/// part's frame around the whole. Every number of the body is a parameter or
/// an expression of parameters; changing one moves every use of it.
/// Primitives that cut are called grown by `overcut` (see io/scad_export.h).

#include <filesystem>
#include <iosfwd>

#include "design/designed_tree.h"
#include "io/scad_export.h"

namespace csgvox {

/// Writes the designed tree as an OpenSCAD program.
/// @throw std::invalid_argument for an empty tree.
void writeDesignedScad(std::ostream& out, const DesignedTree& design,
                       const ScadOptions& options = {});
/// Writes it to `path` atomically. @throw IoError, std::invalid_argument.
void writeDesignedScad(const std::filesystem::path& path, const DesignedTree& design,
                       const ScadOptions& options = {});

/// The numbers written in the body of a designed tree.scad (after its
/// parameter block), and how many of them are parameters or expressions:
/// a number in `segments(...)` or one of 0, 1, 2 and 360 (structure, not
/// dimensions) does not count. For tests and reports.
struct ScadLiteralCount {
  int numbers = 0;     ///< dimension values in the body
  int parameters = 0;  ///< of them, written as parameters or expressions
};
/// Counts the body's literals of an OpenSCAD program written by csgvox
/// (either writer): numbers left as literals count against.
ScadLiteralCount countScadLiterals(const std::string& program);

}  // namespace csgvox
