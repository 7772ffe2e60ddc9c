// Cuboid hypotheses from plane patches (Wu et al. 2018 §3.1): direction sets,
// the orthogonality graph and its decomposition into groups, the group
// frames (Eq. 2), the enumeration of one patch or none per direction (Eq. 3)
// and the three filters.

#include <algorithm>
#include <cmath>
#include <limits>

#include "primitives/hypotheses_internal.h"

namespace csgvox::hypotheses_detail {
namespace {

// A plane patch with what the enumeration needs.
struct PlanePatch {
  int surface = -1;
  Vec3 normal = Vec3::UnitZ();  // unit, outward
  Vec3 centroid = Vec3::Zero();
  double support = 0.0;
  double sigma = 0.0;        // noise across the plane (the surface's rms)
  std::vector<Vec3> points;  // every inlier
};

// Parallel patches (normals n and -n alike).
struct DirectionSet {
  Vec3 direction = Vec3::UnitZ();    // the best-supported patch's normal
  std::vector<std::size_t> patches;  // indices into the patch list, best supported first
  double support = 0.0;
};

// A patch seen in a group's frame.
struct GroupPatch {
  std::size_t patch = 0;       // index into the patch list
  std::size_t axis = 0;        // frame axis its normal is parallel to
  int sign = 1;                // +1: normal along +axis, -1: along -axis
  double plane = 0.0;          // position of its plane along the axis
  std::array<Range, 3> range;  // extent of its points along the frame axes
  double support = 0.0;
  std::vector<Vec3> fitPoints;  // an even subset, in frame coordinates
};

// A box that passed filters 1 and 2, waiting for filter 3.
struct Hypothesis {
  std::array<Range, 3> ranges;
  std::vector<std::size_t> patches;  // indices into the group's patches, ascending
  double support = 0.0;
  bool tool = false;
  std::size_t order = 0;  // enumeration order (tie-break)
};

// Largest value a count saturates at.
constexpr std::size_t kHuge = std::numeric_limits<std::size_t>::max() / 4;

std::size_t saturatingMul(std::size_t a, std::size_t b) {
  if (a == 0 || b == 0) return 0;
  return a > kHuge / b ? kHuge : a * b;
}

// Unsigned distance from a point (frame coordinates) to the surface of the
// box spanning `r`.
double boxSurfaceDistance(const Vec3& p, const std::array<Range, 3>& r) {
  double outside2 = 0.0, insideMax = -std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < 3; ++k) {
    const double c = 0.5 * (r[k].lo + r[k].hi), h = 0.5 * r[k].size();
    const double q = std::abs(p[static_cast<Eigen::Index>(k)] - c) - h;
    if (q > 0.0) outside2 += q * q;
    insideMax = std::max(insideMax, q);
  }
  return outside2 > 0.0 ? std::sqrt(outside2) : -insideMax;
}

// Orthonormal right-handed frame with e0 = a and e1 as close to b as possible.
Mat3 frameFrom(const Vec3& a, const Vec3& b) {
  const Vec3 e0 = a.normalized();
  const Vec3 e1 = (b - b.dot(e0) * e0).normalized();
  Mat3 f;
  f.col(0) = e0;
  f.col(1) = e1;
  f.col(2) = e0.cross(e1);
  return f;
}

// v* of Eq. 2: the direction of the longer side of the minimum-area
// rectangle of the patch's points in its plane.
Vec3 longerRectangleSide(const PlanePatch& patch) {
  const Mat3 basis = frameFromAxis(patch.normal);
  std::vector<Eigen::Vector2d> uv;
  uv.reserve(patch.points.size());
  for (const Vec3& p : patch.points) {
    const Vec3 d = p - patch.centroid;
    uv.emplace_back(d.dot(basis.col(0)), d.dot(basis.col(1)));
  }
  const Rectangle2 rect = minAreaRectangle(uv);
  return rect.direction.x() * basis.col(0) + rect.direction.y() * basis.col(1);
}

// One group's cuboid hypotheses: every selection of one patch or none along
// each of the six directions (Eq. 3), pruned by filter 1 while enumerating,
// then filter 2 per box and filter 3 over the group's survivors.
class GroupEnumerator {
 public:
  // `others`: the patches of other groups parallel to one of this group's
  // axes (planes a free end may snap onto, never chosen).
  GroupEnumerator(const Context& ctx, CuboidStats& stats, const std::vector<PlanePatch>& planes,
                  std::vector<GroupPatch> patches, std::vector<GroupPatch> others,
                  std::size_t& budgetUsed)
      : ctx_(ctx),
        stats_(stats),
        planes_(planes),
        patches_(std::move(patches)),
        others_(std::move(others)),
        budgetUsed_(budgetUsed) {
    for (std::size_t i = 0; i < patches_.size(); ++i) {
      const GroupPatch& g = patches_[i];
      dirs_[2 * g.axis + (g.sign < 0 ? 1 : 0)].push_back(i);
    }
    // Eq. 3 with every patch, then the per-direction cap (best supported first).
    std::size_t product = 1;
    for (auto& d : dirs_) {
      product = saturatingMul(product, d.size() + 1);
      std::stable_sort(d.begin(), d.end(), [&](std::size_t a, std::size_t b) {
        return patches_[a].support > patches_[b].support;
      });
      if (d.size() > ctx_.options.maxPatchesPerDirection) {
        d.resize(ctx_.options.maxPatchesPerDirection);
        stats_.patchesCapped = true;
      }
    }
    stats_.eq3Count = std::min(kHuge, stats_.eq3Count + std::min(kHuge, product + patches_.size()));
    // Number of complete selections of the directions from d on (for pruned subtrees).
    below_[6] = 1;
    for (std::size_t d = 6; d-- > 0;) below_[d] = saturatingMul(below_[d + 1], dirs_[d].size() + 1);
  }

  /// Enumerates and filters; returns the kept boxes of this group.
  std::vector<Hypothesis> run() {
    descend(0, true, ctx_.options.toolCuboids);
    return removeRedundant();
  }

  const GroupPatch& patch(std::size_t i) const { return patches_[i]; }

 private:
  // Counts n hypotheses as considered; `built` ones use up the budget
  // (pruned ones cost nothing).
  void consider(std::size_t n, bool built) {
    stats_.considered = std::min(kHuge, stats_.considered + n);
    if (!built) return;
    budgetUsed_ = std::min(kHuge, budgetUsed_ + n);
    if (budgetUsed_ >= ctx_.options.maxCuboidHypotheses) {
      stop_ = true;
      stats_.enumerationCapped = true;
    }
  }

  // Chooses one patch or none along direction d, then the next directions.
  // solidOk / toolOk: every pair chosen so far faces outwards / inwards.
  void descend(std::size_t d, bool solidOk, bool toolOk) {
    if (stop_) return;
    if (d == 6) {
      evaluate(solidOk);
      return;
    }
    descend(d + 1, solidOk, toolOk);  // no patch along this direction
    const double eps = 1e-9 * ctx_.diagonal;
    for (std::size_t p : dirs_[d]) {
      if (stop_) return;
      bool s = solidOk, t = toolOk;
      const PlanePatch& pa = planes_[patch(p).patch];
      for (std::size_t q : chosen_) {
        const PlanePatch& pb = planes_[patch(q).patch];
        const Vec3 d12 = pb.centroid - pa.centroid;
        const double f1 = pa.normal.dot(d12), f2 = -pb.normal.dot(d12);
        // Wu's filter 1: each normal points away from the other patch; for a
        // tool box, each points towards it.
        s = s && f1 < -eps && f2 < -eps;
        t = t && f1 > eps && f2 > eps;
      }
      if (!s && !t) {
        // Filter 1 rejects every selection containing this pair.
        stats_.rejectedOrientation = std::min(kHuge, stats_.rejectedOrientation + below_[d + 1]);
        consider(below_[d + 1], false);
        continue;
      }
      chosen_.push_back(p);
      descend(d + 1, s, t);
      chosen_.pop_back();
    }
  }

  void evaluate(bool solidOk) {
    if (chosen_.empty()) return;
    if (chosen_.size() == 1) {
      consider(2, true);
      const GroupPatch& g = patch(chosen_[0]);
      // Height: the patch's longest side in the frame.
      double height = 0.0;
      for (std::size_t k = 0; k < 3; ++k) {
        if (k != g.axis) height = std::max(height, g.range[k].size());
      }
      for (bool tool : {false, true}) {
        std::array<Range, 3> r = g.range;
        // Solid: the box lies behind the patch (against its normal); tool: in front.
        const bool above = (g.sign > 0) == tool;
        r[g.axis] = above ? Range{g.plane, g.plane + height} : Range{g.plane - height, g.plane};
        std::array<std::array<bool, 2>, 3> bounded{};
        bounded[g.axis][above ? 0 : 1] = true;  // the patch's plane
        snapFreeEnds(r, bounded);
        test(r, tool);
      }
      return;
    }
    consider(1, true);
    const bool tool = !solidOk;
    std::array<Range, 3> r;
    r.fill({std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()});
    for (std::size_t p : chosen_) {
      for (std::size_t k = 0; k < 3; ++k) {
        r[k].lo = std::min(r[k].lo, patch(p).range[k].lo);
        r[k].hi = std::max(r[k].hi, patch(p).range[k].hi);
      }
    }
    // The chosen planes are exact faces: a solid box ends at a patch on the
    // patch's normal side, a tool box starts there.
    std::array<std::array<bool, 2>, 3> bounded{};
    for (std::size_t p : chosen_) {
      const GroupPatch& g = patch(p);
      const bool upper = (g.sign > 0) != tool;
      (upper ? r[g.axis].hi : r[g.axis].lo) = g.plane;
      bounded[g.axis][upper ? 1 : 0] = true;
    }
    snapFreeEnds(r, bounded);
    test(r, tool);
  }

  // Moves each end of the box that no chosen patch bounds (the extreme
  // inliers of its patches, which noise pushes outwards) onto the nearest
  // fitted plane across that axis within the end's uncertainty (three noise
  // deviations, at least twice the duplicate tolerance) whose patch overlaps
  // the box: a plane is fitted to thousands of points, so its position is far
  // more accurate than the extremes of a noisy patch. Without this a noisy
  // box comes out a fraction of a voxel too large on every free side (the
  // same as the ends of a bounded cylinder, snapEndsToPlanes).
  void snapFreeEnds(std::array<Range, 3>& r,
                    const std::array<std::array<bool, 2>, 3>& bounded) const {
    double sigma = 0.0;
    for (std::size_t p : chosen_) sigma = std::max(sigma, planes_[patch(p).patch].sigma);
    const double tol = std::max(3.0 * sigma, 2.0 * ctx_.lengthTol);
    const std::array<Range, 3> original = r;
    for (std::size_t k = 0; k < 3; ++k) {
      for (const bool upper : {false, true}) {
        if (bounded[k][upper ? 1 : 0]) continue;
        const double end = upper ? original[k].hi : original[k].lo;
        double best = std::numeric_limits<double>::infinity();
        auto tryPlane = [&](const GroupPatch& g) {
          if (g.axis != k || !(std::abs(g.plane - end) <= tol) ||
              std::abs(g.plane - end) >= std::abs(best - end)) {
            return;
          }
          for (std::size_t j = 0; j < 3; ++j) {
            if (j != k && (g.range[j].hi < original[j].lo || g.range[j].lo > original[j].hi)) {
              return;  // the patch does not overlap the box
            }
          }
          best = g.plane;
        };
        for (const GroupPatch& g : patches_) tryPlane(g);
        for (const GroupPatch& g : others_) tryPlane(g);
        if (std::isfinite(best)) (upper ? r[k].hi : r[k].lo) = best;
      }
    }
    for (std::size_t k = 0; k < 3; ++k) {
      if (!(r[k].size() > 0.5 * original[k].size())) r[k] = original[k];
    }
  }

  // The degenerate check and filter 2 (fit); survivors wait for filter 3.
  void test(const std::array<Range, 3>& r, bool tool) {
    const double minSize = 1e-6 * ctx_.diagonal;
    for (const Range& x : r) {
      if (!(x.size() > minSize)) {
        ++stats_.rejectedDegenerate;
        return;
      }
    }
    double weighted = 0.0, weight = 0.0;
    for (std::size_t p : chosen_) {
      const GroupPatch& g = patch(p);
      if (g.fitPoints.empty()) continue;
      double sum = 0.0;
      for (const Vec3& q : g.fitPoints) sum += boxSurfaceDistance(q, r);
      weighted += g.support * sum / static_cast<double>(g.fitPoints.size());
      weight += g.support;
    }
    if (weight > 0.0 && weighted / weight > ctx_.voxel) {
      ++stats_.rejectedFit;
      return;
    }
    Hypothesis h;
    h.ranges = r;
    h.patches = chosen_;
    std::sort(h.patches.begin(), h.patches.end());
    for (std::size_t p : chosen_) h.support += patch(p).support;
    h.tool = tool;
    h.order = passed_.size();
    passed_.push_back(std::move(h));
  }

  // Filter 3: of boxes that are the same within tolerance, one whose patch
  // set contains, or is contained in, a kept one's is redundant. The best
  // supported (then the one with more patches) is kept first.
  std::vector<Hypothesis> removeRedundant() {
    std::sort(passed_.begin(), passed_.end(), [](const Hypothesis& a, const Hypothesis& b) {
      if (a.support != b.support) return a.support > b.support;
      if (a.patches.size() != b.patches.size()) return a.patches.size() > b.patches.size();
      return a.order < b.order;
    });
    const double tol = ctx_.lengthTol;
    auto sameBox = [tol](const Hypothesis& a, const Hypothesis& b) {
      for (std::size_t k = 0; k < 3; ++k) {
        if (std::abs(a.ranges[k].lo - b.ranges[k].lo) > tol ||
            std::abs(a.ranges[k].hi - b.ranges[k].hi) > tol) {
          return false;
        }
      }
      return true;
    };
    auto nested = [](const Hypothesis& a, const Hypothesis& b) {
      return std::includes(a.patches.begin(), a.patches.end(), b.patches.begin(),
                           b.patches.end()) ||
             std::includes(b.patches.begin(), b.patches.end(), a.patches.begin(), a.patches.end());
    };
    std::vector<Hypothesis> kept;
    ToleranceGrid grid(6, tol);
    for (Hypothesis& h : passed_) {
      const std::array<double, 6> key{h.ranges[0].lo, h.ranges[0].hi, h.ranges[1].lo,
                                      h.ranges[1].hi, h.ranges[2].lo, h.ranges[2].hi};
      const bool redundant =
          grid.any(key, [&](std::size_t k) { return sameBox(h, kept[k]) && nested(h, kept[k]); });
      if (redundant) {
        ++stats_.rejectedRedundant;
      } else {
        grid.insert(key, kept.size());
        kept.push_back(std::move(h));
      }
    }
    return kept;
  }

  const Context& ctx_;
  CuboidStats& stats_;
  const std::vector<PlanePatch>& planes_;
  std::vector<GroupPatch> patches_;
  std::vector<GroupPatch> others_;
  std::size_t& budgetUsed_;
  std::array<std::vector<std::size_t>, 6> dirs_;  // +e0, -e0, +e1, -e1, +e2, -e2
  std::array<std::size_t, 7> below_{};
  std::vector<std::size_t> chosen_;
  std::vector<Hypothesis> passed_;
  bool stop_ = false;
};

// Plane patches, best supported first.
std::vector<PlanePatch> planePatches(const Context& ctx) {
  std::vector<PlanePatch> patches;
  for (const PlaneRef& ref : planeSurfaces(ctx)) {
    const PlaneSurface* pl = ref.plane;
    PlanePatch p;
    p.surface = static_cast<int>(ref.index);
    p.normal = pl->normal.normalized();
    p.points = inlierPoints(ctx.scan, *ref.surface);
    p.centroid = Vec3::Zero();
    for (const Vec3& q : p.points) p.centroid += q;
    p.centroid /= static_cast<double>(p.points.size());
    // The centroid moved onto the fitted plane: the patch plane is exact.
    p.centroid -= (p.normal.dot(p.centroid) - pl->offset / pl->normal.norm()) * p.normal;
    p.support = static_cast<double>(p.points.size());
    p.sigma = ref.surface->rms;
    patches.push_back(std::move(p));
  }
  std::stable_sort(patches.begin(), patches.end(),
                   [](const PlanePatch& a, const PlanePatch& b) { return a.support > b.support; });
  return patches;
}

// Direction sets: a patch joins the first set whose direction is parallel.
std::vector<DirectionSet> directionSets(const std::vector<PlanePatch>& patches,
                                        double cosParallel) {
  std::vector<DirectionSet> sets;
  for (std::size_t i = 0; i < patches.size(); ++i) {
    auto it = std::find_if(sets.begin(), sets.end(), [&](const DirectionSet& set) {
      return std::abs(set.direction.dot(patches[i].normal)) >= cosParallel;
    });
    if (it == sets.end()) {
      sets.push_back({patches[i].normal, {}, 0.0});
      it = sets.end() - 1;
    }
    it->patches.push_back(i);
    it->support += patches[i].support;
  }
  return sets;
}

// Graph: an edge between orthogonal sets; cut into triangles, then edges,
// then single nodes, each time taking the best supported first. Returns the
// groups of sets, best supported first, so that a capped enumeration spends
// its budget where the evidence is.
std::vector<std::vector<std::size_t>> orthogonalGroups(const std::vector<DirectionSet>& sets,
                                                       double sinOrthogonal, CuboidStats& stats) {
  const std::size_t m = sets.size();
  auto orthogonal = [&](std::size_t a, std::size_t b) {
    return std::abs(sets[a].direction.dot(sets[b].direction)) <= sinOrthogonal;
  };
  auto supportOf = [&](const auto& nodes) {
    double s = 0.0;
    for (std::size_t n : nodes) s += sets[n].support;
    return s;
  };
  std::vector<std::vector<std::size_t>> groups;
  std::vector<char> used(m, 0);
  std::vector<std::array<std::size_t, 3>> triangles;
  for (std::size_t a = 0; a < m; ++a) {
    for (std::size_t b = a + 1; b < m; ++b) {
      if (!orthogonal(a, b)) continue;
      for (std::size_t c = b + 1; c < m; ++c) {
        if (orthogonal(a, c) && orthogonal(b, c)) triangles.push_back({a, b, c});
      }
    }
  }
  std::stable_sort(triangles.begin(), triangles.end(),
                   [&](const auto& x, const auto& y) { return supportOf(x) > supportOf(y); });
  for (const auto& t : triangles) {
    if (used[t[0]] || used[t[1]] || used[t[2]]) continue;
    used[t[0]] = used[t[1]] = used[t[2]] = 1;
    groups.push_back({t[0], t[1], t[2]});
    ++stats.triangleGroups;
  }
  std::vector<std::array<std::size_t, 2>> edges;
  for (std::size_t a = 0; a < m; ++a) {
    for (std::size_t b = a + 1; b < m; ++b) {
      if (!used[a] && !used[b] && orthogonal(a, b)) edges.push_back({a, b});
    }
  }
  std::stable_sort(edges.begin(), edges.end(),
                   [&](const auto& x, const auto& y) { return supportOf(x) > supportOf(y); });
  for (const auto& e : edges) {
    if (used[e[0]] || used[e[1]]) continue;
    used[e[0]] = used[e[1]] = 1;
    groups.push_back({e[0], e[1]});
    ++stats.edgeGroups;
  }
  for (std::size_t a = 0; a < m; ++a) {
    if (!used[a]) {
      groups.push_back({a});
      ++stats.singleGroups;
    }
  }
  std::stable_sort(groups.begin(), groups.end(),
                   [&](const auto& x, const auto& y) { return supportOf(x) > supportOf(y); });
  return groups;
}

// Patch `pi` in a group's frame: the frame axis nearest its normal, its
// side, its plane and its robust extents along the frame's axes, and the
// points (in frame coordinates) its faces are fitted to.
GroupPatch groupPatch(const Context& ctx, const std::vector<PlanePatch>& patches, std::size_t pi,
                      const Mat3& frame) {
  const PlanePatch& p = patches[pi];
  GroupPatch g;
  g.patch = pi;
  for (std::size_t k = 1; k < 3; ++k) {
    if (std::abs(p.normal.dot(frame.col(static_cast<Eigen::Index>(k)))) >
        std::abs(p.normal.dot(frame.col(static_cast<Eigen::Index>(g.axis))))) {
      g.axis = k;
    }
  }
  const Vec3 axis = frame.col(static_cast<Eigen::Index>(g.axis));
  g.sign = p.normal.dot(axis) > 0.0 ? 1 : -1;
  g.plane = p.centroid.dot(axis);
  for (std::size_t k = 0; k < 3; ++k) {
    std::vector<double> t;
    t.reserve(p.points.size());
    for (const Vec3& q : p.points) t.push_back(q.dot(frame.col(static_cast<Eigen::Index>(k))));
    g.range[k] = robustRange(std::move(t), p.sigma);
  }
  g.range[g.axis] = {g.plane, g.plane};
  g.support = p.support;
  const std::size_t samples = std::max<std::size_t>(1, ctx.options.fitSamples);
  const std::size_t step = std::max<std::size_t>(1, (p.points.size() + samples - 1) / samples);
  for (std::size_t i = 0; i < p.points.size(); i += step) {
    g.fitPoints.push_back(frame.transpose() * p.points[i]);
  }
  return g;
}

}  // namespace

std::vector<Candidate> cuboidCandidates(const Context& ctx, CuboidStats& stats,
                                        std::vector<char>& planeInCuboid) {
  const std::vector<PlanePatch> patches = planePatches(ctx);
  stats.planes = patches.size();
  const std::vector<DirectionSet> sets = directionSets(patches, ctx.cosParallel);
  stats.directionSets = sets.size();
  const std::vector<std::vector<std::size_t>> groups =
      orthogonalGroups(sets, ctx.sinOrthogonal, stats);

  std::vector<Candidate> out;
  std::size_t budgetUsed = 0;
  for (const std::vector<std::size_t>& group : groups) {
    // Eq. 2: the group's frame from its sets' directions (the best supported
    // first); a single set takes v* from its best patch's minimum rectangle.
    const Mat3 frame =
        group.size() >= 2 ? frameFrom(sets[group[0]].direction, sets[group[1]].direction)
                          : frameFrom(sets[group[0]].direction,
                                      longerRectangleSide(patches[sets[group[0]].patches.front()]));
    std::vector<GroupPatch> local, others;
    for (std::size_t node : group) {
      for (std::size_t pi : sets[node].patches)
        local.push_back(groupPatch(ctx, patches, pi, frame));
    }
    for (std::size_t node = 0; node < sets.size(); ++node) {
      if (std::find(group.begin(), group.end(), node) != group.end()) continue;
      for (int k = 0; k < 3; ++k) {
        if (std::abs(sets[node].direction.dot(frame.col(k))) < ctx.cosParallel) continue;
        for (std::size_t pi : sets[node].patches)
          others.push_back(groupPatch(ctx, patches, pi, frame));
      }
    }
    GroupEnumerator enumerator(ctx, stats, patches, std::move(local), std::move(others),
                               budgetUsed);
    for (const Hypothesis& h : enumerator.run()) {
      Candidate c;
      c.tree = CsgTree::leaf(boxFromRanges(frame, h.ranges));
      c.origin = CandidateOrigin::Cuboid;
      for (std::size_t gp : h.patches)
        c.surfaces.push_back(patches[enumerator.patch(gp).patch].surface);
      std::sort(c.surfaces.begin(), c.surfaces.end());
      c.support = h.support;
      c.tool = h.tool;
      if (c.surfaces.size() >= 2) {
        for (int s : c.surfaces) planeInCuboid[static_cast<std::size_t>(s)] = 1;
      }
      ++stats.kept;
      stats.keptTool += h.tool ? 1 : 0;
      out.push_back(std::move(c));
    }
  }
  return out;
}

}  // namespace csgvox::hypotheses_detail
