#pragma once
/// Patterns among equal primitives: bolt circles (n >= 3 copies at equal
/// angles about an axis parallel to z), lattices along the frame's axes
/// (2 × 2 and up) and rows (n >= 2 copies at equal steps along a line; a
/// mirror pair is a row of two). Primitives are in the part's frame.

#include <span>
#include <vector>

#include "core/primitive.h"

namespace csgvox {

/// Kinds of patterns findPatterns() reports.
enum class FoundPatternKind { Circular, Lattice, Row };

/// A pattern among the primitives given to findPatterns().
struct FoundPattern {
  FoundPatternKind kind = FoundPatternKind::Row;  ///< how the members repeat
  std::vector<int> members;    ///< indices into the input; member i (Lattice: i + count·j)
  Vec3 center = Vec3::Zero();  ///< Circular: a point of the axis (z of the members)
  double radius = 0.0;         ///< Circular: distance of the members from the axis
  double phase = 0.0;          ///< Circular: angle of member 0 from x, degrees in [0, 360/n)
  Vec3 step = Vec3::Zero();    ///< Row, Lattice: offset of member i+1 from member i
  Vec3 step2 = Vec3::Zero();   ///< Lattice: offset between rows
  int count = 0;               ///< members (Lattice: along step)
  int count2 = 1;              ///< Lattice: rows
};

/// Options of findPatterns().
struct PatternOptions {
  double tolerance = 1e-3;  ///< sizes, positions and steps this close are equal, scan units
};

/// One primitive as findPatterns() sees it.
struct PatternCandidate {
  Primitive primitive;       ///< in frame coordinates
  bool looseLength = false;  ///< a cylinder whose caps nothing holds (a cutter past the part):
                             ///< its height and its position along its axis are not compared
};

/// Patterns among `primitives` (frame coordinates): groups of primitives
/// equal but for their position (and for loose lengths), whose positions form a circle about a line
/// parallel to z (cylinders, cones and tori along z, spheres), a lattice
/// along the frame's axes or a row. Each primitive is in one pattern at
/// most; groups of other layouts give none.
std::vector<FoundPattern> findPatterns(std::span<const PatternCandidate> candidates,
                                       const PatternOptions& options = {});

/// The position findPatterns() moves: a primitive's centre (a half-space has none: 0).
Vec3 primitiveCenter(const Primitive& primitive);

}  // namespace csgvox
