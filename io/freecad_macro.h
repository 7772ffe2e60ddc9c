#pragma once
/// tree.FCMacro: a FreeCAD Python macro (plain text, written without
/// FreeCAD) that builds the designed tree (design/designed_tree.h) as a
/// parametric document: a Spreadsheet named `Parameters` holds the same
/// parameters as tree.scad (aliases of column B), and every Part feature
/// (Box, Cylinder, Cone, Sphere, Torus; Cut, MultiFuse, MultiCommon) takes
/// its dimensions and placement from it by expressions. A pattern's members
/// are copies bound to the pattern's parameters (its count fixes how many
/// copies there are). The solid is the Part::Compound `part`, placed by the
/// part's frame. Editing a cell and recomputing moves every use of it.

#include <filesystem>
#include <iosfwd>

#include "design/designed_tree.h"

namespace csgvox {

/// Options of the FreeCAD macro.
struct FreecadMacroOptions {
  double overcut = 1e-6;        ///< a removing primitive's faces move out by this, fraction of the
                                ///< part's diagonal (as tree.scad's)
  double halfSpaceScale = 2.0;  ///< size of half-space boxes, multiple of the part's diagonal
};

/// Writes the macro. @throw std::invalid_argument for an empty tree.
void writeFreecadMacro(std::ostream& out, const DesignedTree& design,
                       const FreecadMacroOptions& options = {});
/// Writes it to `path` atomically. @throw IoError, std::invalid_argument.
void writeFreecadMacro(const std::filesystem::path& path, const DesignedTree& design,
                       const FreecadMacroOptions& options = {});

}  // namespace csgvox
