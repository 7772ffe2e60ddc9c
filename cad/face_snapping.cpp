#include "cad/face_snapping.h"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <span>
#include <stdexcept>
#include <unordered_map>
#include <utility>
#include <vector>

namespace csgvox {
namespace {

// Directions closer than the angle to one seen before take its value (with
// its sign flipped when they point the other way); a coordinate axis that
// close is preferred as the first of its group.
class DirectionSnapper {
 public:
  explicit DirectionSnapper(double angle) : cosine_(std::cos(angle)) {}

  // The direction's group and the sign relating it to the group's
  // direction; `d` is replaced by the snapped direction.
  std::pair<std::size_t, double> snap(Vec3& d, std::size_t& turned) {
    for (std::size_t i = 0; i < groups_.size(); ++i) {
      const double c = d.dot(groups_[i]);
      if (std::abs(c) >= cosine_) return replace(d, i, c < 0.0 ? -1.0 : 1.0, turned);
    }
    Vec3 g = d;
    for (int k = 0; k < 3; ++k) {
      if (std::abs(d[k]) >= cosine_) g = Vec3::Unit(k);
    }
    groups_.push_back(g);
    return replace(d, groups_.size() - 1, d.dot(g) < 0.0 ? -1.0 : 1.0, turned);
  }

  const Vec3& group(std::size_t i) const { return groups_[i]; }

 private:
  std::pair<std::size_t, double> replace(Vec3& d, std::size_t i, double sign, std::size_t& turned) {
    const Vec3 snapped = sign * groups_[i];
    if (snapped != d) ++turned;
    d = snapped;
    return {i, sign};
  }

  double cosine_;
  std::vector<Vec3> groups_;
};

// The rotation nearest to the axes (kept when they already are one, as
// snapped coordinate axes are).
Mat3 nearestRotation(const Mat3& axes) {
  if ((axes.transpose() * axes - Mat3::Identity()).cwiseAbs().maxCoeff() <= 1e-15) return axes;
  const Eigen::JacobiSVD<Mat3> svd(axes, Eigen::ComputeFullU | Eigen::ComputeFullV);
  return svd.matrixU() * svd.matrixV().transpose();
}

// One flat cap: the plane direction·x = offset, with direction the group's.
struct Cap {
  std::size_t leaf = 0;   // index into the leaves' primitives
  int slot = 0;           // which cap of the primitive (see capSlots)
  std::size_t group = 0;  // direction group
  double offset = 0.0;    // along the group's direction
  double snapped = 0.0;   // the offset it moves to
  double area = 0.0;      // the cap's area (infinite for the planes that stay)
};

// The slab a capped primitive spans along one of its directions: its low
// and high caps' offsets along that direction.
struct Slab {
  Vec3 direction;                        // the primitive's own (snapped) direction
  std::size_t group;                     // its direction group
  double sign;                           // direction = sign * group direction
  double low, high;                      // offsets along `direction`
  double lowArea = 0.0, highArea = 0.0;  // areas of the caps there
};

std::vector<Slab> slabs(const Primitive& p, DirectionSnapper& snapper, Primitive& snappedOut,
                        std::size_t& turned) {
  std::vector<Slab> out;
  auto slab = [&](Vec3& d, const Vec3& center, double half, double lowArea, double highArea,
                  std::size_t& count) {
    const auto [group, sign] = snapper.snap(d, count);
    const double mid = d.dot(center);
    out.push_back({d, group, sign, mid - half, mid + half, lowArea, highArea});
  };
  if (const auto* h = p.as<HalfSpace>()) {
    HalfSpace s = *h;
    const Vec3 onPlane = s.offset * s.normal;
    const auto [group, sign] = snapper.snap(s.normal, turned);
    s.offset = s.normal.dot(onPlane);
    const double inf = std::numeric_limits<double>::infinity();
    out.push_back({s.normal, group, sign, s.offset, s.offset, inf, inf});
    snappedOut = s;
  } else if (const auto* b = p.as<Box>()) {
    Box s = *b;
    for (int k = 0; k < 3; ++k) {
      Vec3 d = s.axes.col(k);
      snapper.snap(d, turned);
      s.axes.col(k) = d;
    }
    s.axes = nearestRotation(s.axes);
    std::size_t again = 0;  // the axes were counted above
    for (int k = 0; k < 3; ++k) {
      Vec3 d = s.axes.col(k);
      const double area = 4.0 * s.halfSize[(k + 1) % 3] * s.halfSize[(k + 2) % 3];
      slab(d, s.center, s.halfSize[k], area, area, again);
    }
    snappedOut = s;
  } else if (const auto* c = p.as<Cylinder>()) {
    Cylinder s = *c;
    const double area = std::numbers::pi * s.radius * s.radius;
    slab(s.axis, s.center, 0.5 * s.height, area, area, turned);
    snappedOut = s;
  } else if (const auto* c = p.as<Cone>()) {
    Cone s = *c;
    slab(s.axis, s.center, 0.5 * s.height, std::numbers::pi * s.radiusBottom * s.radiusBottom,
         std::numbers::pi * s.radiusTop * s.radiusTop, turned);
    snappedOut = s;
  } else if (const auto* t = p.as<Torus>()) {
    Torus s = *t;
    snapper.snap(s.axis, turned);
    snappedOut = s;
  } else {
    snappedOut = p;
  }
  return out;
}

// The primitive with its slabs' new low and high offsets.
Primitive withSlabs(const Primitive& p, const std::vector<Slab>& moved) {
  auto recentre = [](Vec3 center, const Slab& s) {
    return center + s.direction * (0.5 * (s.low + s.high) - s.direction.dot(center));
  };
  if (const auto* h = p.as<HalfSpace>()) return HalfSpace{h->normal, moved[0].high};
  if (const auto* b = p.as<Box>()) {
    Box s = *b;
    for (int k = 0; k < 3; ++k) {
      s.center = recentre(s.center, moved[k]);
      s.halfSize[k] = 0.5 * (moved[k].high - moved[k].low);
    }
    return s;
  }
  if (const auto* c = p.as<Cylinder>()) {
    Cylinder s = *c;
    s.center = recentre(s.center, moved[0]);
    s.height = moved[0].high - moved[0].low;
    return s;
  }
  if (const auto* c = p.as<Cone>()) {
    Cone s = *c;
    const double low = s.axis.dot(s.center) - 0.5 * s.height;
    const double slope = (s.radiusTop - s.radiusBottom) / s.height;
    s.radiusBottom = std::max(0.0, c->radiusBottom + slope * (moved[0].low - low));
    s.radiusTop = std::max(0.0, c->radiusBottom + slope * (moved[0].high - low));
    s.center = recentre(s.center, moved[0]);
    s.height = moved[0].high - moved[0].low;
    return s;
  }
  return p;
}

// The offset of a group of caps sorted by offset where half their area
// lies on either side: the largest faces stay put and the small ones come
// to them, which changes the volume least. A half-space's plane (infinite)
// or a torus's plane (infinite) outweighs every bounded cap.
double weightedMedian(std::span<const Cap> caps) {
  const bool plane =
      std::any_of(caps.begin(), caps.end(), [](const Cap& c) { return std::isinf(c.area); });
  auto weight = [&](const Cap& c) {
    if (plane) return std::isinf(c.area) ? 1.0 : 0.0;
    return std::max(c.area, 1e-300);
  };
  double total = 0.0;
  for (const Cap& c : caps) total += weight(c);
  double below = 0.0;
  for (const Cap& c : caps) {
    below += weight(c);
    if (below >= 0.5 * total) return c.offset;
  }
  return caps.back().offset;
}

}  // namespace

FaceSnapResult snapFaces(const CsgTree& tree, const FaceSnapOptions& options) {
  if (!(options.tolerance >= 0.0)) throw std::invalid_argument("snapFaces: negative tolerance");
  FaceSnapResult result;
  if (tree.empty()) return result;

  // Leaves once each (a shared leaf is one primitive), in tree order.
  std::vector<const Node*> leaves;
  std::unordered_map<const Node*, std::size_t> leafIndex;
  for (const Node* n : tree.leaves()) {
    if (leafIndex.emplace(n, leaves.size()).second) leaves.push_back(n);
  }

  DirectionSnapper snapper(options.angle);
  std::vector<Primitive> primitives(leaves.size());
  std::vector<std::vector<Slab>> leafSlabs(leaves.size());
  std::vector<Cap> caps;
  for (std::size_t i = 0; i < leaves.size(); ++i) {
    leafSlabs[i] = slabs(leaves[i]->primitive, snapper, primitives[i], result.turnedAxes);
    const bool halfSpace = primitives[i].type() == PrimitiveType::HalfSpace;
    for (std::size_t k = 0; k < leafSlabs[i].size(); ++k) {
      const Slab& s = leafSlabs[i][k];
      // Offsets along the group's direction: s.sign * (offset along s).
      caps.push_back({i, int(2 * k + 1), s.group, s.sign * s.high, 0.0, s.highArea});
      if (!halfSpace) caps.push_back({i, int(2 * k), s.group, s.sign * s.low, 0.0, s.lowArea});
    }
    // A torus (a fillet, mostly) stays, and caps near its equator's plane
    // (and, when asked, near the planes tangent to its tube) come to them:
    // a cap just off the equator leaves a sliver that ends where the tube
    // is tangent to a neighbouring cylinder, where OpenCASCADE misclassifies
    // faces.
    if (const auto* t = primitives[i].as<Torus>()) {
      Vec3 axis = t->axis;
      std::size_t again = 0;
      const auto [group, sign] = snapper.snap(axis, again);
      const double mid = sign * axis.dot(t->center);
      std::vector<double> planes;
      if (options.torusEquator) planes.push_back(mid);
      if (options.torusTangents) {
        planes.push_back(mid - t->minorRadius);
        planes.push_back(mid + t->minorRadius);
      }
      for (const double offset : planes) {
        caps.push_back({i, -1, group, offset, 0.0, std::numeric_limits<double>::infinity()});
      }
    }
  }

  // Groups of parallel caps within the tolerance of the group's first.
  std::sort(caps.begin(), caps.end(), [](const Cap& a, const Cap& b) {
    if (a.group != b.group) return a.group < b.group;
    if (a.offset != b.offset) return a.offset < b.offset;
    if (a.leaf != b.leaf) return a.leaf < b.leaf;
    return a.slot < b.slot;
  });
  for (std::size_t begin = 0; begin < caps.size();) {
    std::size_t end = begin + 1;
    while (end < caps.size() && caps[end].group == caps[begin].group &&
           caps[end].offset - caps[begin].offset <= options.tolerance) {
      ++end;
    }
    const double target = weightedMedian(std::span<const Cap>(caps).subspan(begin, end - begin));
    for (std::size_t i = begin; i < end; ++i) caps[i].snapped = target;
    begin = end;
  }

  // New slabs; a primitive whose slab would shrink below half keeps it.
  std::vector<std::vector<Slab>> moved = leafSlabs;
  for (const Cap& c : caps) {
    if (c.slot < 0) continue;  // a torus's plane
    Slab& s = moved[c.leaf][std::size_t(c.slot / 2)];
    const double value = s.sign * c.snapped;  // along the primitive's own direction
    if (primitives[c.leaf].type() == PrimitiveType::HalfSpace) {
      s.low = s.high = value;
    } else {
      (c.slot % 2 ? s.high : s.low) = value;
    }
  }
  for (std::size_t i = 0; i < leaves.size(); ++i) {
    bool changed = false;
    for (std::size_t k = 0; k < moved[i].size(); ++k) {
      const Slab& before = leafSlabs[i][k];
      Slab& after = moved[i][k];
      if (primitives[i].type() != PrimitiveType::HalfSpace &&
          after.high - after.low < 0.5 * (before.high - before.low)) {
        after = before;
      }
      const bool halfSpace = primitives[i].type() == PrimitiveType::HalfSpace;
      for (const double d : {halfSpace ? 0.0 : after.low - before.low, after.high - before.high}) {
        if (d != 0.0) {
          changed = true;
          ++result.movedCaps;
          result.largestMove = std::max(result.largestMove, std::abs(d));
        }
      }
    }
    if (changed) primitives[i] = withSlabs(primitives[i], moved[i]);
  }

  // The same tree over the new primitives, sharing what it shared.
  std::unordered_map<const Node*, NodePtr> rebuilt;
  auto rebuild = [&](auto&& self, const NodePtr& n) -> NodePtr {
    if (auto it = rebuilt.find(n.get()); it != rebuilt.end()) return it->second;
    NodePtr out;
    if (n->kind == NodeKind::Primitive) {
      out = std::make_shared<const Node>(primitives[leafIndex.at(n.get())], n->name);
    } else {
      std::vector<NodePtr> children;
      children.reserve(n->children.size());
      for (const NodePtr& c : n->children) children.push_back(self(self, c));
      out = std::make_shared<const Node>(n->kind, std::move(children));
    }
    rebuilt.emplace(n.get(), out);
    return out;
  };
  result.tree = CsgTree(rebuild(rebuild, tree.root()));
  return result;
}

}  // namespace csgvox
