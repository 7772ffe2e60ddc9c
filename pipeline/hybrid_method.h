#pragma once
/// The hybrid method's second half: the points judge the voxel stage's tree
/// and the genetic search repairs it where the voxels could not see.
///
/// Points the tree explains badly (farther than εd from its surface, or with
/// a normal off by more than badAngle) are grouped into regions, and so are
/// the samples of the tree's boundary no scan point is near (material or a
/// hole the voxel stage kept where the part has none, which no point can
/// call bad); the union
/// members of the tree whose bounds meet a region (with the members meeting
/// those, until none is added) are its subtree. Regions whose boxes meet
/// (regions sharing a member do) are one. Each region's subtree is searched again by the genetic
/// search, seeded with the subtree and its one-step variants (∪ or − one candidate), over the
/// subtree's primitives and the bounded candidates that fit the region's points — including those
/// the voxel stage dropped — and, where the boundary is unsupported, also seeded with the repairs
/// the voxel labels ask for there (a candidate c, c − q or c ∩ q, q one of the subtree's
/// primitives, taken away or added), with Eq. 7 on the points around it plus the voxel term there
/// (min/max field by default: SARDF gave the same trees on the bundled scans, its generations
/// about 10 times min/max's, docs/benchmarks.md). Regions are independent, so they run in
/// parallel. A refined subtree replaces the original only when the whole tree's fitness on all
/// points improves (by more than minGain·N, so noise
/// alone does not swap primitives) once the points it explains only by a zero set that bounds no
/// volume are no longer credited (the min/max field of (A − X) ∪ (A ∩ X) is zero on X's surface
/// inside A), and of the points the boundary it adds where the scan has no points would hold at the
/// scan's density (a fitness at the points cannot see such surfaces: a slab carved inside a plate,
/// thinner than a voxel); so the result is never worse than the voxel tree by that measure. Last,
/// when a subtree was replaced, redundant nodes of the whole tree are removed. Then the holes the
/// detection saw that the tree lacks are subtracted where the fitness rises and the voxel term
/// does not get worse (HybridOptions::seenHoles). When nothing was replaced or subtracted, the
/// result is the input tree itself.

#include <algorithm>
#include <cstddef>
#include <span>
#include <vector>

#include "core/csg_tree.h"
#include "core/point_cloud.h"
#include "evolve/fitness.h"
#include "evolve/genetic_search.h"
#include "primitives/hypotheses.h"
#include "voxel/voxel_grid.h"
#include "voxel/voxel_set.h"

namespace csgvox {

/// The search of a region: population 100, at most 300 generations, 40
/// without improvement, offspring normalised.
inline EvolveOptions repairSearchDefaults() {
  EvolveOptions o;
  o.population = 100;
  o.maxGenerations = 300;
  o.stallGenerations = 40;
  o.normalizeOffspring = true;
  return o;
}

/// Options of repairTree().
struct HybridOptions {
  FitnessOptions fitness = {.voxelWeight = 1.0};  ///< Eq. 7 (min/max field) + the voxel term
  EvolveOptions evolve = repairSearchDefaults();  ///< each region's search
  double badAngle = 30.0;  ///< degrees: a normal further off is badly explained
  double noise = 0.0;  ///< the scan's noise sigma (scan units): a point within 3 sigma of the tree
                       ///< is not badly explained by its distance (0: εd alone decides)
  double regionCell = 2.0;         ///< voxels: bad points in neighbouring cells of this size join
  double minRegionPoints = 0.002;  ///< regions with fewer points than this fraction of N are left
  double margin = 2.0;             ///< voxels added around a region and its subtree
  double minGain = 0.002;  ///< a replacement must raise the whole tree's fitness by this fraction
                           ///< of N at least (a smallest region's worth of points)
  std::size_t maxCandidates = 32;  ///< candidates added to a region's primitives at most
  std::size_t roughPoints = 6000;  ///< a region's generations use at most this many points until
                                   ///< its search stalls
  double supportDistance = 1.0;  ///< × εd: the tree's boundary farther than this from every point
                                 ///< is unsupported
  std::size_t supportSamples = 20000;  ///< boundary points sampled to measure the support
  bool unsupportedRegions = true;      ///< the tree's boundary no point is near makes regions too
  double supportSpacing = 1.5;  ///< × the scan's mean point spacing (√(boundary area / N)):
                                ///< boundary nearer a point than this is not unsupported enough
                                ///< to form a region (a random gap between points of a sparse
                                ///< scan is wider than εd; one this wide is rarer than 1 in 1000)
  std::size_t maxRepairs = 16;  ///< seeds of such a region that set its voxels right, at most
  std::size_t searches = 1;     ///< independent searches of each region (seeds of their own), all
                                ///< run in parallel; the one with the best fitness on the region's
                                ///< points is judged (one search finds a repair that another
                                ///< misses; the first search is the one a single search runs)
  /// Last, each bounded cylinder fitted to a detected surface that no
  /// cylinder of the tree stands for is subtracted from the whole tree (best
  /// supported first) and kept when the tree's fitness rises and its voxel
  /// term does not get worse: the holes a scan shows by their rims and a
  /// little wall, too narrow for the labels and worth less than minGain·N.
  bool seenHoles = true;
};

/// What became of a region's refined subtree.
enum class RegionVerdict {
  NotImproved,  ///< the search found nothing better on the region's points
  NoGain,       ///< the whole tree's fitness did not rise by minGain·N
  Ghost,        ///< it rose only through surfaces that bound no volume (the surface of X in
          ///< (A − X) ∪ (A ∩ X)): once those points' credit is taken away, by too little
  Unsupported,  ///< it added boundary no scan point is near (a slab carved inside a plate): once
                ///< the credit of the points that area would hold is taken away, by too little
  Replaced,     ///< the repaired subtree went into the tree
};

/// The verdict's name in reports: "not improved", "no gain", "ghost surfaces",
/// "unsupported boundary", "replaced".
const char* regionVerdictName(RegionVerdict verdict);

/// What repairTree() did in one region.
struct HybridRegion {
  std::size_t badPoints = 0;     ///< badly explained points that formed the region
  double unsupportedArea = 0.0;  ///< the tree's boundary no point is near that formed it (units²)
  std::size_t points = 0;        ///< points its search was judged on
  std::size_t members = 0;       ///< union members of the tree in its subtree
  std::size_t library = 0;       ///< primitives its search combined
  std::size_t generations = 0;   ///< generations of its kept search
  double localBefore = 0.0;      ///< the subtree's fitness on the region's points
  double localAfter = 0.0;       ///< the search's best tree's
  RegionVerdict verdict = RegionVerdict::NotImproved;  ///< why it went in or not
  /// The refined subtree went into the tree.
  bool replaced() const { return verdict == RegionVerdict::Replaced; }
  /// Which of its searches was kept (0-based): the best, the first of equals
  /// (0 before any search).
  std::size_t search() const {
    return std::size_t(std::max_element(searchFitness.begin(), searchFitness.end()) -
                       searchFitness.begin());
  }
  double unsupported = -1.0;  ///< the tree with it: boundary no point is near (< 0: not weighed)
  std::size_t primitivesBefore = 0;   ///< primitives of the subtree
  std::size_t primitivesAfter = 0;    ///< primitives of the repaired subtree
  std::vector<double> searchFitness;  ///< each search's best fitness on the region's points, in
                                      ///< search order (localAfter is the largest)
  double seconds = 0.0;               ///< wall time of its searches, summed
};

/// Result of repairTree().
struct HybridResult {
  CsgTree tree;                       ///< the repaired tree
  std::vector<HybridRegion> regions;  ///< in order of their first point
  std::size_t badPoints = 0;          ///< points the input tree explained badly
  Fitness before;                     ///< the input tree's fitness on all points
  Fitness after;                      ///< the result's
  std::size_t primitivesBefore = 0;
  std::size_t primitivesAfter = 0;
  std::size_t replaced = 0;        ///< regions whose subtree was replaced
  std::size_t holesAdded = 0;      ///< seen holes subtracted last (HybridOptions::seenHoles)
  std::size_t ghostBefore = 0;     ///< points the input tree explains only by a ghost surface
  std::size_t ghostAfter = 0;      ///< the result's
  double area = 0.0;               ///< the input tree's boundary area (scan units²)
  double unsupportedBefore = 0.0;  ///< its boundary area no scan point is near
  double unsupportedAfter = 0.0;   ///< the result's
};

/// Refines a tree on an oriented scan. `candidates` are the bounded
/// hypotheses (their leaves are the extra primitives), `grid` and `inside`
/// the voxel labels. `control`'s deadline bounds the searches, which then
/// keep their best trees; a cancel request stops them too.
/// @throw std::invalid_argument when the scan has no normals or the tree is empty.
HybridResult repairTree(const PointCloud& scan, const CsgTree& tree,
                        std::span<const Candidate> candidates, const VoxelGrid& grid,
                        const VoxelSet& inside, const HybridOptions& options = {},
                        const RunControl& control = {});

}  // namespace csgvox
