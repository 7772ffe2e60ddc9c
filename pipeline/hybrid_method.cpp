#include "pipeline/hybrid_method.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <numbers>
#include <optional>
#include <stdexcept>

#include "core/sardf.h"
#include "core/seed.h"
#include "evolve/point_regions.h"
#include "evolve/redundancy.h"
#include "mesh/surface_support.h"
#include "voxel/description_sets.h"

namespace csgvox {
namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

// The operands of a top-level union, or the tree itself.
std::vector<CsgTree> unionMembers(const CsgTree& tree) {
  std::vector<CsgTree> out;
  if (tree.root()->kind == NodeKind::Union) {
    for (const NodePtr& child : tree.root()->children) out.emplace_back(child);
  } else {
    out.push_back(tree);
  }
  return out;
}

CsgTree uniteAll(const std::vector<CsgTree>& trees) {
  return trees.size() == 1 ? trees.front() : CsgTree::unite(trees);
}

bool meets(const Aabb& a, const Aabb& b) { return !a.intersected(b).isEmpty(); }

// Points farther than `distance` from the tree's surface, or whose normal is
// further than `angle` (radians) from the field's outward direction.
std::vector<std::uint32_t> badlyExplained(const PointCloud& scan, const CsgTree& tree,
                                          const SetOperations& ops, double distance, double angle) {
  std::vector<char> bad(scan.size(), 0);
  const double cosLimit = std::cos(angle);
  tbb::parallel_for(std::size_t{0}, scan.size(), [&](std::size_t i) {
    const FieldValue v = tree.evaluate(scan.points[i], ops);
    const double g = v.gradient.norm();
    // ∇f points inwards, the scan's normal outwards.
    const double c = g > 0.0 ? -v.gradient.dot(scan.normals[i]) / g : -1.0;
    bad[i] = std::abs(v.f) > distance || c < cosLimit;
  });
  std::vector<std::uint32_t> out;
  for (std::size_t i = 0; i < bad.size(); ++i)
    if (bad[i]) out.push_back(std::uint32_t(i));
  return out;
}

// Points the tree explains (within `distance` of its zero set) where that
// zero set bounds no volume: the solid is on both sides of it or on
// neither, e.g. the surface of X in (A − X) ∪ (A ∩ X), or of X in A − (X − X).
// A fitness at the points credits such a surface as if it were the part's.
// The point is projected onto the zero set along the field's gradient and
// the field read a small step either side.
std::size_t ghostPoints(const PointCloud& scan, const CsgTree& tree, const SetOperations& ops,
                        double distance) {
  const double step = 0.05 * distance;
  std::vector<char> ghost(scan.size(), 0);
  tbb::parallel_for(std::size_t{0}, scan.size(), [&](std::size_t i) {
    const FieldValue v = tree.evaluate(scan.points[i], ops);
    const double g2 = v.gradient.squaredNorm();
    if (std::abs(v.f) > distance || g2 <= 0.0) return;
    const Vec3 q = scan.points[i] - v.f * v.gradient / g2;
    const Vec3 u = v.gradient / std::sqrt(g2);  // inwards
    const bool in = tree.evaluate(q + step * u, ops).f >= 0.0;
    const bool out = tree.evaluate(q - step * u, ops).f < 0.0;
    ghost[i] = !(in && out);
  });
  return std::size_t(std::count(ghost.begin(), ghost.end(), 1));
}

// A region: its bad points, the box around them, and the union members of
// the tree (indices) its subtree is made of.
struct Region {
  std::vector<std::uint32_t> bad;
  double unsupportedArea = 0.0;  // the tree's boundary in it no scan point is near
  Aabb box;
  std::vector<std::size_t> members;
};

// The members whose (grown) bounds meet the box, growing the box by each
// one taken, until no member is added.
void selectMembers(Region& region, std::span<const Aabb> memberBounds) {
  std::vector<char> taken(memberBounds.size(), 0);
  for (bool added = true; added;) {
    added = false;
    for (std::size_t m = 0; m < memberBounds.size(); ++m) {
      if (taken[m] || !meets(region.box, memberBounds[m])) continue;
      taken[m] = 1;
      region.box.extend(memberBounds[m]);
      added = true;
    }
  }
  region.members.clear();
  for (std::size_t m = 0; m < taken.size(); ++m)
    if (taken[m]) region.members.push_back(m);
}

// Regions of unsupported boundary: `samples` (each standing for `sampleArea`
// of it) grouped as bad points are, each group kept when the area it stands
// for would hold `least` points at `density`, in a box grown by `margin`.
std::vector<Region> boundaryRegions(std::span<const Vec3> samples, double sampleArea,
                                    double density, double least, double cell, double margin,
                                    std::span<const Aabb> memberBounds) {
  std::vector<std::uint32_t> all(samples.size());
  for (std::size_t i = 0; i < all.size(); ++i) all[i] = std::uint32_t(i);
  std::vector<Region> out;
  for (const std::vector<std::uint32_t>& group : pointRegions(samples, all, cell)) {
    const double area = double(group.size()) * sampleArea;
    if (area * density < least) continue;
    Region r;
    for (const std::uint32_t i : group) r.box.extend(samples[i]);
    r.unsupportedArea = area;
    r.box = r.box.grown(margin);
    selectMembers(r, memberBounds);
    out.push_back(std::move(r));
  }
  return out;
}

// Regions whose boxes meet become one (in order of their first point): a
// region's box holds its members' bounds, so regions sharing a member are
// joined too, and the regions left are independent.
std::vector<Region> joinMeetingRegions(std::vector<Region> regions,
                                       std::span<const Aabb> memberBounds) {
  for (bool joined = true; joined;) {
    joined = false;
    for (std::size_t a = 0; a < regions.size() && !joined; ++a) {
      for (std::size_t b = a + 1; b < regions.size() && !joined; ++b) {
        if (!meets(regions[a].box, regions[b].box)) continue;
        regions[a].bad.insert(regions[a].bad.end(), regions[b].bad.begin(), regions[b].bad.end());
        std::sort(regions[a].bad.begin(), regions[a].bad.end());
        regions[a].unsupportedArea += regions[b].unsupportedArea;
        regions[a].box.extend(regions[b].box);
        selectMembers(regions[a], memberBounds);
        regions.erase(regions.begin() + std::ptrdiff_t(b));
        joined = true;
      }
    }
  }
  return regions;
}

// The voxels whose centre lies in the box.
VoxelSet voxelsIn(const VoxelGrid& grid, const Aabb& box) {
  return solidVoxels(CsgTree::leaf(Box{box.center(), Mat3::Identity(), 0.5 * box.size()}), grid);
}

// A change of a subtree that the voxel labels ask for: candidate `candidate`,
// less (or intersected with, `intersect`) the subtree's leaf `leaf` (< 0:
// alone), taken away (`cut`) or added.
struct Repair {
  std::ptrdiff_t gain = 0;  // voxels of the box set right less voxels set wrong
  std::size_t candidate = 0;
  std::ptrdiff_t leaf = -1;
  bool intersect = false;
  bool cut = true;
};

// A repair must set right at least a block of 2 × 2 × 2 voxels.
constexpr std::ptrdiff_t kLeastRepair = 8;

// The best `count` repairs of `subtree` inside `box` with a gain of at least kLeastRepair,
// best first (ties in candidate, leaf order).
std::vector<Repair> voxelRepairs(const CsgTree& subtree, const Aabb& box,
                                 std::span<const Candidate> candidates, const VoxelGrid& grid,
                                 const VoxelSet& inside, std::size_t count) {
  const CsgTree boxLeaf = CsgTree::leaf(Box{box.center(), Mat3::Identity(), 0.5 * box.size()});
  const VoxelSet inBox = voxelsIn(grid, box);
  const VoxelSet solid = solidVoxels(subtree, grid) & inBox;
  // The box's voxels by what the subtree and the labels say: material the
  // labels say is outside (wrong), material they agree with (right), labelled
  // inside but not in the subtree (missing), neither (empty); each also
  // within each of the subtree's leaves.
  enum { kWrong, kRight, kMissing, kEmpty };
  const std::array<VoxelSet, 4> kinds = {solid - inside, solid & inside, (inside & inBox) - solid,
                                         inBox - solid - inside};
  const std::vector<const Node*> leaves = subtree.leaves();
  std::vector<std::array<VoxelSet, 4>> inLeaf(leaves.size());
  tbb::parallel_for(std::size_t(0), leaves.size(), [&](std::size_t l) {
    const VoxelSet q =
        solidVoxels(CsgTree::intersect({CsgTree::leaf(leaves[l]->primitive), boxLeaf}), grid);
    inLeaf[l] = {q & kinds[kWrong], q & kinds[kRight], q & kinds[kMissing], q & kinds[kEmpty]};
  });
  using Index = std::ptrdiff_t;
  // Each candidate's repairs in its own slot (in parallel), then in candidate order.
  std::vector<std::vector<Repair>> byCandidate(candidates.size());
  tbb::parallel_for(std::size_t(0), candidates.size(), [&](std::size_t c) {
    if (!meets(candidates[c].tree.bounds(), box)) return;
    const VoxelSet v = solidVoxels(CsgTree::intersect({candidates[c].tree, boxLeaf}), grid);
    if (v.count() == 0) return;
    std::array<Index, 4> all;  // v's voxels of each kind
    for (std::size_t k = 0; k < kinds.size(); ++k) all[k] = Index(VoxelSet::countAnd(v, kinds[k]));
    const auto consider = [&](Index gain, Index leaf, bool intersect, bool cut) {
      if (gain >= kLeastRepair) byCandidate[c].push_back({gain, c, leaf, intersect, cut});
    };
    consider(all[kWrong] - all[kRight], -1, false, true);
    consider(all[kMissing] - all[kEmpty], -1, false, false);
    for (std::size_t l = 0; l < inLeaf.size(); ++l) {
      std::array<Index, 4> q;  // v's voxels of each kind within leaf l
      for (std::size_t k = 0; k < kinds.size(); ++k)
        q[k] = Index(VoxelSet::countAnd(v, inLeaf[l][k]));
      consider((all[kWrong] - q[kWrong]) - (all[kRight] - q[kRight]), Index(l), false, true);
      consider(q[kWrong] - q[kRight], Index(l), true, true);
      consider((all[kMissing] - q[kMissing]) - (all[kEmpty] - q[kEmpty]), Index(l), false, false);
      consider(q[kMissing] - q[kEmpty], Index(l), true, false);
    }
  });
  std::vector<Repair> out;
  for (std::vector<Repair>& r : byCandidate) out.insert(out.end(), r.begin(), r.end());
  std::stable_sort(out.begin(), out.end(),
                   [](const Repair& a, const Repair& b) { return a.gain > b.gain; });
  if (out.size() > count) out.resize(count);
  return out;
}

// What a region's search found.
struct RegionSearch {
  HybridRegion report;
  CsgTree subtree;   // the original subtree (union of its members)
  CsgTree repaired;  // the search's best tree
};

// What every region's search reads: the scan, the tree's union members, the
// candidates and the voxel labels.
struct SearchInputs {
  const PointCloud& scan;
  const std::vector<CsgTree>& members;
  std::span<const Candidate> candidates;
  const VoxelGrid& grid;
  const VoxelSet& inside;
  const HybridOptions& options;
};

// A candidate that fits a region: (bad points near it, candidate).
using Fit = std::pair<std::size_t, std::size_t>;

// The candidates that fit the region: in its box, and with a surface near
// many of its bad points; best supported first, options.maxCandidates at most.
std::vector<Fit> fittingCandidates(const SearchInputs& in, const Region& region) {
  const double tolerance = in.options.fitness.distanceTolerance * in.scan.diagonal();
  std::vector<Fit> fits;
  for (std::size_t c = 0; c < in.candidates.size(); ++c) {
    const CsgTree& t = in.candidates[c].tree;
    if (!meets(t.bounds(), region.box)) continue;
    const std::vector<const Node*> leaves = t.leaves();
    std::size_t near = 0;
    for (const std::uint32_t i : region.bad) {
      for (const Node* leaf : leaves) {
        if (std::abs(leaf->primitive.value(in.scan.points[i])) <= 2.0 * tolerance) {
          ++near;
          break;
        }
      }
    }
    if (near >= 5) fits.push_back({near, c});
  }
  std::stable_sort(fits.begin(), fits.end(),
                   [](const auto& a, const auto& b) { return a.first > b.first; });
  if (fits.size() > in.options.maxCandidates) fits.resize(in.options.maxCandidates);
  return fits;
}

// What a region's search starts from besides its subtree: the voxel repairs
// and the candidates (the repairs' first, then the fitting ones).
struct RegionPicks {
  std::vector<Repair> repairs;
  std::vector<Fit> fits;
};

// Where the subtree holds material no point bounds (or leaves a hole no
// point bounds), the repairs that would set its voxels right there: a
// candidate c, c − q or c ∩ q (q one of the subtree's primitives) taken
// away or added, scored by the region's voxels it sets right against the
// labels less those it sets wrong. The best become seeds, their
// candidates join the library.
RegionPicks pickCandidates(const SearchInputs& in, const Region& region, const CsgTree& subtree) {
  const std::vector<Fit> fits = fittingCandidates(in, region);
  RegionPicks picks;
  if (region.unsupportedArea > 0.0)
    picks.repairs =
        voxelRepairs(subtree, region.box, in.candidates, in.grid, in.inside, in.options.maxRepairs);
  std::vector<Fit>& picked = picks.fits;  // the repairs' candidates first
  for (const Repair& r : picks.repairs) {
    if (std::none_of(picked.begin(), picked.end(),
                     [&](const auto& f) { return f.second == r.candidate; }))
      picked.push_back({0, r.candidate});
  }
  for (const auto& f : fits) {
    if (picked.size() >= std::max(in.options.maxCandidates, picks.repairs.size())) break;
    if (std::none_of(picked.begin(), picked.end(),
                     [&](const auto& g) { return g.second == f.second; }))
      picked.push_back(f);
  }
  return picks;
}

// The library: the subtree's primitives and the picked candidates'.
PrimitiveLibrary regionLibrary(const CsgTree& subtree, const std::vector<Fit>& fits,
                               std::span<const Candidate> candidates) {
  std::vector<Primitive> primitives;
  std::vector<std::string> names;
  const auto add = [&](const Node* leaf) {
    for (const Primitive& p : primitives)
      if (p == leaf->primitive) return;
    primitives.push_back(leaf->primitive);
    names.push_back(leaf->name.empty() ? "p" + std::to_string(names.size()) : leaf->name);
  };
  for (const Node* leaf : subtree.leaves()) add(leaf);
  for (const auto& [near, c] : fits)
    for (const Node* leaf : candidates[c].tree.leaves()) add(leaf);
  return PrimitiveLibrary(std::move(primitives), std::move(names));
}

// The scan's points in a box, with their normals.
struct BoxPoints {
  std::vector<Vec3> points, normals;
};

// The points around the region.
BoxPoints pointsIn(const PointCloud& scan, const Aabb& box) {
  BoxPoints out;
  for (std::size_t i = 0; i < scan.size(); ++i) {
    if (!box.contains(scan.points[i])) continue;
    out.points.push_back(scan.points[i]);
    out.normals.push_back(scan.normals[i]);
  }
  return out;
}

// Seeds: the subtree (`original`, adopted by the library), the subtree with
// each repair, and the subtree with one picked candidate added or taken away.
std::vector<CsgTree> regionSeeds(const SearchInputs& in, const CsgTree& original,
                                 const PrimitiveLibrary& library, const RegionPicks& picks) {
  const CsgTree subtree = library.adopt(original);
  std::vector<CsgTree> seeds = {subtree};
  const std::vector<const Node*> subtreeLeaves = original.leaves();
  for (const Repair& r : picks.repairs) {
    CsgTree t = library.adopt(in.candidates[r.candidate].tree);
    if (r.leaf >= 0) {
      const CsgTree q = library.adopt(CsgTree::leaf(subtreeLeaves[std::size_t(r.leaf)]->primitive));
      t = r.intersect ? CsgTree::intersect({t, q}) : CsgTree::subtract({t, q});
    }
    seeds.push_back(r.cut ? CsgTree::subtract({subtree, t}) : CsgTree::unite({subtree, t}));
  }
  for (const auto& [near, c] : picks.fits) {
    const CsgTree candidate = library.adopt(in.candidates[c].tree);
    seeds.push_back(CsgTree::unite({subtree, candidate}));
    seeds.push_back(CsgTree::subtract({subtree, candidate}));
    if (seeds.size() + 2 > in.options.evolve.population) break;
  }
  return seeds;
}

RegionSearch searchRegion(const SearchInputs& in, const Region& region, std::uint64_t seed,
                          const RunControl& control) {
  const Clock::time_point start = Clock::now();
  const HybridOptions& options = in.options;
  RegionSearch out;
  std::vector<CsgTree> chosen;
  for (const std::size_t m : region.members) chosen.push_back(in.members[m]);
  out.subtree = uniteAll(chosen);
  const RegionPicks picks = pickCandidates(in, region, out.subtree);
  const PrimitiveLibrary library = regionLibrary(out.subtree, picks.fits, in.candidates);

  // The points around the region and the labels there.
  const BoxPoints around = pointsIn(in.scan, region.box);
  const VoxelTarget target{in.grid, in.inside & voxelsIn(in.grid, region.box)};
  const VoxelTarget* t = options.fitness.voxelWeight > 0.0 ? &target : nullptr;
  const FitnessModel model(around.points, around.normals, in.scan.diagonal(), library,
                           options.fitness, t);
  const std::optional<FitnessModel> rough =
      roughModel(model, around.points, around.normals, options.roughPoints, seed);

  const CsgTree subtree = library.adopt(out.subtree);
  EvolveOptions eo = options.evolve;
  eo.seed = seed;
  eo.control = control;
  eo.variation.maxDepth = std::max(eo.variation.maxDepth, subtree.depth() + 3);
  const EvolveResult r = evolve(model, regionSeeds(in, out.subtree, library, picks), eo, {},
                                rough ? &*rough : nullptr);
  out.repaired = r.best;

  HybridRegion& h = out.report;
  h.badPoints = region.bad.size();
  h.unsupportedArea = region.unsupportedArea;
  h.points = around.points.size();
  h.members = region.members.size();
  h.library = library.size();
  h.generations = r.generations;
  h.localBefore = model.evaluate(subtree).total;
  h.localAfter = r.fitness.total;
  h.primitivesBefore = subtree.primitiveCount();
  h.primitivesAfter = r.best.primitiveCount();
  h.seconds = secondsSince(start);
  return out;
}

// The regions' searches, `searches` of each with seeds of their own, all in
// parallel; each is deterministic for its seed. A region keeps the search
// with the best fitness on its points (the first of equals).
std::vector<RegionSearch> searchRegions(const SearchInputs& in, const std::vector<Region>& regions,
                                        const RunControl& control) {
  const std::size_t searches = std::max<std::size_t>(in.options.searches, 1);
  std::vector<RegionSearch> runs(regions.size() * searches);
  tbb::parallel_for(std::size_t{0}, runs.size(), [&](std::size_t j) {
    const std::size_t k = j / searches, s = j % searches;
    const std::uint64_t seed = mixSeed(in.options.evolve.seed, k);
    runs[j] = searchRegion(in, regions[k], s == 0 ? seed : mixSeed(seed, s), control);
  });
  std::vector<RegionSearch> found(regions.size());
  for (std::size_t k = 0; k < regions.size(); ++k) {
    HybridRegion all;  // every search's fitness, and their time
    for (std::size_t j = k * searches; j < (k + 1) * searches; ++j) {
      all.searchFitness.push_back(runs[j].report.localAfter);
      all.seconds += runs[j].report.seconds;
    }
    found[k] = std::move(runs[k * searches + all.search()]);
    found[k].report.searchFitness = std::move(all.searchFitness);
    found[k].report.seconds = all.seconds;
  }
  return found;
}

// How regions are cut: the members' bounds grown by the margin, the margin
// and cell size (scan units) and the least bad points of a region.
struct RegionLayout {
  std::vector<Aabb> memberBounds;
  double margin = 0.0;
  double cell = 0.0;
  std::size_t least = 0;
};

// The layout of the regions around `members` for a scan of `points` points.
RegionLayout regionLayout(const std::vector<CsgTree>& members, std::size_t points,
                          const HybridOptions& options, double voxel) {
  RegionLayout layout;
  layout.margin = options.margin * voxel;
  layout.cell = options.regionCell * voxel;
  for (const CsgTree& m : members) layout.memberBounds.push_back(m.bounds().grown(layout.margin));
  layout.least =
      std::max<std::size_t>(10, std::size_t(std::ceil(options.minRegionPoints * double(points))));
  return layout;
}

// Regions of bad points, each with the members of the tree around it.
std::vector<Region> badPointRegions(const PointCloud& scan, std::span<const std::uint32_t> bad,
                                    const RegionLayout& layout) {
  std::vector<Region> regions;
  for (std::vector<std::uint32_t>& points : pointRegions(scan.points, bad, layout.cell)) {
    if (points.size() < layout.least) continue;
    Region r;
    for (const std::uint32_t i : points) r.box.extend(scan.points[i]);
    r.box = r.box.grown(layout.margin);
    r.bad = std::move(points);
    selectMembers(r, layout.memberBounds);
    regions.push_back(std::move(r));
  }
  return regions;
}

// The support of a tree's boundary by the scan's points (none when the tree
// cannot be sampled), the points' search built on first use.
struct SupportMeter {
  const PointCloud& scan;
  SupportOptions options;
  std::optional<NearestNeighbors> nearest{};

  std::optional<SurfaceSupport> operator()(const CsgTree& t, bool keep) {
    if (!nearest) nearest.emplace(scan.points);
    SupportOptions o = options;
    o.keepUnsupported = keep;
    try {
      return surfaceSupport(t, *nearest, o);
    } catch (const std::invalid_argument&) {
      return std::nullopt;
    }
  }
};

// The regions of the input tree's unsupported boundary, `support` kept with
// its samples. On a sparse scan, random gaps between points are wider than
// εd: only samples farther than a few mean spacings from every point form
// regions.
std::vector<Region> unsupportedRegions(const SurfaceSupport& support, const SupportMeter& meter,
                                       const HybridOptions& options, const RegionLayout& layout) {
  const double density = double(meter.scan.size()) / support.area;
  const double far = std::max(meter.options.distance, options.supportSpacing / std::sqrt(density));
  std::vector<Vec3> samples;
  for (std::size_t i = 0; i < support.unsupportedSamples.size(); ++i)
    if (support.unsupportedDistances[i] > far) samples.push_back(support.unsupportedSamples[i]);
  return boundaryRegions(samples, support.sampleArea, density, double(layout.least), layout.cell,
                         layout.margin, layout.memberBounds);
}

// Each member's region (-1: none).
std::vector<std::ptrdiff_t> memberRegions(std::size_t members, const std::vector<Region>& regions) {
  std::vector<std::ptrdiff_t> regionOf(members, -1);
  for (std::size_t k = 0; k < regions.size(); ++k)
    for (const std::size_t m : regions[k].members) regionOf[m] = std::ptrdiff_t(k);
  return regionOf;
}

// The regions' repaired subtrees and which of them the tree has taken.
struct Assembly {
  const std::vector<CsgTree>& members;
  const std::vector<Region>& regions;
  const std::vector<RegionSearch>& found;
  std::vector<std::ptrdiff_t> regionOf = memberRegions(members.size(), regions);
  std::vector<char> accepted = std::vector<char>(found.size(), 0);

  // The tree with the repaired subtrees of the accepted regions and of
  // region `trial` in place of their members (regions are disjoint in
  // members; a region's repaired subtree takes its first member's place).
  CsgTree operator()(std::ptrdiff_t trial) const {
    std::vector<CsgTree> parts;
    for (std::size_t m = 0; m < members.size(); ++m) {
      const std::ptrdiff_t k = regionOf[m];
      if (k < 0 || (!accepted[std::size_t(k)] && k != trial)) {
        parts.push_back(members[m]);
      } else if (m == regions[std::size_t(k)].members.front()) {
        parts.push_back(found[std::size_t(k)].repaired);
      }
    }
    return normalizeTree(uniteAll(parts));
  }
};

// Judges the regions' replacements in order, each in the tree with those
// accepted before it, by the whole tree's fitness less the credit (a
// distance and a normal term) of the points explained only by ghost
// surfaces, then less that of the points the boundary it adds where the scan
// has none would hold at the scan's density (a tree that cannot be sampled
// supports nothing).
struct ReplacementJudge {
  const PointCloud& scan;
  const SetOperations& ops;
  const FitnessModel& model;
  const PrimitiveLibrary& library;
  SupportMeter& support;
  std::optional<SurfaceSupport>& bestSupport;  // the tree's so far
  Assembly& assemble;
  HybridResult& out;
  double tolerance;  // εd, scan units
  double gain;       // the least rise of the score a replacement must bring
  double best;       // the tree's score so far

  // The verdict on region k, whose report is `h`; a replacement is accepted.
  RegionVerdict operator()(std::size_t k, HybridRegion& h) {
    if (!(h.localAfter > h.localBefore)) return RegionVerdict::NotImproved;
    const CsgTree trial = assemble(std::ptrdiff_t(k));
    const Fitness f = model.evaluate(library.adopt(trial));
    if (!(f.total > best + gain)) return RegionVerdict::NoGain;
    const std::size_t ghosts = ghostPoints(scan, trial, ops, tolerance);
    const double score = f.total - 2.0 * double(ghosts);
    if (!(score > best + gain)) return RegionVerdict::Ghost;
    const std::optional<SurfaceSupport> s = support(trial, false);
    if (s) h.unsupported = s->unsupported;
    if (!bestSupport || !s) return RegionVerdict::Unsupported;
    const double density = double(scan.size()) / bestSupport->area;
    if (!(score - 2.0 * density * (s->unsupported - bestSupport->unsupported) > best + gain))
      return RegionVerdict::Unsupported;
    best = score;
    bestSupport->unsupported = out.unsupportedAfter = s->unsupported;
    out.ghostAfter = ghosts;
    assemble.accepted[k] = 1;
    ++out.replaced;
    return RegionVerdict::Replaced;
  }
};

// The set operations the fitness options name (`sardf` for Sardf).
const SetOperations& setOperations(const FitnessOptions& fitness, const SardfOperations& sardf) {
  return fitness.operations == SetOperationKind::Sardf ? static_cast<const SetOperations&>(sardf)
         : fitness.operations == SetOperationKind::RFunction ? rFunctionOperations()
                                                             : minMaxOperations();
}

// A cylinder of the tree that stands for `c`: axes parallel within 8°, the
// axes within a third of c's radius of each other, radii within a quarter.
bool sameCylinder(const Cylinder& t, const Cylinder& c) {
  if (std::abs(t.axis.dot(c.axis)) < std::cos(8.0 * std::numbers::pi / 180.0)) return false;
  const Vec3 d = t.center - c.center;
  return (d - d.dot(c.axis) * c.axis).norm() < c.radius / 3.0 &&
         std::abs(t.radius - c.radius) < 0.25 * c.radius;
}

// The holes the detection saw that the tree lacks: each bounded cylinder
// fitted to a detected surface (a Quadric candidate) that no cylinder of the
// tree stands for is subtracted from the whole tree, best supported first,
// and kept when the tree's fitness on all points rises and its voxel term
// does not get worse. A hole one or two voxels wide, whose rims and a little
// of whose wall the scan shows, raises the fitness by less than minGain·N (a
// region's worth of points), and the labels hold too few of its voxels
// empty for the voxel stage to cut it.
void addSeenHoles(const PointCloud& scan, std::span<const Candidate> candidates,
                  const VoxelGrid& grid, const VoxelSet& inside, const HybridOptions& options,
                  HybridResult& out) {
  std::vector<Cylinder> have;
  for (const Node* leaf : out.tree.leaves())
    if (const auto* c = leaf->primitive.as<Cylinder>()) have.push_back(*c);
  std::vector<const Candidate*> holes;
  for (const Candidate& c : candidates) {
    if (c.origin != CandidateOrigin::Quadric || c.tree.empty() ||
        c.tree.root()->kind != NodeKind::Primitive)
      continue;
    const auto* cylinder = c.tree.root()->primitive.as<Cylinder>();
    if (cylinder == nullptr) continue;
    if (std::none_of(have.begin(), have.end(),
                     [&](const Cylinder& t) { return sameCylinder(t, *cylinder); }))
      holes.push_back(&c);
  }
  if (holes.empty()) return;
  std::stable_sort(holes.begin(), holes.end(), [](const Candidate* a, const Candidate* b) {
    return a->support > b->support;
  });
  std::vector<CsgTree> all = {out.tree};
  for (const Candidate* h : holes) all.push_back(h->tree);
  const PrimitiveLibrary library = PrimitiveLibrary::ofTree(uniteAll(all));
  const VoxelTarget target{grid, inside};
  const FitnessModel model(scan.points, scan.normals, scan.diagonal(), library, options.fitness,
                           options.fitness.voxelWeight > 0.0 ? &target : nullptr);
  std::vector<CsgTree> operands = {out.tree};
  Fitness best = model.evaluate(library.adopt(out.tree));
  for (const Candidate* h : holes) {
    operands.push_back(h->tree);
    const CsgTree trial = library.adopt(CsgTree::subtract(operands));
    const Fitness f = model.evaluate(trial);
    if (f.total > best.total && f.voxelPenalty <= best.voxelPenalty) {
      best = f;
      ++out.holesAdded;
    } else {
      operands.pop_back();
    }
  }
  if (out.holesAdded == 0) return;
  out.tree = library.adopt(normalizeTree(CsgTree::subtract(operands)));
  out.after = model.evaluate(out.tree);
}

}  // namespace

const char* regionVerdictName(RegionVerdict verdict) {
  switch (verdict) {
    case RegionVerdict::NotImproved:
      return "not improved";
    case RegionVerdict::NoGain:
      return "no gain";
    case RegionVerdict::Ghost:
      return "ghost surfaces";
    case RegionVerdict::Unsupported:
      return "unsupported boundary";
    case RegionVerdict::Replaced:
      return "replaced";
  }
  return "?";
}

HybridResult repairTree(const PointCloud& scan, const CsgTree& tree,
                        std::span<const Candidate> candidates, const VoxelGrid& grid,
                        const VoxelSet& inside, const HybridOptions& options,
                        const RunControl& control) {
  if (!scan.hasNormals())
    throw std::invalid_argument("the hybrid method needs a scan with normals");
  if (tree.empty()) throw std::invalid_argument("the hybrid method needs a tree to repair");
  const double diagonal = scan.diagonal();
  HybridResult out;
  out.tree = tree;
  out.primitivesBefore = out.primitivesAfter = tree.primitiveCount();

  const SardfOperations sardf(options.fitness.sardfRadius * diagonal);
  const SetOperations& ops = setOperations(options.fitness, sardf);
  const std::vector<std::uint32_t> bad = badlyExplained(
      scan, tree, ops, std::max(options.fitness.distanceTolerance * diagonal, 3.0 * options.noise),
      options.badAngle * std::numbers::pi / 180.0);
  out.badPoints = bad.size();

  // Regions of bad points, each with the members of the tree around it.
  const std::vector<CsgTree> members = unionMembers(tree);
  const RegionLayout layout = regionLayout(members, scan.size(), options, grid.voxelSize());
  std::vector<Region> regions = badPointRegions(scan, bad, layout);

  // The tree's boundary no scan point is near: material (or a hole) the
  // voxels kept where the part has none, which no point can call bad. Its
  // samples are grouped as the bad points are; a group is a region when the
  // area it stands for would hold as many points as the least region.
  const double tolerance = options.fitness.distanceTolerance * diagonal;
  SupportOptions so;
  so.distance = options.supportDistance * tolerance;
  so.samples = options.supportSamples;
  so.seed = options.evolve.seed;
  SupportMeter support{scan, so};
  // The input tree's support, which also weighs every replacement below.
  std::optional<SurfaceSupport> bestSupport = support(tree, options.unsupportedRegions);
  if (bestSupport) {
    out.area = bestSupport->area;
    out.unsupportedBefore = out.unsupportedAfter = bestSupport->unsupported;
  }
  if (bestSupport && bestSupport->area > 0.0 && options.unsupportedRegions) {
    for (Region& r : unsupportedRegions(*bestSupport, support, options, layout))
      regions.push_back(std::move(r));
  }
  regions = joinMeetingRegions(std::move(regions), layout.memberBounds);

  const SearchInputs in{scan, members, candidates, grid, inside, options};
  std::vector<RegionSearch> found = searchRegions(in, regions, control);
  if (control.cancelled()) return out;  // the input tree, unjudged: the caller drops it

  // One model of the whole tree on all points, over its primitives and those
  // of every subtree its region's search improved, judges each replacement.
  std::vector<CsgTree> all = {tree};
  for (const RegionSearch& f : found)
    if (f.report.localAfter > f.report.localBefore) all.push_back(f.repaired);
  const PrimitiveLibrary library = PrimitiveLibrary::ofTree(uniteAll(all));
  const VoxelTarget target{grid, inside};
  const FitnessModel model(scan.points, scan.normals, diagonal, library, options.fitness,
                           options.fitness.voxelWeight > 0.0 ? &target : nullptr);
  out.before = model.evaluate(library.adopt(tree));
  out.ghostBefore = out.ghostAfter = ghostPoints(scan, tree, ops, tolerance);
  Assembly assemble{members, regions, found};
  ReplacementJudge judge{.scan = scan,
                         .ops = ops,
                         .model = model,
                         .library = library,
                         .support = support,
                         .bestSupport = bestSupport,
                         .assemble = assemble,
                         .out = out,
                         .tolerance = tolerance,
                         .gain = options.minGain * double(scan.size()),
                         // less its ghosts' credit
                         .best = out.before.total - 2.0 * double(out.ghostBefore)};
  for (std::size_t k = 0; k < found.size(); ++k) {
    found[k].report.verdict = judge(k, found[k].report);
    out.regions.push_back(found[k].report);
  }
  if (out.replaced == 0) {
    // Nothing the points paid for: the voxel tree, as it was (its own stage
    // already removed what changes no voxel).
    out.after = out.before;
  } else {
    out.tree = library.adopt(assemble(-1));
    // Redundancy removal evaluates the tree once per node and operand on all
    // points: skipped once the time limit is spent (or the work cancelled).
    if (!control.shouldStop()) {
      out.tree = removeRedundancy(out.tree, model);
    }
    out.after = model.evaluate(out.tree);
  }
  if (options.seenHoles && !control.shouldStop())
    addSeenHoles(scan, candidates, grid, inside, options, out);
  out.primitivesAfter = out.tree.primitiveCount();
  return out;
}

}  // namespace csgvox
