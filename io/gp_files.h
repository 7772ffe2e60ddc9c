#pragma once
/// The files of the published genetic-programming baseline (Fayolle & Pasko
/// 2016): its primitive list (`.fit`) and its tree (an expression such as
/// `intersection[plane0,negation[cylinder7]]`), read into a csgvox tree.
/// Formats (README.md, "Importing the GP baseline's trees"):
/// - `.fit`: one primitive per line, `TYPE p1 p2 …`, the primitive's index
///   is its line number counted from 0; every primitive is an unbounded solid
///   whose baseline value f is >= 0 inside:
///   `plane nx ny nz d` (f = d − n·x), `sphere cx cy cz r`,
///   `cylinder ax ay az px py pz r` (axis a through p),
///   `cone ax ay az cx cy cz angle` (apex c, axis a from the apex into the
///   cone, half-angle in radians), `torus nx ny nz cx cy cz r_minor r_major`
///   (axis n through centre c).
/// - expression: `union[A,B]` (max), `intersection[A,B]` (min),
///   `subtraction[A,B]` (min(A, −B)), `negation[A]` (−A), leaves TYPE + index
///   (`plane0`, `cylinder7`); blanks are allowed between the parts.
/// The imported leaves carry exact signed distances rather than the
/// baseline's f: the same solids, but a plane's f is a distance only when
/// |n| = 1, and behind a cone's apex the baseline's f is minus the distance to
/// the generator's line, not to the apex.

#include <cstddef>
#include <filesystem>
#include <iosfwd>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "core/csg_tree.h"
#include "core/geometry.h"
#include "core/surface.h"

namespace csgvox {

/// One primitive of a `.fit` file.
struct GpPrimitive {
  std::string name;    ///< the baseline's leaf name: TYPE + index, e.g. "plane0", "cylinder7"
  SurfaceShape shape;  ///< the unbounded surface (unit normal/axis); its solid is the inside
};

/// Nesting depth of an expression beyond which it is refused, so that the
/// imported tree stays within tree.json's depth limit.
inline constexpr std::size_t kMaxGpNesting = 900;

/// Reads a `.fit` primitive file. A plane `n d` becomes PlaneSurface{n/|n|,
/// d/|n|} (the solid {n·x <= d}); axes are normalised. `source` names the input
/// in error messages.
/// @throw ParseError "<source>: line L (index I): <problem>" for an unknown
///        type, a wrong count of numbers, a word that is not a finite number,
///        a zero normal or axis, a radius <= 0, a cone half-angle outside
///        (0, pi/2), a torus whose minor radius exceeds its major radius, an
///        empty line before the last primitive (indices are line numbers); and
///        "<source>: no primitives" for a file without any.
std::vector<GpPrimitive> readGpPrimitives(std::istream& in, const std::string& source = "<stream>");
/// Reads a `.fit` primitive file.
/// @throw IoError when the file cannot be read; ParseError as the stream overload.
std::vector<GpPrimitive> readGpPrimitives(const std::filesystem::path& path);

/// Reads a baseline expression over `primitives` into a tree whose leaves are
/// clippedSolid(primitive, box) (core/clipped_solid.h), named like the
/// baseline's leaves. Operations map to CsgTree::unite, intersect, subtract
/// and complement; with min/max operations the tree's value is the baseline's
/// semantics applied to the leaves' distances. The tree is unbounded when its
/// solid is (a half-space, a complement): see importGp for a bounded one.
/// @throw ParseError "<source>: line L, column C: <problem>" for an unknown
///        operation or primitive type, a leaf index past the primitives or
///        naming another type than its line, a wrong number of operands,
///        a missing or unbalanced bracket, text after the expression, nesting
///        deeper than kMaxGpNesting; "<source>: empty expression".
/// @throw std::invalid_argument when `box` is empty or unbounded.
CsgTree readGpExpression(std::istream& in, std::span<const GpPrimitive> primitives, const Aabb& box,
                         const std::string& source = "<stream>");
/// Reads a baseline expression file.
/// @throw IoError when the file cannot be read; otherwise as the stream overload.
CsgTree readGpExpression(const std::filesystem::path& path, std::span<const GpPrimitive> primitives,
                         const Aabb& box);

/// The clip box used when no scan is given: the box of the primitives'
/// reference points — each plane's point nearest the origin (offset·normal),
/// each cylinder's axis point grown by its radius in every direction, each
/// cone's apex, each sphere's and torus' bounds — grown on every side by
/// `margin` times its diagonal (by 1 scan unit when all those points coincide).
/// For a part whose planes are its faces (the baseline's boxes) this is the
/// part's box, grown.
/// @throw std::invalid_argument when `primitives` is empty or margin is not > 0.
Aabb gpClipBox(std::span<const GpPrimitive> primitives,
               double margin = 0.1);  // fraction of the diagonal

/// The clip box when a scan is given: its bounds grown on every side by
/// `margin` times their diagonal.
/// @throw std::invalid_argument when `scanBounds` is empty or unbounded, or has
///        a zero diagonal, or margin is not > 0.
Aabb gpScanClipBox(const Aabb& scanBounds, double margin = 0.05);  // fraction of the diagonal

/// Options of importGp.
struct GpImportOptions {
  std::optional<Aabb> box;  ///< region where the leaves are exact; default gpClipBox(primitives)
  bool clipToBox = true;    ///< intersect the tree with the box (a leaf "clip_box"): bounded
};

/// An imported baseline tree.
struct GpImport {
  std::vector<GpPrimitive> primitives;  ///< the `.fit` primitives, in file order
  Aabb box;                             ///< the clip box the leaves are exact in
  CsgTree tree;  ///< the expression's tree (intersected with the box when clipToBox)
};

/// Reads a `.fit` file and an expression file into a csgvox tree. With
/// clipToBox (the default) the tree is intersection[expression, clip_box]:
/// a bounded solid that `csgvox render` and `csgvox eval` accept, equal to the
/// baseline's solid inside the box.
/// @throw IoError when a file cannot be read; ParseError for bad content (as
///        readGpPrimitives and readGpExpression); std::invalid_argument when
///        options.box is empty, unbounded or has a zero-size side with
///        clipToBox.
GpImport importGp(const std::filesystem::path& fit, const std::filesystem::path& expression,
                  const GpImportOptions& options = {});

}  // namespace csgvox
