#include "design/part_frame.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <unordered_map>
#include <vector>

#include "core/export_cutters.h"
#include "core/export_extent.h"
#include "design/point_support.h"
#include "design/value_ladder.h"

namespace csgvox {
namespace {

struct Vote {
  Vec3 direction;  // unit
  double weight = 0.0;
  bool axial = false;  // a cylinder, cone or torus axis
};

bool isAxial(const Primitive& p) {
  return p.type() == PrimitiveType::Cylinder || p.type() == PrimitiveType::Cone ||
         p.type() == PrimitiveType::Torus;
}

// Areas of the faces each of Primitive::directions() orients.
std::vector<double> faceAreas(const Primitive& p, double diagonal) {
  // A plane's face within the part: at most about a square of half the
  // part's diagonal.
  if (p.as<HalfSpace>()) return {0.25 * diagonal * diagonal};
  if (const auto* b = p.as<Box>()) {
    const Vec3 s = 2.0 * b->halfSize;
    return {2 * s.y() * s.z(), 2 * s.x() * s.z(), 2 * s.x() * s.y()};
  }
  if (p.isBounded() && p.type() != PrimitiveType::Sphere) return {p.surfaceArea()};
  return {};
}

void addVote(std::vector<Vote>& votes, const Vec3& d, double w, bool axial, double cosTol) {
  if (!(w > 0.0)) return;
  for (Vote& v : votes) {
    if (std::abs(v.direction.dot(d)) >= cosTol) {
      v.weight += w;
      v.axial = v.axial || axial;
      return;
    }
  }
  votes.push_back({d.normalized(), w, axial});
}

std::vector<Vote> directionVotes(const CsgTree& tree, std::span<const Vec3> points, double cosTol) {
  std::vector<Vote> votes;
  const std::vector<const Node*> leaves = tree.distinctLeaves();
  if (!points.empty()) {
    const PointSupport support = pointSupport(tree, points);
    // Points per leaf and direction, in the tree's order.
    std::unordered_map<const Node*, std::vector<double>> counts;
    for (std::size_t i = 0; i < points.size(); ++i) {
      const Node* leaf = support.leaf[i];
      if (!leaf) continue;
      const std::vector<Vec3> dirs = leaf->primitive.directions();
      if (dirs.empty()) continue;
      auto& c = counts[leaf];
      c.resize(dirs.size(), 0.0);
      if (isAxial(leaf->primitive) || dirs.size() == 1) {
        c[0] += 1.0;
        continue;
      }
      std::size_t k = 0;
      for (std::size_t j = 1; j < dirs.size(); ++j) {
        if (std::abs(dirs[j].dot(support.gradient[i])) > std::abs(dirs[k].dot(support.gradient[i])))
          k = j;
      }
      c[k] += 1.0;
    }
    for (const Node* leaf : leaves) {
      const auto it = counts.find(leaf);
      if (it == counts.end()) continue;
      const std::vector<Vec3> dirs = leaf->primitive.directions();
      for (std::size_t j = 0; j < dirs.size(); ++j) {
        addVote(votes, dirs[j], it->second[j], isAxial(leaf->primitive), cosTol);
      }
    }
    if (!votes.empty()) return votes;
  }
  const double diagonal = exportExtent(tree).diagonal();
  for (const Node* leaf : leaves) {
    const std::vector<Vec3> dirs = leaf->primitive.directions();
    const std::vector<double> areas = faceAreas(leaf->primitive, diagonal);
    for (std::size_t j = 0; j < dirs.size() && j < areas.size(); ++j) {
      addVote(votes, dirs[j], areas[j], isAxial(leaf->primitive), cosTol);
    }
  }
  return votes;
}

// The solid's centroid, from a grid over its extent (the extent's centre
// when the grid holds no inside point).
Vec3 solidCentroid(const CsgTree& tree, const Aabb& extent) {
  constexpr int n = 24;
  std::vector<Vec3> grid;
  grid.reserve(n * n * n);
  const Vec3 step = extent.size() / n;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k)
        grid.push_back(extent.min + Vec3(i + 0.5, j + 0.5, k + 0.5).cwiseProduct(step));
  std::vector<double> f(grid.size());
  tree.values(grid, f);
  Vec3 sum = Vec3::Zero();
  double count = 0.0;
  for (std::size_t i = 0; i < grid.size(); ++i) {
    if (f[i] >= 0.0) {
      sum += grid[i];
      count += 1.0;
    }
  }
  return count > 0.0 ? Vec3(sum / count) : extent.center();
}

}  // namespace

Mat3 nearestWorldAxes(const Mat3& r, double tol) {
  Mat3 out = Mat3::Zero();
  for (int c = 0; c < 3; ++c) {
    int k = 0;
    r.col(c).cwiseAbs().maxCoeff(&k);
    if (std::abs(r(k, c)) < std::cos(tol)) return r;
    out(k, c) = r(k, c) > 0.0 ? 1.0 : -1.0;
  }
  return std::abs(out.determinant() - 1.0) < 1e-12 ? out : r;
}

Vec3 PartFrame::eulerDegrees() const {
  const Mat3& r = rotation;
  constexpr double deg = 180.0 / std::numbers::pi;
  const double sb = std::clamp(-r(2, 0), -1.0, 1.0);
  const double b = std::asin(sb);
  double a = 0.0, c = 0.0;
  if (std::abs(sb) < 1.0 - 1e-12) {
    a = std::atan2(r(2, 1), r(2, 2));
    c = std::atan2(r(1, 0), r(0, 0));
  } else {
    a = std::atan2(-r(1, 2), r(1, 1));
  }
  return Vec3(a, b, c) * deg;
}

PartFrame partFrame(const CsgTree& tree, std::span<const Vec3> points,
                    const FrameOptions& options) {
  if (tree.empty()) throw std::invalid_argument("partFrame: empty tree");
  const double cosTol = std::cos(options.parallelTolerance);
  const double sinTol = std::sin(options.parallelTolerance);
  std::vector<Vote> votes = directionVotes(tree, points, cosTol);
  // Heaviest first; ties keep the tree's order.
  std::stable_sort(votes.begin(), votes.end(),
                   [](const Vote& a, const Vote& b) { return a.weight > b.weight; });
  double total = 0.0;
  for (const Vote& v : votes) total += v.weight;
  Vec3 z = Vec3::UnitZ();
  const auto axial =
      std::find_if(votes.begin(), votes.end(), [](const Vote& v) { return v.axial; });
  if (axial != votes.end()) {
    z = axial->direction;
  } else if (!votes.empty()) {
    z = votes.front().direction;
  }
  // x: of the directions orthogonal to z that carry a share of the faces,
  // the one the part is longest along (a plate's length, not the normal of
  // its largest side); else the world axis farthest from z, made orthogonal.
  constexpr double minShare = 0.05;
  const auto lengthAlong = [&](const Vec3& d) {
    Mat3 r;
    r.col(0) = d;
    r.col(1) = z.cross(d).normalized();
    r.col(2) = z;
    return exportExtent(transformedTree(tree, r.transpose(), Vec3::Zero())).size().x();
  };
  Vec3 x = Vec3::Zero();
  double longest = 0.0;
  for (const Vote& v : votes) {
    if (std::abs(v.direction.dot(z)) > sinTol || v.weight < minShare * total) continue;
    const Vec3 d = (v.direction - v.direction.dot(z) * z).normalized();
    const double length = lengthAlong(d);
    if (length > longest * (1.0 + 1e-6)) {
      longest = length;
      x = d;
    }
  }
  const bool spinFree = x.isZero();
  if (spinFree) {
    int k = 0;
    z.cwiseAbs().minCoeff(&k);
    const Vec3 w = Vec3::Unit(k);
    x = (w - w.dot(z) * z).normalized();
  }
  // Signs: the solid's centroid on the low side of its extent along z and x,
  // both measured in the frame (so that a turned copy decides alike).
  Mat3 r;
  r.col(0) = x;
  r.col(1) = z.cross(x).normalized();
  r.col(2) = z;
  {
    const CsgTree inFrame = transformedTree(tree, r.transpose(), Vec3::Zero());
    const Aabb e = exportExtent(inFrame);
    const Vec3 c = solidCentroid(inFrame, e);
    // A part symmetric along the axis (its centroid within 10⁻³ of its
    // extent of the middle) keeps the sign that points the axis most along
    // a world axis's positive side: either gives the same values.
    const auto flip = [&](int k, const Vec3& axis) {
      const double off = c[k] - e.center()[k], margin = 1e-3 * e.size()[k];
      if (std::abs(off) > margin) return off > 0.0;
      int w = 0;
      axis.cwiseAbs().maxCoeff(&w);
      return axis[w] < 0.0;
    };
    if (flip(2, z)) z = -z;
    if (flip(0, x)) x = -x;
  }
  PartFrame frame;
  frame.spinFree = spinFree;
  frame.rotation.col(0) = x;
  frame.rotation.col(1) = z.cross(x).normalized();
  frame.rotation.col(2) = z;
  frame.rotation = nearestWorldAxes(frame.rotation, options.worldTolerance);

  // Origin: on the heaviest axis parallel to z of a primitive that adds
  // material (by its area), at the bottom of the part; else the low corner of
  // the part's bounds.
  const CsgTree local = transformedTree(tree, frame.rotation.transpose(), Vec3::Zero());
  const Aabb localExtent = exportExtent(local);
  Vec3 origin = localExtent.min;
  double bestWeight = 0.0;
  const LeafRoles roles = leafRoles(tree);
  const std::vector<const Node*> worldLeaves = tree.distinctLeaves();
  const std::vector<const Node*> localLeaves = local.distinctLeaves();
  for (std::size_t i = 0; i < localLeaves.size(); ++i) {
    const Primitive& p = localLeaves[i]->primitive;
    if (!isAxial(p) || !roles.adding.count(worldLeaves[i])) continue;
    const auto axisAndCenter = [&]() -> std::pair<Vec3, Vec3> {
      if (const auto* c = p.as<Cylinder>()) return {c->axis, c->center};
      if (const auto* c = p.as<Cone>()) return {c->axis, c->center};
      const auto* t = p.as<Torus>();
      return {t->axis, t->center};
    }();
    if (std::abs(std::abs(axisAndCenter.first.z()) - 1.0) > 1 - cosTol) continue;
    const double w = p.surfaceArea();
    if (w > bestWeight) {
      bestWeight = w;
      origin.x() = axisAndCenter.second.x();
      origin.y() = axisAndCenter.second.y();
    }
  }
  frame.origin =
      roundedOrigin(frame.rotation * origin, options.originTolerance * localExtent.diagonal());
  return frame;
}

Vec3 roundedOrigin(Vec3 origin, double tolerance) {
  for (int i = 0; i < 3; ++i) {
    if (const auto v = simplestLength(origin[i], tolerance, UnitSystem::Millimetre)) {
      origin[i] = *v;
    }
  }
  return origin;
}

Primitive transformedPrimitive(const Primitive& primitive, const Mat3& rotation,
                               const Vec3& translation) {
  const auto place = [&](const Vec3& p) -> Vec3 { return rotation * p + translation; };
  const auto turn = [&](const Vec3& d) -> Vec3 { return (rotation * d).normalized(); };
  return std::visit(
      [&](auto s) -> Primitive {
        using T = decltype(s);
        if constexpr (std::is_same_v<T, HalfSpace>) {
          s.normal = turn(s.normal);
          s.offset += s.normal.dot(translation);
        } else if constexpr (std::is_same_v<T, Box>) {
          s.center = place(s.center);
          s.axes = rotation * s.axes;
        } else if constexpr (std::is_same_v<T, Sphere>) {
          s.center = place(s.center);
        } else {
          s.center = place(s.center);
          s.axis = turn(s.axis);
        }
        return s;
      },
      primitive.shape());
}

namespace {

NodePtr transformedNode(const NodePtr& node, const Mat3& rotation, const Vec3& translation,
                        std::unordered_map<const Node*, NodePtr>& done) {
  if (const auto it = done.find(node.get()); it != done.end()) return it->second;
  NodePtr out;
  if (node->kind == NodeKind::Primitive) {
    out = std::make_shared<const Node>(transformedPrimitive(node->primitive, rotation, translation),
                                       node->name);
  } else {
    std::vector<NodePtr> children;
    for (const NodePtr& c : node->children) {
      children.push_back(transformedNode(c, rotation, translation, done));
    }
    out = std::make_shared<const Node>(node->kind, std::move(children));
  }
  done[node.get()] = out;
  return out;
}

}  // namespace

CsgTree transformedTree(const CsgTree& tree, const Mat3& rotation, const Vec3& translation) {
  if (tree.empty()) return tree;
  std::unordered_map<const Node*, NodePtr> done;
  return CsgTree(transformedNode(tree.root(), rotation, translation, done));
}

CsgTree treeInFrame(const CsgTree& tree, const PartFrame& frame) {
  const Mat3 rt = frame.rotation.transpose();
  return transformedTree(tree, rt, -(rt * frame.origin));
}

CsgTree treeInWorld(const CsgTree& tree, const PartFrame& frame) {
  return transformedTree(tree, frame.rotation, frame.origin);
}

}  // namespace csgvox
