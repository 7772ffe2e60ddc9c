#pragma once
/// tree.csg: the tree in OpenSCAD's flattened CSG format (what OpenSCAD
/// itself exports as .csg): every primitive is a `cube`, `cylinder`,
/// `sphere` or `rotate_extrude` of a `circle` placed by a `multmatrix`, and
/// the operations are `union`, `difference` and `intersection`. FreeCAD
/// opens it natively (its OpenSCAD workbench's importCSG) as a parametric
/// feature tree, with no OpenSCAD installed: each primitive an editable Part
/// feature, each operation a boolean. Curved primitives are exact ($fn = 0).
/// Half-spaces and complements become cubes much larger than the part that
/// clip it as they do (as in tree.scad). As in tree.scad, a primitive that
/// removes material is written grown by `overcut` (core/export_cutters.h):
/// FreeCAD's cut of coplanar faces fails silently (a bore flush with the
/// faces it goes through was cut through one of its solids only).

#include <filesystem>
#include <iosfwd>

#include "core/csg_tree.h"

namespace csgvox {

/// Options of the CSG export.
struct CsgOptions {
  double halfSpaceScale = 2.0;  ///< edge of the half-space cubes, multiple of the part's diagonal
  double overcut = 1e-6;        ///< a removing primitive's faces move out by this, fraction of the
                                ///< part's diagonal (0: written as they are)
};

/// Writes the tree as OpenSCAD CSG; each primitive carries its name in a
/// comment. @throw std::invalid_argument for an empty tree or one whose
/// bounded primitives give no extent for the half-space cubes.
void writeCsg(std::ostream& out, const CsgTree& tree, const CsgOptions& options = {});
/// Writes tree.csg atomically. @throw IoError, std::invalid_argument.
void writeCsg(const std::filesystem::path& path, const CsgTree& tree,
              const CsgOptions& options = {});

}  // namespace csgvox
