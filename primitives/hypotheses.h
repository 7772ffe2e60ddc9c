#pragma once
/// Bounded primitive hypotheses (Wu et al. 2018 §3 and §4.1, Fayolle & Pasko
/// 2016 §5.2): from the surfaces fitted to a scan, the candidate primitives
/// and two-primitive subtrees that the optimisation chooses from.
///
/// * Cuboids from plane patches: patches are grouped by parallel normals into
///   direction sets, the sets form a graph (an edge when orthogonal) that is
///   cut into triangles, then edges, then single nodes; each group has a frame
///   (Wu Eq. 2) and every choice of one patch or none along each of its six
///   directions (Wu Eq. 3) gives a box: the bounding box of the chosen
///   patches' points in the frame, with the chosen patch planes as exact
///   faces. A single chosen patch gives two boxes, one on each side of it,
///   as tall as the patch's longest side. Filters: orientation, fit (mean
///   distance of the chosen points to the box surface at most one voxel) and
///   redundancy.
/// * Bounded quadrics (cylinder, cone frustum, sphere, torus) from their
///   patches; "additional" boxes: the minimal oriented bounding box of each
///   quadric patch (the maximal box for a quarter cylinder); indirect
///   candidates box − quadric and box ∩ quadric; Fayolle's separators (the
///   planes of those boxes, a major-radius cylinder per torus).
/// * Half-spaces for the planes that are not a face of a kept cuboid built
///   from two or more patches (chamfers, slopes, wedge-like cuts).
///
/// Beyond Wu: "tool" cuboids, built from patches that all face into the box
/// (the walls of a slot, keyway, pocket or rebate: boxes to subtract, which
/// Wu's orientation filter rejects), and a copy of a cylinder extended to the
/// end face behind a coaxial chamfer or round (a chamfered shaft end), since
/// the inliers of the cylinder stop at the chamfer. Both can be switched off.
///
/// Everything is computed in the scan's own frame; nothing depends on the
/// world axes. Scale-dependent tolerances refer to D, here the diagonal of
/// the scan's minimal oriented bounding box (not the axis-aligned one), so a
/// rotated scan gives the same candidates, rotated.

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "core/csg_tree.h"
#include "core/point_cloud.h"
#include "core/surface.h"

namespace csgvox {

/// Where a candidate comes from.
enum class CandidateOrigin {
  Cuboid,      ///< a box built from plane patches (Wu §3.1)
  Quadric,     ///< a bounded cylinder, cone, sphere or torus from its patch (Wu §3.2)
  Plane,       ///< the half-space below a plane patch that no kept cuboid uses
  Additional,  ///< the bounding box of a quadric patch (Wu §3.2, "additional primitive")
  Indirect,    ///< an additional box minus, or intersected with, its quadric (Wu §4.1)
  Separator,   ///< Fayolle §5.2: a plane of an additional box, or a torus' major-radius cylinder
};

/// Number of CandidateOrigin values.
inline constexpr std::size_t kCandidateOriginCount = 6;

/// Lower-case name of an origin: "cuboid", "quadric", "plane", "additional",
/// "indirect", "separator".
std::string_view candidateOriginName(CandidateOrigin origin);

/// One hypothesis: a primitive or a two-primitive subtree.
struct Candidate {
  /// A single primitive leaf; for indirect candidates difference(a, q) or
  /// intersection(a, q) of an additional box a and its quadric q.
  CsgTree tree;
  CandidateOrigin origin = CandidateOrigin::Cuboid;
  /// Indices (into the surfaces passed in) of the surfaces it was built from,
  /// ascending.
  std::vector<int> surfaces;
  /// Number of scan points (inliers of those surfaces) explaining it.
  double support = 0.0;
  /// Cuboids only: true when the chosen patches face into the box, so the
  /// material lies outside it (a slot, pocket, keyway or rebate: a tool to
  /// subtract); false for an ordinary solid box.
  bool tool = false;
};

/// Options of generateHypotheses. D is the diagonal of the scan's minimal
/// oriented bounding box. Tool cuboids are boxes whose chosen patches all
/// face inwards (subtracted slots, pockets, rebates); without them only
/// Wu's solid boxes (and the two one-patch boxes) are built. The cap on the
/// candidates removes the worst-supported cuboids first, then the others by
/// support. The cap extension adds a copy of a cylinder that reaches a
/// perpendicular plane patch past its end across a coaxial chamfer or round.
/// A convex cylinder or cone patch whose inliers leave an empty band across
/// the whole circumference (a groove in a boss, a neck between two shoulders
/// of the same radius) also gives one bounded primitive per band, its ends
/// snapped onto the fitted planes there; the whole patch's primitive stays.
struct HypothesisOptions {
  double voxelSize = 0.0;                  ///< fit threshold, scan units; 0: OBB longest side / 64
  double parallelTolerance = 2.0;          ///< degrees; normals and axes this close are parallel
  double orthogonalTolerance = 2.0;        ///< degrees from 90 for an edge between direction sets
  double duplicateTolerance = 0.005;       ///< fraction of D; closer lengths are the same
  std::size_t maxCandidates = 600;         ///< cap on the candidates returned; 0: none
  std::size_t maxPatchesPerDirection = 8;  ///< best-supported patches per group direction
  std::size_t maxCuboidHypotheses = 200000;  ///< boxes built per call before stopping
  std::size_t fitSamples = 256;              ///< points per patch for the fit filter (even subset)
  bool toolCuboids = true;                   ///< also build inward-facing (tool) cuboids
  double quarterTolerance = 15.0;  ///< degrees; a cylinder patch of 90 +- this is a quarter
  bool extendToCaps = true;        ///< also cylinders extended to a cap past a chamfer
  bool snapToPlanes =
      true;  ///< cylinder and cone ends onto the fitted planes that cap or cross them
  bool extendOpenEnds =
      true;                ///< also cylinders run out to the scan's extent past ends on no plane
  bool axialBands = true;  ///< also one cylinder or frustum per band of a convex patch that an
                           ///< empty gap across its whole circumference splits (a groove, a neck)
  std::uint32_t seed = 1;  ///< seed of CGAL's bounding-box search
};

/// Candidate counts per origin (index: CandidateOrigin).
struct OriginCounts {
  std::array<std::size_t, kCandidateOriginCount> count{};

  std::size_t& operator[](CandidateOrigin o) { return count[static_cast<std::size_t>(o)]; }
  std::size_t operator[](CandidateOrigin o) const { return count[static_cast<std::size_t>(o)]; }
  /// Sum over all origins.
  std::size_t total() const;
};

/// What the cuboid enumeration did. Every hypothesis considered ends in
/// exactly one of the rejected counters or in `kept`, so
/// considered = rejectedOrientation + rejectedDegenerate + rejectedFit +
/// rejectedRedundant + kept. `eq3Count` is Wu's Eq. 3, prod(n_i + 1) + tn,
/// summed over the groups with every patch (before the per-direction cap,
/// the empty selection included); `considered` counts the hypotheses built
/// or pruned by filter 1 after that cap (the empty selection excluded).
/// Filter 1 rejects a selection with a pair of patches that face neither
/// both outwards nor (tool cuboids) both inwards; filter 2 a box whose chosen
/// points lie farther than one voxel from its surface on average; filter 3
/// the same box as a kept one whose patch set contains, or is contained in,
/// its own.
struct CuboidStats {
  std::size_t planes = 0;               ///< plane patches used
  std::size_t directionSets = 0;        ///< sets of parallel patches (graph nodes)
  std::size_t triangleGroups = 0;       ///< groups of three mutually orthogonal sets
  std::size_t edgeGroups = 0;           ///< groups of two orthogonal sets
  std::size_t singleGroups = 0;         ///< groups of one set
  std::size_t eq3Count = 0;             ///< Wu Eq. 3 over all groups
  std::size_t considered = 0;           ///< hypotheses built or pruned
  std::size_t rejectedOrientation = 0;  ///< filter 1
  std::size_t rejectedDegenerate = 0;   ///< the chosen planes leave no volume
  std::size_t rejectedFit = 0;          ///< filter 2
  std::size_t rejectedRedundant = 0;    ///< filter 3
  std::size_t kept = 0;                 ///< boxes that passed every filter
  std::size_t keptTool = 0;             ///< of which tool boxes (material outside)
  bool patchesCapped = false;           ///< a direction had more than maxPatchesPerDirection
  bool enumerationCapped = false;       ///< maxCuboidHypotheses stopped the enumeration
};

/// Statistics of one generateHypotheses call.
struct HypothesisStats {
  CuboidStats cuboids;                ///< the cuboid enumeration
  OriginCounts generated;             ///< candidates produced, before duplicate removal
  OriginCounts afterDuplicates;       ///< after duplicate removal
  OriginCounts returned;              ///< after the maxCandidates cap: what the set holds
  std::size_t duplicatesRemoved = 0;  ///< candidates dropped as duplicates
  std::size_t ownBoundsDropped = 0;   ///< additional boxes equal to their quadric's own box
  std::size_t quarterCylinders = 0;   ///< cylinder patches given a maximal box
  std::size_t extendedCylinders = 0;  ///< cylinders extended to a cap plane or past an open end
  std::size_t axialBands = 0;         ///< bands of split cylinder and cone patches
  std::size_t skippedSurfaces = 0;    ///< too few inliers or invalid parameters
  bool capped = false;                ///< maxCandidates removed candidates
  double voxelSize = 0.0;             ///< fit threshold used, scan units
  double diagonal = 0.0;              ///< D (oriented bounding-box diagonal), scan units
};

/// The candidates of a scan, with statistics.
struct HypothesisSet {
  /// Ordered by origin (in CandidateOrigin order), then by decreasing support.
  std::vector<Candidate> candidates;
  HypothesisStats stats;
};

/// Builds the bounded primitive hypotheses of a scan from its fitted
/// surfaces (see the file comment). Deterministic for a given seed. Surfaces
/// with fewer than 4 inliers are skipped. An empty surface list gives an
/// empty set.
/// @throw std::invalid_argument if an inlier index is outside the scan or an
///        option is out of range (negative sizes, tolerances outside [0, 45)
///        degrees).
HypothesisSet generateHypotheses(const PointCloud& scan, std::span<const Surface> surfaces,
                                 const HypothesisOptions& options = {});

}  // namespace csgvox
