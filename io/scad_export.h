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
///
/// Curved primitives are written with a segment count ($fn) each, chosen
/// from their radius so that their facets stay within a tolerance of the
/// true surface: OpenSCAD's render time grows fast with facets (a torus has
/// the product of its sweep's and its tube's), and one $fn for every curve
/// made a turned part with 11 tori render for minutes. The file starts with
/// a `detail` variable that scales every count, for a finer render.

#include <filesystem>
#include <iosfwd>
#include <string>

#include "core/csg_tree.h"

namespace csgvox {

/// Options of the OpenSCAD export.
struct ScadOptions {
  double chordTolerance = 2e-4;    ///< largest distance of a curve's facets from it, fraction of
                                   ///< the part's diagonal
  double surfaceCoarsening = 2.5;  ///< spheres' and tori's tolerance, multiple of chordTolerance
                                   ///< (their facets are the square of a circle's)
  int minSegments = 12;            ///< fewest segments of a full circle
  int minTubeSegments = 8;         ///< fewest segments of a torus's tube
  int maxSegments = 96;            ///< most segments of a full circle
  int facets = 0;  ///< when > 0: every curve's segments, whatever its size (else chosen as above)
  double halfSpaceScale = 2.0;  ///< size of half-space boxes, multiple of the part's diagonal
  double overcut = 1e-6;        ///< a removing primitive's faces move out by this, fraction of the
                                ///< part's diagonal (0: written as they are)
};

/// `$fn = segments(N)` for a curve of radius r: the fewest of 8, 12, 16, 24,
/// 32, 48, 64, 96, ... sides whose chords stay within `tolerance` (scan units)
/// of the circle, at least max(minimum, options.minSegments) and at most
/// options.maxSegments; options.facets when it is > 0. `segments` is the
/// program's function that scales the count by its `detail` variable.
std::string scadSegments(double r, double tolerance, const ScadOptions& options, int minimum = 0);

/// Writes the OpenSCAD program. @throw std::invalid_argument for an empty tree
/// or one whose bounded primitives give no extent for the half-space boxes.
void writeScad(std::ostream& out, const CsgTree& tree, const ScadOptions& options = {});
/// Writes tree.scad atomically. @throw IoError, std::invalid_argument.
void writeScad(const std::filesystem::path& path, const CsgTree& tree,
               const ScadOptions& options = {});

}  // namespace csgvox
