#pragma once
/// tree.scad: the tree as an OpenSCAD program. Each primitive is a named
/// module on its own line (the lines a designer edits), followed by the CSG
/// expression over those modules. Half-spaces and complements become large
/// boxes clipped to the part. A primitive that removes material (under an
/// odd number of differences' cutters and complements) is written grown by
/// `overcut`: OpenSCAD's booleans are exact, so a hole whose end lies on the
/// face it goes through (as the fitted tree places it, to the last bits)
/// would otherwise leave a film of that face across it or not, as the
/// rounding falls.

#include <filesystem>
#include <iosfwd>

#include "core/csg_tree.h"

namespace csgvox {

/// Options of the OpenSCAD export.
struct ScadOptions {
  int facets = 64;              ///< $fn: segments of a full circle for curved primitives
  double halfSpaceScale = 2.0;  ///< size of half-space boxes, multiple of the part's diagonal
  double overcut = 1e-6;        ///< a removing primitive's faces move out by this, fraction of the
                                ///< part's diagonal (0: written as they are)
};

/// Writes the OpenSCAD program. @throw std::invalid_argument for an empty tree
/// or one whose bounded primitives give no extent for the half-space boxes.
void writeScad(std::ostream& out, const CsgTree& tree, const ScadOptions& options = {});
/// Writes tree.scad atomically. @throw IoError, std::invalid_argument.
void writeScad(const std::filesystem::path& path, const CsgTree& tree,
               const ScadOptions& options = {});

}  // namespace csgvox
