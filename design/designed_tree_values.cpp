#include <algorithm>
#include <cmath>
#include <numbers>
#include <unordered_map>

#include "design/designed_tree.h"

// The designed tree's own functions: its leaves realised from the
// parameters' values, in the frame and in the scan.

namespace csgvox {
namespace {

constexpr double kDeg = 180.0 / std::numbers::pi;

// Rebuilds `node` with each leaf replaced by make(leaf): its primitive and name.
template <class Make>
NodePtr rebuilt(const NodePtr& node, const Make& make,
                std::unordered_map<const Node*, NodePtr>& done) {
  if (const auto it = done.find(node.get()); it != done.end()) return it->second;
  NodePtr out;
  if (node->kind == NodeKind::Primitive) {
    auto [primitive, name] = make(node.get());
    out = std::make_shared<const Node>(std::move(primitive), std::move(name));
  } else {
    std::vector<NodePtr> children;
    for (const NodePtr& c : node->children) children.push_back(rebuilt(c, make, done));
    out = std::make_shared<const Node>(node->kind, std::move(children));
  }
  done[node.get()] = out;
  return out;
}

}  // namespace

std::string DesignedPattern::kindName() const {
  switch (kind) {
    case PatternKind::Circular:
      return "circular";
    case PatternKind::Lattice:
      return "lattice";
    default:
      return "row";
  }
}

int DesignedTree::leafIndex(const Node* node) const {
  for (std::size_t i = 0; i < leaves.size(); ++i) {
    if (leaves[i].node == node) return int(i);
  }
  return -1;
}

int DesignedTree::snappedCount() const {
  return int(std::count_if(parameters.begin(), parameters.end(),
                           [](const DesignParameter& p) { return p.snapped; }));
}

Primitive DesignedTree::localPrimitive(int index) const {
  const DesignedLeaf& l = leaves[std::size_t(index)];
  const auto v = [&](const Expression& e) { return e.value(parameters); };
  const int a = l.axis;
  Vec3 shift = Vec3::Zero();
  bool onCircle = false;
  double cx = 0.0, cy = 0.0;
  if (l.pattern >= 0) {
    const DesignedPattern& pat = patterns[std::size_t(l.pattern)];
    const int n = int(std::lround(parameters[std::size_t(pat.count)].value));
    if (pat.kind == PatternKind::Circular) {
      const double angle = (v(pat.phase) + l.member * 360.0 / n) / kDeg;
      cx = v(pat.centerX) + v(pat.radius) * std::cos(angle);
      cy = v(pat.centerY) + v(pat.radius) * std::sin(angle);
      onCircle = true;
    } else {
      const int i = l.member % n, j = l.member / n;
      for (int k = 0; k < 3; ++k) {
        shift[k] = i * v(pat.step[std::size_t(k)]) + j * v(pat.step2[std::size_t(k)]);
      }
    }
  }
  Vec3 at(v(l.at[0]), v(l.at[1]), v(l.at[2]));
  if (onCircle) at.x() = cx, at.y() = cy;
  Primitive p = l.local;
  switch (l.form) {
    case LeafForm::AlignedBox: {
      Box b;
      for (int k = 0; k < 3; ++k) {
        const double lo = v(l.lo[std::size_t(k)]), hi = v(l.hi[std::size_t(k)]);
        b.center[k] = 0.5 * (lo + hi);
        b.halfSize[k] = 0.5 * (hi - lo);
      }
      p = b;
      break;
    }
    case LeafForm::TurnedBox: {
      const double t = v(l.angle) / kDeg;
      Box b;
      b.center = Vec3(at.x(), at.y(), 0.5 * (v(l.lo[2]) + v(l.hi[2])));
      b.axes << std::cos(t), -std::sin(t), 0, std::sin(t), std::cos(t), 0, 0, 0, 1;
      b.halfSize = 0.5 * Vec3(v(l.radius), v(l.radius2), v(l.hi[2]) - v(l.lo[2]));
      p = b;
      break;
    }
    case LeafForm::Axial: {
      const Vec3 axis = Vec3::Unit(a);
      const double lo = v(l.lo[std::size_t(a)]), hi = v(l.hi[std::size_t(a)]);
      Vec3 c = at;
      if (l.type == PrimitiveType::Torus) {
        p = Torus{c, axis, v(l.radius), v(l.radius2)};
        break;
      }
      c[a] = 0.5 * (lo + hi);
      if (l.type == PrimitiveType::Cylinder) {
        p = Cylinder{c, axis, v(l.radius), hi - lo};
      } else {
        p = Cone{c, axis, v(l.radius), v(l.radius2), hi - lo};
      }
      break;
    }
    case LeafForm::Sphere:
      p = Sphere{at, v(l.radius)};
      break;
    case LeafForm::AlignedHalfSpace:
      p = l.flipped ? HalfSpace{-Vec3::Unit(a), -v(l.lo[std::size_t(a)])}
                    : HalfSpace{Vec3::Unit(a), v(l.hi[std::size_t(a)])};
      break;
    case LeafForm::TiltedHalfSpace: {
      const double tilt = v(l.angle) / kDeg, turn = v(l.angle2) / kDeg;
      const Vec3 n(std::sin(tilt) * std::cos(turn), std::sin(tilt) * std::sin(turn),
                   std::cos(tilt));
      p = HalfSpace{n.normalized(), v(l.radius)};
      break;
    }
    case LeafForm::Free:
      break;
  }
  if (!shift.isZero(0.0)) p = transformedPrimitive(p, Mat3::Identity(), shift);
  return p;
}

CsgTree DesignedTree::localTree() const {
  if (fitted.empty()) return {};
  std::unordered_map<const Node*, NodePtr> done;
  return CsgTree(rebuilt(
      fitted.root(),
      [&](const Node* leaf) {
        const int i = leafIndex(leaf);
        return std::make_pair(localPrimitive(i), leaves[std::size_t(i)].name);
      },
      done));
}

CsgTree DesignedTree::tree() const { return treeInWorld(localTree(), frame); }

}  // namespace csgvox
