#pragma once
/// The designed tree: the fitted tree as a designer would have drawn it.
/// Every primitive is expressed in the part's frame (design/part_frame.h)
/// through named parameters; values the fit shares (equal radii, coaxial
/// axes, coplanar faces, the members of a pattern) are one parameter; each
/// parameter is snapped to the simplest value within its uncertainty
/// (design/value_ladder.h) when the tree still fits:
///
///   uncertainty  u = k·σ/√n: σ the scan's noise about the tree, n the
///                points on the faces the value places (infinite when no
///                point holds it, the tree's own tolerance without points;
///                points within 1 % of D that the noise band leaves out
///                hold it too, as tightly as they agree, and where they
///                all lie off the face the value is snapped from there);
///   kept         a value no point holds: when it changes no IoU grid
///                point's side; the values the points hold: all together
///                when that costs the tree at most 1 − minIou of voxel IoU;
///                else per parameter (a group of values the fit shares):
///                when snapping it alone costs at most that, or, for a
///                length with u at most a quarter of its rung's step, what
///                moving it by u costs (against the fitted tree;
///                stratified points, one per cell), and the points near
///                the change do not move away by more than σ/√m on
///                average — then for the ones kept, together, while the
///                points' mean distance to the tree grows by at most
///                fitnessSlack·σ (the costliest dropped until it does).
///
/// Caps of adding primitives that face each other across a sliver (at most
/// 0.125 % of D) become one parameter. Patterns (design/pattern_detection.h)
/// are written as one member, a count and a step. The fitted tree's structure is kept: every leaf
/// of it has a designed leaf.

#include <array>
#include <span>
#include <string>
#include <unordered_map>
#include <vector>

#include "core/csg_tree.h"
#include "design/expression.h"
#include "design/part_frame.h"
#include "design/value_ladder.h"

namespace csgvox {

/// What a parameter measures.
enum class ParameterKind {
  Length,  ///< a position along a frame axis, a size or a radius (scan units)
  Angle,   ///< degrees
  Count    ///< members of a pattern
};

/// A named number of the designed tree.
struct DesignParameter {
  std::string name;                            ///< identifier, e.g. "bolt_circle_r"
  ParameterKind kind = ParameterKind::Length;  ///< what it measures
  double fitted = 0.0;                         ///< the fitted tree's value (mean over its uses)
  double value = 0.0;        ///< the designed value (the fitted one when not snapped)
  double uncertainty = 0.0;  ///< half-width it was snapped within (inf: no point holds it)
  bool snapped = false;      ///< value is a designed (ladder) value
  std::string usedBy;        ///< what uses it, e.g. "6 holes"
};

/// How a designed leaf is written.
enum class LeafForm {
  AlignedBox,        ///< a box along the frame's axes: lo and hi faces per axis
  TurnedBox,         ///< a box with one axis along frame z, turned by `angle` about it
  Axial,             ///< a cylinder, cone or torus along frame axis `axis`
  Sphere,            ///< centre and radius
  AlignedHalfSpace,  ///< a plane across frame axis `axis`: keeps x[axis] <= hi (or >= lo)
  TiltedHalfSpace,   ///< an oblique plane: normal tilted by `angle` from z, turned by `angle2`
                     ///< about z; keeps normal·x <= radius (its offset)
  Free               ///< oblique to the frame: written as fitted (frame coordinates)
};

/// One leaf of the designed tree. Which expressions are used depends on the
/// form: AlignedBox: lo, hi per axis; Axial: at[] of the two other axes
/// (the axis line), lo[axis] and hi[axis] (caps; a torus's centre is
/// at[axis]), radius (cone: at lo) and radius2 (cone: at hi; torus: minor);
/// Sphere: at[], radius; AlignedHalfSpace: hi[axis] (normal +axis) or
/// lo[axis] (flipped); TurnedBox: at[0], at[1] (centre), lo[2], hi[2]
/// (faces), radius and radius2 (its sizes along its own x and y), angle.
struct DesignedLeaf {
  const Node* node = nullptr;               ///< the leaf of the fitted tree
  std::string name;                         ///< unique identifier from its role, e.g. "hole_2"
  std::string role;                         ///< "hole", "plate", ... (design/role_names.h)
  bool cuts = false;                        ///< used to remove material
  bool adds = false;                        ///< used to add material
  LeafForm form = LeafForm::Free;           ///< how it is written
  PrimitiveType type = PrimitiveType::Box;  ///< its primitive type
  int axis = 2;                             ///< Axial and AlignedHalfSpace: the frame axis
  bool flipped = false;                     ///< AlignedHalfSpace: outward normal is −axis
  std::array<Expression, 3> lo;             ///< low faces / caps, per frame axis
  std::array<Expression, 3> hi;             ///< high faces / caps, per frame axis
  std::array<Expression, 3> at;             ///< centre coordinates, per frame axis
  Expression radius;                        ///< radius (cone: at lo; torus: major)
  Expression radius2;                       ///< cone: radius at hi; torus: minor radius
  Expression angle;   ///< TurnedBox: its turn about z from the frame's x; TiltedHalfSpace:
                      ///< its normal's angle from z (degrees)
  Expression angle2;  ///< TiltedHalfSpace: its normal's turn about z from x (degrees)
  Primitive local;    ///< Free: the primitive in frame coordinates
  int pattern = -1;   ///< index of its pattern, or -1
  int member = 0;     ///< its index in the pattern (0: the one written)
};

/// How a pattern repeats its member.
enum class PatternKind {
  Circular,  ///< count copies at equal angles about the frame's z through (centerX, centerY)
  Row,       ///< count copies at equal steps
  Lattice    ///< count × count2 copies on a grid of two steps
};

/// A pattern: one member, a count and a step.
struct DesignedPattern {
  PatternKind kind = PatternKind::Row;  ///< how it repeats
  std::string name;                     ///< e.g. "bolt_circle"
  std::vector<int> members;             ///< indices of designed leaves; member i at members[i]
  int count = -1;                       ///< parameter: number of copies (Lattice: along step)
  int count2 = -1;                      ///< Lattice: parameter, copies along step2
  Expression centerX, centerY;          ///< Circular: the axis line
  Expression radius;                    ///< Circular: distance of the members from it
  Expression phase;                     ///< Circular: angle of member 0, degrees from x
  std::array<Expression, 3> step;       ///< Row, Lattice: offset between copies
  std::array<Expression, 3> step2;      ///< Lattice: offset between rows
  /// "circular", "row" or "lattice".
  std::string kindName() const;
};

/// Options of designTree().
struct DesignOptions {
  double confidence = 3.0;         ///< k: a value's uncertainty is k·σ/√n
  double treeUncertainty = 1e-3;   ///< without points: every value's uncertainty, fraction of
                                   ///< the part's diagonal
  double groupTolerance = 1e-6;    ///< values of a kind this close are one parameter, fraction of
                                   ///< the part's diagonal
  double patternTolerance = 1e-3;  ///< members and steps this close count as equal, fraction of
                                   ///< the part's diagonal (and its angle in radians)
  double alignTolerance = 1e-4;    ///< a direction this close to a frame axis is taken as it,
                                   ///< radians
  double minIou = 0.999;  ///< least voxel IoU against the fitted tree after one parameter's snap
  double fitnessSlack = 1.0;  ///< the points' mean distance may grow by this many noise
                              ///< deviations
  double minNoise = 1e-4;     ///< least noise deviation that test allows, fraction of the
                              ///< part's diagonal (no scanner measures finer; a sampled
                              ///< mesh's points lie on the surface to the last bits)
  int iouResolution = 48;     ///< IoU grid cells along the longest side of the part
  int maxPoints = 20000;      ///< scan points used at most (every k-th of a larger scan)
  bool snap = true;           ///< false: parameters keep their fitted values
  FrameOptions frame;         ///< how the frame is chosen
};

/// The designed form of a fitted tree.
struct DesignedTree {
  CsgTree fitted;                             ///< the fitted tree (world coordinates)
  PartFrame frame;                            ///< frame to world
  UnitSystem units = UnitSystem::Millimetre;  ///< the grid values were snapped on
  std::vector<DesignParameter> parameters;    ///< in order of first use
  std::vector<DesignedLeaf> leaves;           ///< each leaf of `fitted` once, in tree order
  std::vector<DesignedPattern> patterns;      ///< patterns found
  double noise = 0.0;                         ///< σ of the points about the fitted tree (0: none)
  double iouToFitted = 1.0;                   ///< voxel IoU of the designed tree against the fitted
  double meanDistanceFitted = 0.0;    ///< points' mean |f| to the fitted tree (0: no points)
  double meanDistanceDesigned = 0.0;  ///< points' mean |f| to the designed tree
  /// Along each frame axis, the mean of (fitted − snapped) over the snapped
  /// positions the points hold (weights 1/u²): how far the origin, itself
  /// a fitted face or axis, lies from where the snapped values put it (0
  /// where that is below a tenth of the finest such uncertainty).
  Vec3 datumOffset = Vec3::Zero();

  /// The designed tree in world coordinates (the fitted tree's structure,
  /// every leaf realised from the parameters' values and named as its
  /// designed leaf).
  CsgTree tree() const;
  /// The designed tree in frame coordinates.
  CsgTree localTree() const;
  /// The designed leaf of a leaf node of `fitted`, or -1.
  int leafIndex(const Node* node) const;
  /// The frame-coordinate primitive of designed leaf `index` (a pattern's
  /// member `member` of it).
  Primitive localPrimitive(int index) const;
  /// Number of snapped parameters.
  int snappedCount() const;
};

/// The designed form of `fitted`. `points` (world coordinates, may be
/// empty) give each value's uncertainty and check each snap.
/// @throw std::invalid_argument for an empty tree.
DesignedTree designTree(const CsgTree& fitted, std::span<const Vec3> points = {},
                        const DesignOptions& options = {});
/// The same in a given frame (e.g. the one tree.json records).
DesignedTree designTree(const CsgTree& fitted, const PartFrame& frame, std::span<const Vec3> points,
                        const DesignOptions& options = {});

}  // namespace csgvox
