#include "optimize/csg_construction.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <map>
#include <numbers>

namespace csgvox {
namespace {

// One operand of the final union: a root candidate with its truncation.
struct Member {
  std::uint32_t root = 0;
  std::vector<SubtreeAction> actions;
  VoxelSet voxels;
};

VoxelSet memberVoxels(const Member& m, std::span<const DescriptionSet> d,
                      std::size_t skipAction = std::size_t(-1)) {
  VoxelSet v = d[m.root].voxels;
  for (std::size_t a = 0; a < m.actions.size(); ++a) {
    if (a == skipAction) continue;
    const VoxelSet& tool = d[m.actions[a].primitive].voxels;
    if (m.actions[a].subtract) {
      v.subtract(tool);
    } else {
      v &= tool;
    }
  }
  return v;
}

VoxelSet unionVoxels(const std::vector<Member>& members, std::size_t size,
                     std::size_t skip = std::size_t(-1)) {
  VoxelSet v(size);
  for (std::size_t i = 0; i < members.size(); ++i) {
    if (i != skip) v |= members[i].voxels;
  }
  return v;
}

// Corners of a solid's bounds: exact support points for a box, conservative
// ones otherwise.
std::vector<Vec3> supportCorners(const CsgTree& solid) {
  std::vector<Vec3> corners;
  const Node& root = *solid.root();
  if (root.kind == NodeKind::Primitive) {
    if (const Box* b = root.primitive.as<Box>()) {
      for (int c = 0; c < 8; ++c) {
        const Vec3 s((c & 1) ? 1 : -1, (c & 2) ? 1 : -1, (c & 4) ? 1 : -1);
        corners.push_back(b->center + b->axes * s.cwiseProduct(b->halfSize));
      }
      return corners;
    }
  }
  const Aabb a = solid.bounds();
  if (!a.isBounded()) return corners;
  for (int c = 0; c < 8; ++c) {
    corners.emplace_back((c & 1) ? a.max.x() : a.min.x(), (c & 2) ? a.max.y() : a.min.y(),
                         (c & 4) ? a.max.z() : a.min.z());
  }
  return corners;
}

// A subtracted box whose faces stop just short of the root's outer
// boundary is grown through it (see ConstructOptions::snapDistance).
// A skin's outer face that holds scan points is a real wall thinner than a
// voxel, not an artefact: true when most probes (points on that face) have
// a scan point near them.
bool scanned(const ScannedAt& scannedAt, const std::vector<Vec3>& probes) {
  if (!scannedAt || probes.empty()) return false;
  std::size_t hits = 0;
  for (const Vec3& p : probes) hits += scannedAt(p) ? 1 : 0;
  return 2 * hits > probes.size();
}

// The centre of a face and four points a quarter of the way to its rim,
// along u and v: far enough from the rim that a hole's cap has no scan
// point near them, spread enough that one gap in a scanned wall's sampling
// does not decide.
std::vector<Vec3> innerProbes(const Vec3& centre, const Vec3& u, const Vec3& v) {
  return {centre, centre + 0.25 * u, centre - 0.25 * u, centre + 0.25 * v, centre - 0.25 * v};
}

CsgTree throughCut(const CsgTree& tool, const CsgTree& root, double snap,
                   const ScannedAt& scannedAt) {
  if (snap <= 0.0 || tool.root()->kind != NodeKind::Primitive) return tool;
  const Box* b = tool.root()->primitive.as<Box>();
  const std::vector<Vec3> corners = supportCorners(root);
  if (!b || corners.empty()) return tool;
  Box grown = *b;
  bool changed = false;
  for (int axis = 0; axis < 3; ++axis) {
    for (double sign : {-1.0, 1.0}) {
      const Vec3 dir = sign * b->axes.col(axis);
      const double face = dir.dot(b->center) + b->halfSize[axis];
      double reach = -1e300;
      for (const Vec3& c : corners) reach = std::max(reach, dir.dot(c));
      if (face <= reach && reach - face <= snap) {
        const int u = (axis + 1) % 3, v = (axis + 2) % 3;
        const Vec3 outer = b->center + (b->halfSize[axis] + reach - face) * dir;
        if (scanned(scannedAt, innerProbes(outer, b->halfSize[u] * b->axes.col(u),
                                           b->halfSize[v] * b->axes.col(v)))) {
          continue;
        }
        const double extra = reach - face + 2.0 * snap;
        grown.center += 0.5 * extra * dir;
        grown.halfSize[axis] += 0.5 * extra;
        changed = true;
      }
    }
  }
  return changed ? CsgTree::leaf(grown, tool.root()->name) : tool;
}

// How far past `from` along `dir` the solid ends, when it ends within
// `snap` (and holds `from`); -1 otherwise.
double exitWithin(const CsgTree& solid, const Vec3& from, const Vec3& dir, double snap) {
  if (solid.value(from) < 0.0) return -1.0;
  constexpr int kSteps = 16;
  for (int k = 1; k <= kSteps; ++k) {
    const double s = snap * k / kSteps;
    if (solid.value(from + s * dir) < 0.0) return s;
  }
  return -1.0;
}

// The centre of a disc (radius vectors u and v) and eight points at 0.95 of
// its radius.
std::vector<Vec3> discSamples(const Vec3& centre, const Vec3& u, const Vec3& v) {
  std::vector<Vec3> out{centre};
  for (int k = 0; k < 8; ++k) {
    const double a = k * std::numbers::pi / 4.0;
    out.push_back(centre + 0.95 * (std::cos(a) * u + std::sin(a) * v));
  }
  return out;
}

// A 3 x 3 grid over a rectangle (half extents u and v), reaching 0.95 of them.
std::vector<Vec3> rectangleSamples(const Vec3& centre, const Vec3& u, const Vec3& v) {
  std::vector<Vec3> out;
  for (int k = 0; k < 9; ++k) {
    out.push_back(centre + 0.95 * ((k % 3) - 1) * u + 0.95 * ((k / 3) - 1) * v);
  }
  return out;
}

// A subtracted box, cylinder or cone whose end face stops within `snap` of
// where the cut solid ends (along the face's normal) leaves a skin thinner
// than voxels can see: a hole that should go through a shaft stops short of
// its curved surface, and OpenSCAD then renders a closed cavity. Returns how
// far to move the face (centre `face`, outward `dir`, half extents u and v
// across it, `samples` on it): one `snap` past the farthest exit over the
// samples. -1 when the solid does not end within `snap` at every sample, or
// when the skin's outer face holds scan points (a real thin wall).
double pushThrough(const CsgTree& solid, const Vec3& face, const Vec3& dir, const Vec3& u,
                   const Vec3& v, const std::vector<Vec3>& samples, double snap,
                   const ScannedAt& scannedAt) {
  double reach = -1.0;
  for (const Vec3& p : samples) {
    const double e = exitWithin(solid, p, dir, snap);
    if (e < 0.0) return -1.0;
    reach = std::max(reach, e);
  }
  const std::vector<Vec3> probes = innerProbes(face, u, v);
  std::vector<Vec3> outer;
  for (const Vec3& p : probes) {
    const double e = exitWithin(solid, p, dir, snap);
    if (e >= 0.0) outer.push_back(p + e * dir);
  }
  if (2 * outer.size() > probes.size() && scanned(scannedAt, outer)) return -1.0;
  return reach + snap;
}

// The tool with every face that stops in a skin of `solid` pushed through it
// (see pushThrough).
CsgTree throughSkin(const CsgTree& tool, const CsgTree& solid, double snap,
                    const ScannedAt& scannedAt) {
  if (snap <= 0.0 || tool.root()->kind != NodeKind::Primitive) return tool;
  const Primitive& prim = tool.root()->primitive;
  bool changed = false;
  if (const Cylinder* c = prim.as<Cylinder>()) {
    const Mat3 frame = frameFromAxis(c->axis);
    const Vec3 u = c->radius * frame.col(0), v = c->radius * frame.col(1);
    Cylinder grown = *c;
    for (const double sign : {-1.0, 1.0}) {
      const Vec3 dir = sign * c->axis;
      const Vec3 face = c->center + 0.5 * c->height * dir;
      const double extra =
          pushThrough(solid, face, dir, u, v, discSamples(face, u, v), snap, scannedAt);
      if (extra < 0.0) continue;
      grown.center += 0.5 * extra * dir;
      grown.height += extra;
      changed = true;
    }
    return changed ? CsgTree::leaf(grown, tool.root()->name) : tool;
  }
  if (const Cone* c = prim.as<Cone>()) {
    const Mat3 frame = frameFromAxis(c->axis);
    const double slope = (c->radiusTop - c->radiusBottom) / c->height;
    Cone grown = *c;
    for (const double sign : {-1.0, 1.0}) {
      const Vec3 dir = sign * c->axis;
      const Vec3 face = c->center + 0.5 * c->height * dir;
      const double radius = sign > 0.0 ? c->radiusTop : c->radiusBottom;
      const Vec3 u = radius * frame.col(0), v = radius * frame.col(1);
      const double extra =
          pushThrough(solid, face, dir, u, v, discSamples(face, u, v), snap, scannedAt);
      if (extra < 0.0) continue;
      // The frustum runs on along its own slope.
      if (sign > 0.0) {
        grown.radiusTop += slope * extra;
      } else {
        grown.radiusBottom = std::max(0.0, grown.radiusBottom - slope * extra);
      }
      grown.center += 0.5 * extra * dir;
      grown.height += extra;
      changed = true;
    }
    return changed ? CsgTree::leaf(grown, tool.root()->name) : tool;
  }
  if (const Box* b = prim.as<Box>()) {
    Box grown = *b;
    for (int axis = 0; axis < 3; ++axis) {
      const Vec3 u = b->halfSize[(axis + 1) % 3] * b->axes.col((axis + 1) % 3);
      const Vec3 v = b->halfSize[(axis + 2) % 3] * b->axes.col((axis + 2) % 3);
      for (const double sign : {-1.0, 1.0}) {
        const Vec3 dir = sign * b->axes.col(axis);
        const Vec3 face = b->center + b->halfSize[axis] * dir;
        const double extra =
            pushThrough(solid, face, dir, u, v, rectangleSamples(face, u, v), snap, scannedAt);
        if (extra < 0.0) continue;
        grown.center += 0.5 * extra * dir;
        grown.halfSize[axis] += 0.5 * extra;
        changed = true;
      }
    }
    return changed ? CsgTree::leaf(grown, tool.root()->name) : tool;
  }
  return tool;
}

CsgTree memberTree(const Member& m, std::span<const CsgTree> candidates, double snap,
                   const ScannedAt& scannedAt) {
  std::vector<CsgTree> inter{candidates[m.root]};
  std::vector<CsgTree> sub;
  for (const SubtreeAction& a : m.actions) {
    if (a.subtract) {
      sub.push_back(throughCut(candidates[a.primitive], candidates[m.root], snap, scannedAt));
    } else {
      inter.push_back(candidates[a.primitive]);
    }
  }
  CsgTree t = inter.size() == 1 ? inter.front() : CsgTree::intersect(inter);
  if (sub.empty()) return t;
  for (CsgTree& tool : sub) tool = throughSkin(tool, t, snap, scannedAt);
  sub.insert(sub.begin(), t);
  return CsgTree::subtract(sub);
}

// Primitives a member puts in the tree.
std::size_t memberPrimitives(const Member& m) { return 1 + m.actions.size(); }

// Energy of a whole union for the final local search: `cost` voxels per
// primitive plus every voxel where the union and the labels disagree. It is
// Eq. 4 and Eq. 6 made global: an action or member pays for itself when it
// corrects about `cost` voxels, the same rule as minFeatureVoxels.
double unionEnergy(const std::vector<Member>& members, const VoxelSet& inside, double cost) {
  VoxelSet u(inside.size());
  std::size_t prims = 0;
  for (const Member& m : members) {
    u |= m.voxels;
    prims += memberPrimitives(m);
  }
  const std::size_t disagree =
      VoxelSet::countAndNot(u, inside) + VoxelSet::countAndNot(inside, u);
  return cost * double(prims) + double(disagree);
}

// Removes members, one at a time, while that lowers the energy.
double pruneMembers(std::vector<Member>& members, const VoxelSet& inside, double cost,
                    double energy) {
  for (bool improved = true; improved && members.size() > 1;) {
    improved = false;
    for (std::size_t i = 0; i < members.size(); ++i) {
      std::vector<Member> trial = members;
      trial.erase(trial.begin() + long(i));
      const double e = unionEnergy(trial, inside, cost);
      if (e < energy - 1e-9) {
        members = std::move(trial);
        energy = e;
        improved = true;
        break;
      }
    }
  }
  return energy;
}

// Phase 1 builds each subtree for its own root against its own neighbours
// and phase 2 then picks members independently among the subtrees free of
// outside voxels. So a root that cut too much gets its loss covered by
// extra members, a subtree a few mislabelled voxels short of clean is never
// offered, and an action that only pays for the union as a whole (a chamfer
// cone cutting a boss that another member's fillet meets) is never tried.
// This local search over the whole union repairs all three with five
// moves, each followed by pruning the members that no longer pay: drop one
// action of a member; add one of `extra` (every subtree phase 1 built,
// clean or not, and every bare candidate) as a member; add one candidate to
// a member as an intersection or a subtraction, or put one in place of an
// action's candidate (the best such move of each round). A move is kept when the global energy falls, so the search ends.
void refineUnion(std::vector<Member>& members, const std::vector<Member>& extra,
                 std::span<const DescriptionSet> d, const VoxelSet& inside, double cost) {
  const std::size_t insideCount = inside.count();
  double energy = unionEnergy(members, inside, cost);
  energy = pruneMembers(members, inside, cost, energy);
  const auto tryMove = [&](std::vector<Member>& trial) {
    double e = unionEnergy(trial, inside, cost);
    e = pruneMembers(trial, inside, cost, e);
    if (e < energy - 1e-9) {
      members = std::move(trial);
      energy = e;
      return true;
    }
    return false;
  };
  for (bool improved = true; improved;) {
    improved = false;
    for (std::size_t i = 0; i < members.size() && !improved; ++i) {
      for (std::size_t a = 0; a < members[i].actions.size() && !improved; ++a) {
        std::vector<Member> trial = members;
        Member& m = trial[i];
        m.actions.erase(m.actions.begin() + long(a));
        m.voxels = memberVoxels(m, d);
        improved = tryMove(trial);
      }
    }
    for (std::size_t k = 0; k < extra.size() && !improved; ++k) {
      const bool present = std::any_of(members.begin(), members.end(), [&](const Member& m) {
        return m.root == extra[k].root && m.actions == extra[k].actions;
      });
      if (present || VoxelSet::countAnd(extra[k].voxels, inside) == 0) continue;
      std::vector<Member> trial = members;
      trial.push_back(extra[k]);
      improved = tryMove(trial);
    }
    if (improved) continue;
    // The best new or replaced action over all members and candidates.
    std::size_t prims = 0;
    for (const Member& m : members) prims += memberPrimitives(m);
    double bestEnergy = energy - 1e-9;
    std::size_t bestMember = 0;
    std::size_t bestSlot = std::size_t(-1);  // -1: a new action, else the action replaced
    SubtreeAction bestAction;
    bool found = false;
    for (std::size_t i = 0; i < members.size(); ++i) {
      const Member& m = members[i];
      VoxelSet rest(inside.size());
      for (std::size_t j = 0; j < members.size(); ++j) {
        if (j != i) rest |= members[j].voxels;
      }
      // Tries `base` (the member's voxels without the changed slot) cut by
      // candidate k, as the action in `slot`, with `count` primitives.
      const auto tryAction = [&](const VoxelSet& base, std::size_t slot, std::uint32_t k,
                                 bool subtract, std::size_t count) {
        VoxelSet v = subtract ? base - d[k].voxels : base & d[k].voxels;
        v |= rest;
        const double e = cost * double(count) + double(v.count() + insideCount) -
                         2.0 * double(VoxelSet::countAnd(v, inside));
        if (e < bestEnergy) {
          bestEnergy = e;
          bestMember = i;
          bestSlot = slot;
          bestAction = SubtreeAction{k, subtract};
          found = true;
        }
      };
      for (std::uint32_t k = 0; k < d.size(); ++k) {
        if (k == m.root || !VoxelSet::intersects(d[k].voxels, m.voxels)) continue;
        for (const bool subtract : {true, false}) {
          tryAction(m.voxels, std::size_t(-1), k, subtract, prims + 1);
        }
      }
      // Or the best replacement of one action's candidate by another, with
      // the same operation (a better fit of the same surface).
      for (std::size_t a = 0; a < m.actions.size(); ++a) {
        const SubtreeAction old = m.actions[a];
        const VoxelSet without = memberVoxels(m, d, a);
        for (std::uint32_t k = 0; k < d.size(); ++k) {
          if (k == old.primitive || k == m.root || !VoxelSet::intersects(d[k].voxels, without)) {
            continue;
          }
          tryAction(without, a, k, old.subtract, prims);
        }
      }
    }
    if (found) {
      std::vector<Member> trial = members;
      Member& m = trial[bestMember];
      if (bestSlot == std::size_t(-1)) {
        m.actions.push_back(bestAction);
      } else {
        m.actions[bestSlot] = bestAction;
      }
      m.voxels = memberVoxels(m, d);
      improved = tryMove(trial);
    }
  }
}

// Removes truncation actions and union members that change no voxel.
void dropNoOps(std::vector<Member>& members, std::span<const DescriptionSet> d, std::size_t size) {
  for (Member& m : members) {
    for (std::size_t a = m.actions.size(); a-- > 0;) {
      if (memberVoxels(m, d, a) == m.voxels) m.actions.erase(m.actions.begin() + long(a));
    }
  }
  const VoxelSet all = unionVoxels(members, size);
  // Try the smallest members first: they are the likeliest to be covered.
  std::vector<std::size_t> order(members.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return members[a].voxels.count() < members[b].voxels.count();
  });
  std::vector<char> gone(members.size(), 0);
  for (std::size_t i : order) {
    VoxelSet rest(size);
    for (std::size_t j = 0; j < members.size(); ++j) {
      if (j != i && !gone[j]) rest |= members[j].voxels;
    }
    if (rest == all) gone[i] = 1;
  }
  std::vector<Member> kept;
  for (std::size_t i = 0; i < members.size(); ++i) {
    if (!gone[i]) kept.push_back(std::move(members[i]));
  }
  members = std::move(kept);
}

}  // namespace

Construction constructCsg(std::span<const CsgTree> candidates,
                          std::span<const DescriptionSet> d, const VoxelSet& inside,
                          const ConstructOptions& options, const ProgressCallback& progress) {
  Construction out;
  const std::size_t n = candidates.size();
  const std::size_t size = inside.size();
  out.stats.candidates = n;
  out.voxels = VoxelSet(size);
  const auto clean = [&](std::size_t outside, std::size_t all) {
    return double(outside) <= options.outsideTolerance * double(all);
  };
  // Roots (Wu §4.1).
  std::vector<std::uint32_t> usable, truncate;
  for (std::uint32_t i = 0; i < n; ++i) {
    if (d[i].plus == 0 || d[i].exceedsGrid) continue;
    (clean(d[i].minus, d[i].voxels.count()) ? usable : truncate).push_back(i);
  }
  std::vector<VoxelSet> usablePlus;
  for (std::uint32_t i : usable) usablePlus.push_back(d[i].voxels & inside);
  std::erase_if(truncate, [&](std::uint32_t i) {
    const VoxelSet plus = d[i].voxels & inside;
    return std::any_of(usablePlus.begin(), usablePlus.end(),
                       [&](const VoxelSet& p) { return p == plus; });
  });
  out.stats.usableRoots = usable.size();
  out.stats.truncationRoots = truncate.size();

  // Phase 1: a subtree per truncation root, in parallel.
  std::vector<SubtreeResult> subtrees(truncate.size());
  std::atomic<std::size_t> done{0};
  std::atomic<bool> cancelled{false};
  tbb::parallel_for(std::size_t(0), truncate.size(), [&](std::size_t r) {
    if (cancelled) return;
    const std::uint32_t j = truncate[r];
    std::vector<const VoxelSet*> nb;
    std::vector<std::uint32_t> ids;
    for (std::uint32_t k = 0; k < n; ++k) {
      if (k != j && VoxelSet::intersects(d[k].voxels, d[j].voxels)) {
        nb.push_back(&d[k].voxels);
        ids.push_back(k);
      }
    }
    subtrees[r] = selectSubtree(d[j].voxels, inside, nb, ids, options.subtree);
    const std::size_t finished = ++done;
    if (progress && !progress(0.9 * double(finished) / double(truncate.size()), "subtrees")) {
      cancelled = true;
    }
  });

  // Phase 2 candidates: usable primitives and subtrees without outside voxels.
  std::vector<Member> pool;
  for (std::uint32_t i : usable) pool.push_back(Member{i, {}, d[i].voxels});
  for (std::size_t r = 0; r < truncate.size(); ++r) {
    if (!out.stats.provedOptimal || !subtrees[r].provedOptimal) out.stats.provedOptimal = false;
    const VoxelSet& v = subtrees[r].voxels;
    if (v.none() || !clean(VoxelSet::countAndNot(v, inside), v.count())) continue;
    pool.push_back(Member{truncate[r], subtrees[r].actions, v});
    ++out.stats.subtrees;
  }
  out.stats.unionCandidates = pool.size();
  std::vector<const VoxelSet*> sets;
  for (const Member& m : pool) sets.push_back(&m.voxels);
  const UnionResult u = selectUnion(inside, sets, options.unionChoice);
  if (!u.provedOptimal) out.stats.provedOptimal = false;
  std::vector<Member> members;
  for (std::uint32_t i : u.chosen) members.push_back(pool[i]);
  if (progress) progress(0.95, "union");

  if (options.refine) {
    std::vector<Member> extra;
    for (std::uint32_t i = 0; i < n; ++i) {
      if (d[i].plus > 0 && !d[i].exceedsGrid) extra.push_back(Member{i, {}, d[i].voxels});
    }
    for (std::size_t r = 0; r < truncate.size(); ++r) {
      if (!subtrees[r].voxels.none()) {
        extra.push_back(Member{truncate[r], subtrees[r].actions, subtrees[r].voxels});
      }
    }
    refineUnion(members, extra, d, inside, std::max(options.unionChoice.minFeatureVoxels, 1.0));
  }
  if (options.simplify) dropNoOps(members, d, size);
  out.stats.chosen = members.size();
  out.voxels = unionVoxels(members, size);
  if (members.empty()) return out;

  // Subtractions shared by several members are applied once to the union
  // when that leaves the voxels unchanged.
  std::vector<std::uint32_t> lifted;
  if (options.simplify) {
    std::map<std::uint32_t, int> uses;
    for (const Member& m : members) {
      for (const SubtreeAction& a : m.actions) uses[a.primitive] += a.subtract ? 1 : 0;
    }
    for (const auto& [prim, count] : uses) {
      if (count < 2) continue;
      std::vector<Member> trial = members;
      for (Member& m : trial) {
        std::erase_if(m.actions, [&](const SubtreeAction& a) {
          return a.subtract && a.primitive == prim;
        });
        m.voxels = memberVoxels(m, d);
      }
      VoxelSet v = unionVoxels(trial, size);
      for (std::uint32_t l : lifted) v.subtract(d[l].voxels);
      v.subtract(d[prim].voxels);
      if (v == out.voxels) {
        members = std::move(trial);
        lifted.push_back(prim);
      }
    }
  }
  std::vector<CsgTree> parts;
  for (const Member& m : members) {
    parts.push_back(memberTree(m, candidates, options.snapDistance, options.scannedAt));
  }
  CsgTree tree = parts.size() == 1 ? parts.front() : CsgTree::unite(parts);
  if (!lifted.empty()) {
    std::vector<CsgTree> ops{tree};
    for (std::uint32_t l : lifted) {
      ops.push_back(throughSkin(candidates[l], tree, options.snapDistance, options.scannedAt));
    }
    tree = CsgTree::subtract(ops);
  }
  out.tree = tree;
  if (progress) progress(1.0, "union");
  return out;
}

}  // namespace csgvox
