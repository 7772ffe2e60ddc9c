#include "evolve/redundancy.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>

#include "evolve/tree_variation.h"

namespace csgvox {
namespace {

bool sameSubtree(const NodePtr& a, const NodePtr& b) {
  return a == b || CsgTree(a).structurallyEqual(CsgTree(b));
}

bool isComplementOf(const NodePtr& a, const NodePtr& b) {
  return a->kind == NodeKind::Complement && sameSubtree(a->children.front(), b);
}

// The node with double complements, single-operand operations, repeated
// operands and operands that cancel (X − X, X ∩ ¬X) removed; nullptr for an
// empty solid.
NodePtr normalizeNode(const NodePtr& node) {
  if (node->kind == NodeKind::Primitive) return node;
  if (node->kind == NodeKind::Complement) {
    const NodePtr inner = normalizeNode(node->children.front());
    if (!inner) return node;  // everything: left as it was
    if (inner->kind == NodeKind::Complement) return inner->children.front();
    if (inner == node->children.front()) return node;
    return std::make_shared<const Node>(NodeKind::Complement, std::vector<NodePtr>{inner});
  }
  std::vector<NodePtr> children;
  children.reserve(node->children.size());
  bool changed = false;
  for (std::size_t k = 0; k < node->children.size(); ++k) {
    const NodePtr& c = node->children[k];
    NodePtr n = normalizeNode(c);
    changed = changed || n != c;
    if (!n) {
      // An empty operand empties an intersection and a difference's first
      // operand; elsewhere it is dropped.
      if (node->kind == NodeKind::Intersection) return nullptr;
      if (node->kind == NodeKind::Difference && k == 0) return nullptr;
      continue;
    }
    // A difference's cutters are compared among themselves and with what
    // they cut; the operands of a union or an intersection with each other.
    const bool cut = node->kind == NodeKind::Difference;
    const auto same = [&](const NodePtr& other) { return sameSubtree(other, n); };
    if (std::any_of(children.begin() + std::ptrdiff_t(cut && !children.empty()), children.end(),
                    same)) {
      changed = true;  // repeated
      continue;
    }
    if (cut && k > 0 && same(children.front())) return nullptr;  // X − X
    if (node->kind == NodeKind::Intersection) {
      for (const NodePtr& other : children)
        if (isComplementOf(other, n) || isComplementOf(n, other)) return nullptr;
    }
    children.push_back(std::move(n));
  }
  if (children.empty()) return nullptr;
  if (children.size() == 1) return children.front();
  if (!changed) return node;
  return std::make_shared<const Node>(node->kind, std::move(children));
}

constexpr double kUnbounded = std::numeric_limits<double>::infinity();

// Support of a primitive along the unit direction u: the largest u·x over
// its solid (infinite when unbounded that way).
double support(const Primitive& p, const Vec3& u) {
  // sin of the angle between u and an axis: how far a circle about the
  // axis reaches along u, per unit radius.
  const auto across = [&u](const Vec3& axis) {
    const double c = axis.dot(u);
    return std::sqrt(std::max(0.0, 1.0 - c * c));
  };
  if (const auto* h = p.as<HalfSpace>()) {
    return h->normal.dot(u) >= 1.0 - 1e-12 ? h->offset : kUnbounded;
  }
  if (const auto* b = p.as<Box>()) {
    return b->center.dot(u) + (b->axes.transpose() * u).cwiseAbs().dot(b->halfSize);
  }
  if (const auto* c = p.as<Cylinder>()) {
    return c->center.dot(u) + 0.5 * c->height * std::abs(c->axis.dot(u)) +
           c->radius * across(c->axis);
  }
  if (const auto* k = p.as<Cone>()) {
    const double along = 0.5 * k->height * k->axis.dot(u);
    return k->center.dot(u) + std::max(-along + k->radiusBottom * across(k->axis),
                                       along + k->radiusTop * across(k->axis));
  }
  if (const auto* s = p.as<Sphere>()) return s->center.dot(u) + s->radius;
  const Torus& t = std::get<Torus>(p.shape());
  return t.center.dot(u) + t.majorRadius * across(t.axis) + t.minorRadius;
}

// An upper bound of u·x over the node's solid.
double support(const Node& n, const Vec3& u) {
  switch (n.kind) {
    case NodeKind::Primitive:
      return support(n.primitive, u);
    case NodeKind::Complement:
      return kUnbounded;
    case NodeKind::Difference:
      return support(*n.children.front(), u);
    case NodeKind::Union: {
      double s = -kUnbounded;
      for (const NodePtr& c : n.children) s = std::max(s, support(*c, u));
      return s;
    }
    case NodeKind::Intersection: {
      double s = kUnbounded;
      for (const NodePtr& c : n.children) s = std::min(s, support(*c, u));
      return s;
    }
  }
  return kUnbounded;
}

// The half-space an operand is, read through a complement: {normal·x <=
// offset} or, complemented, its closure's opposite; nullopt for any other.
std::optional<HalfSpace> asHalfSpace(const Node& operand) {
  const Node* leaf = &operand;
  bool flipped = false;
  if (leaf->kind == NodeKind::Complement) {
    leaf = leaf->children.front().get();
    flipped = true;
  }
  if (leaf->kind != NodeKind::Primitive) return std::nullopt;
  const HalfSpace* h = leaf->primitive.as<HalfSpace>();
  if (!h) return std::nullopt;
  return flipped ? HalfSpace{-h->normal, -h->offset} : *h;
}

// Whether `x` has no volume inside the half-space h: x lies on or beyond
// its plane (up to a relative rounding slack).
bool beyond(const Node& x, const HalfSpace& h) {
  const double lowest = -support(x, -h.normal);
  return std::isfinite(lowest) &&
         lowest >= h.offset - 1e-9 * (std::abs(h.offset) + std::abs(lowest));
}

// Whether the operation's solid provably has no volume, its operands being
// non-empty.
bool provablyEmpty(const NodePtr& node) {
  const Node& n = *node;
  if (n.kind != NodeKind::Intersection && n.kind != NodeKind::Difference) return false;
  if (CsgTree(node).bounds().isEmpty()) return true;
  const bool difference = n.kind == NodeKind::Difference;
  // The operands intersected: a difference's cutters as the sets they leave.
  for (std::size_t i = difference ? 1 : 0; i < n.children.size(); ++i) {
    std::optional<HalfSpace> h = asHalfSpace(*n.children[i]);
    if (!h) continue;
    if (difference) h = HalfSpace{-h->normal, -h->offset};  // what the cut leaves
    for (std::size_t j = 0; j < n.children.size(); ++j) {
      if (j == i || (difference && j > 0)) continue;
      if (beyond(*n.children[j], *h)) return true;
    }
  }
  return false;
}

// The node without its empty subtrees; nullptr when its solid is empty.
NodePtr pruneEmpty(const NodePtr& node) {
  if (node->kind == NodeKind::Primitive) return node;
  if (node->kind == NodeKind::Complement) {
    const NodePtr inner = pruneEmpty(node->children.front());
    if (!inner || inner == node->children.front()) return node;  // everything: left as it was
    return std::make_shared<const Node>(NodeKind::Complement, std::vector<NodePtr>{inner});
  }
  std::vector<NodePtr> children;
  bool changed = false;
  for (std::size_t k = 0; k < node->children.size(); ++k) {
    NodePtr c = pruneEmpty(node->children[k]);
    if (!c) {
      if (node->kind == NodeKind::Intersection) return nullptr;
      if (node->kind == NodeKind::Difference && k == 0) return nullptr;
      changed = true;
      continue;
    }
    changed = changed || c != node->children[k];
    children.push_back(std::move(c));
  }
  if (children.empty()) return nullptr;
  if (children.size() == 1) return children.front();
  const NodePtr pruned =
      changed ? std::make_shared<const Node>(node->kind, std::move(children)) : node;
  return provablyEmpty(pruned) ? nullptr : pruned;
}

// The tree with the operation at `path` without its operand k (an operation
// left with one operand replaced by it).
CsgTree withoutOperand(const CsgTree& tree, const NodePath& path, std::size_t k) {
  const NodePtr& node = tree.nodeAt(path);
  std::vector<NodePtr> rest = node->children;
  rest.erase(rest.begin() + std::ptrdiff_t(k));
  return tree.replaceSubtree(
      path, CsgTree(rest.size() == 1 ? rest.front()
                                     : std::make_shared<const Node>(node->kind, std::move(rest))));
}

// The variants of the tree with the operation at `path` simplified: replaced
// by each operand, or (n-ary) without one operand.
std::vector<CsgTree> simplerVariants(const CsgTree& tree, const NodePath& path) {
  std::vector<CsgTree> out;
  const NodePtr& node = tree.nodeAt(path);
  if (node->kind == NodeKind::Primitive || node->kind == NodeKind::Complement) return out;
  for (const NodePtr& child : node->children)
    out.push_back(tree.replaceSubtree(path, CsgTree(child)));
  if (node->children.size() > 2) {
    for (std::size_t k = 0; k < node->children.size(); ++k) {
      // The first operand of a difference is what the others are cut from.
      if (node->kind == NodeKind::Difference && k == 0) continue;
      out.push_back(withoutOperand(tree, path, k));
    }
  }
  return out;
}

// A box holding every point where removing the node's operand k can change
// the solid: the operand's bounds for a union member, those met with what a
// cutter cuts for a difference, the others' for an intersection.
Aabb changeBox(const Node& node, std::size_t k) {
  if (node.kind == NodeKind::Union) return CsgTree(node.children[k]).bounds();
  if (node.kind == NodeKind::Difference) {
    return CsgTree(node.children[k]).bounds().intersected(CsgTree(node.children[0]).bounds());
  }
  std::vector<NodePtr> others = node.children;
  others.erase(others.begin() + std::ptrdiff_t(k));
  return CsgTree(others.size() == 1
                     ? others.front()
                     : std::make_shared<const Node>(NodeKind::Intersection, std::move(others)))
      .bounds();
}

// Whether `a` and `b` disagree on less than `minVolume` within `box`,
// counted on a lattice of `spacing` (see withoutNegligibleOperands). The
// lattice is turned against the axes, so that a plate thinner than its
// spacing and parallel to them is counted by its volume, not missed between
// two layers of points.
bool differOnLess(const CsgTree& a, const CsgTree& b, const Aabb& box, double spacing,
                  double minVolume) {
  constexpr double kMaxPoints = double(1u << 18);
  if (box.isEmpty()) return true;
  const Vec3 size = box.max - box.min;
  if (!size.allFinite()) return false;
  const Mat3 turn = Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  // The box in the lattice's frame.
  Aabb frame;
  for (int c = 0; c < 8; ++c) {
    const Vec3 corner((c & 1) ? box.max.x() : box.min.x(), (c & 2) ? box.max.y() : box.min.y(),
                      (c & 4) ? box.max.z() : box.min.z());
    frame.extend(Vec3(turn.transpose() * corner));
  }
  const Vec3 span = frame.max - frame.min;
  const double cells = span.prod() / (spacing * spacing * spacing);
  const double s = cells > kMaxPoints ? spacing * std::cbrt(cells / kMaxPoints) : spacing;
  const double allowed = minVolume / (s * s * s);  // lattice points
  if (allowed < 1.0) return false;
  std::array<std::size_t, 3> n{};
  for (int k = 0; k < 3; ++k) n[k] = std::max<std::size_t>(1, std::size_t(std::ceil(span[k] / s)));
  const std::size_t total = n[0] * n[1] * n[2];
  // Batches of points spread over the whole box, so a change anywhere in it
  // is found within the first few.
  constexpr std::size_t kBatch = 4096;
  const std::size_t stride = (total + kBatch - 1) / kBatch;
  std::vector<Vec3> points;
  std::vector<double> va, vb;
  std::size_t differing = 0;
  for (std::size_t first = 0; first < stride; ++first) {
    points.clear();
    for (std::size_t i = first; i < total; i += stride) {
      const std::size_t x = i % n[0], y = (i / n[0]) % n[1], z = i / (n[0] * n[1]);
      const Vec3 p =
          turn * Vec3(frame.min + s * Vec3(double(x) + 0.5, double(y) + 0.5, double(z) + 0.5));
      if ((p.array() >= box.min.array()).all() && (p.array() <= box.max.array()).all())
        points.push_back(p);
    }
    if (points.empty()) continue;
    va.resize(points.size());
    vb.resize(points.size());
    a.values(points, va);
    b.values(points, vb);
    for (std::size_t i = 0; i < points.size(); ++i) differing += (va[i] >= 0.0) != (vb[i] >= 0.0);
    if (double(differing) >= allowed) return false;
  }
  return true;
}

// A primitive whose solid holds a's and b's and no more than both where they
// join (see withSharedCuts), or nullopt. Lengths agree within `tolerance`.
std::optional<Primitive> spanningPrimitive(const Primitive& a, const Primitive& b,
                                           double tolerance) {
  if (!a.isBounded() || a.type() != b.type()) return std::nullopt;
  if (a.approxEqual(b, tolerance)) return a;
  if (const auto* p = a.as<Cylinder>()) {
    const Cylinder& q = *b.as<Cylinder>();
    if (std::abs(p->radius - q.radius) > tolerance) return std::nullopt;
    // q's axis segment on p's axis line: both ends within the tolerance of it.
    double lo = -0.5 * p->height, hi = 0.5 * p->height;
    for (const double end : {-0.5, 0.5}) {
      const Vec3 e = q.center + end * q.height * q.axis - p->center;
      const double t = e.dot(p->axis);
      if ((e - t * p->axis).norm() > tolerance) return std::nullopt;
      lo = std::min(lo, t);
      hi = std::max(hi, t);
    }
    return Cylinder{p->center + 0.5 * (lo + hi) * p->axis, p->axis, p->radius, hi - lo};
  }
  if (const auto* p = a.as<Box>()) {
    const Box& q = *b.as<Box>();
    // q's extent along each of p's axes (its support, larger if q is turned).
    Vec3 lo, hi;
    int apart = -1;
    for (int k = 0; k < 3; ++k) {
      const Vec3 axis = p->axes.col(k);
      const double c = (q.center - p->center).dot(axis);
      const double e = (q.axes.transpose() * axis).cwiseAbs().dot(q.halfSize);
      const bool agree = std::abs(c - e + p->halfSize[k]) <= tolerance &&
                         std::abs(c + e - p->halfSize[k]) <= tolerance;
      if (!agree) {
        if (apart >= 0) return std::nullopt;
        apart = k;
      }
      lo[k] = std::min(-p->halfSize[k], c - e);
      hi[k] = std::max(p->halfSize[k], c + e);
    }
    if (apart < 0) return a;
    Vec3 half = p->halfSize;
    half[apart] = 0.5 * (hi[apart] - lo[apart]);
    return Box{p->center + p->axes.col(apart) * (0.5 * (lo[apart] + hi[apart])), p->axes, half};
  }
  return std::nullopt;
}

// The difference `member` without its cutter k (its first operand alone when
// no other cutter is left).
NodePtr withoutCutter(const NodePtr& member, std::size_t k) {
  std::vector<NodePtr> rest = member->children;
  rest.erase(rest.begin() + std::ptrdiff_t(k));
  return rest.size() == 1 ? rest.front()
                          : std::make_shared<const Node>(NodeKind::Difference, std::move(rest));
}

// The union or difference at `path` with two of its leaf operands (members,
// or cutters) that one primitive spans made that primitive, the first such
// change of the solid by less than minVolume; nullopt if none.
std::optional<CsgTree> joinOneSurface(const CsgTree& tree, const NodePath& path, double spacing,
                                      double minVolume) {
  const NodePtr& node = tree.nodeAt(path);
  const std::vector<NodePtr>& operands = node->children;
  for (std::size_t i = node->kind == NodeKind::Difference ? 1 : 0; i < operands.size(); ++i) {
    if (operands[i]->kind != NodeKind::Primitive) continue;
    for (std::size_t j = i + 1; j < operands.size(); ++j) {
      if (operands[j]->kind != NodeKind::Primitive) continue;
      const std::optional<Primitive> span =
          spanningPrimitive(operands[i]->primitive, operands[j]->primitive, 0.25 * spacing);
      if (!span) continue;
      std::vector<NodePtr> rest = operands;
      rest[i] = std::make_shared<const Node>(*span, operands[i]->name);
      rest.erase(rest.begin() + std::ptrdiff_t(j));
      const CsgTree variant = tree.replaceSubtree(
          path,
          CsgTree(rest.size() == 1 ? rest.front()
                                   : std::make_shared<const Node>(node->kind, std::move(rest))));
      if (differOnLess(tree, variant, span->bounds(), spacing, minVolume)) return variant;
    }
  }
  return std::nullopt;
}

// The union at `path` with one cut shared by two of its members, the first
// such rewrite that changes the solid by less than minVolume; nullopt if none.
std::optional<CsgTree> shareOneCut(const CsgTree& tree, const NodePath& path, double spacing,
                                   double minVolume) {
  const NodePtr& node = tree.nodeAt(path);
  const std::vector<NodePtr>& members = node->children;
  const auto cutters = [](const NodePtr& m) {
    return m->kind == NodeKind::Difference ? m->children.size() : std::size_t{0};
  };
  const Aabb unionBox = CsgTree(node).bounds();
  for (std::size_t i = 0; i < members.size(); ++i) {
    for (std::size_t j = i + 1; j < members.size(); ++j) {
      for (std::size_t ci = 1; ci < cutters(members[i]); ++ci) {
        const Node& first = *members[i]->children[ci];
        if (first.kind != NodeKind::Primitive) continue;
        for (std::size_t cj = 1; cj < cutters(members[j]); ++cj) {
          const Node& second = *members[j]->children[cj];
          if (second.kind != NodeKind::Primitive) continue;
          const std::optional<Primitive> span =
              spanningPrimitive(first.primitive, second.primitive, 0.25 * spacing);
          if (!span) continue;
          const NodePtr cut = std::make_shared<const Node>(*span, first.name);
          const NodePtr a = withoutCutter(members[i], ci), b = withoutCutter(members[j], cj);
          const Aabb box = span->bounds().intersected(unionBox);
          // Every member cut, then only the two.
          std::vector<NodePtr> all = members;
          all[i] = a;
          all[j] = b;
          std::vector<NodePtr> others;
          for (std::size_t k = 0; k < members.size(); ++k)
            if (k != i && k != j) others.push_back(members[k]);
          const auto cutFrom = [&cut](std::vector<NodePtr> operands) {
            return std::make_shared<const Node>(
                NodeKind::Difference,
                std::vector<NodePtr>{
                    std::make_shared<const Node>(NodeKind::Union, std::move(operands)), cut});
          };
          std::vector<NodePtr> variants{cutFrom(all)};
          if (!others.empty()) {
            others.push_back(cutFrom({a, b}));
            variants.push_back(std::make_shared<const Node>(NodeKind::Union, std::move(others)));
          }
          for (const NodePtr& v : variants) {
            CsgTree variant = tree.replaceSubtree(path, CsgTree(v));
            // A union cut from something else: the new cut joins its cutters.
            if (v == variants.front() && !path.empty() && path.back() == 0) {
              const NodePath parentPath(path.begin(), path.end() - 1);
              const NodePtr& parent = tree.nodeAt(parentPath);
              if (parent->kind == NodeKind::Difference) {
                std::vector<NodePtr> operands = v->children;
                operands.insert(operands.end(), parent->children.begin() + 1,
                                parent->children.end());
                variant = tree.replaceSubtree(
                    parentPath, CsgTree(std::make_shared<const Node>(NodeKind::Difference,
                                                                     std::move(operands))));
              }
            }
            if (differOnLess(tree, variant, box, spacing, minVolume)) return variant;
          }
        }
      }
    }
  }
  return std::nullopt;
}

}  // namespace

CsgTree withoutNegligibleOperands(const CsgTree& tree, double spacing, double minVolume) {
  if (tree.empty() || !(spacing > 0.0) || !(minVolume > 0.0)) return tree;
  CsgTree current = tree;
  bool removed = true;
  while (removed) {
    removed = false;
    for (const NodePath& path : nodePaths(current)) {
      const Node& node = *current.nodeAt(path);
      if (node.kind == NodeKind::Primitive || node.kind == NodeKind::Complement) continue;
      for (std::size_t k = node.kind == NodeKind::Difference ? 1 : 0; k < node.children.size();
           ++k) {
        CsgTree variant = withoutOperand(current, path, k);
        if (differOnLess(current, variant, changeBox(node, k), spacing, minVolume)) {
          current = std::move(variant);
          removed = true;
          break;
        }
      }
      if (removed) break;
    }
  }
  return current;
}

CsgTree withSharedCuts(const CsgTree& tree, double spacing, double minVolume) {
  if (tree.empty() || !(spacing > 0.0) || !(minVolume > 0.0)) return tree;
  CsgTree current = tree;
  for (bool shared = true; shared;) {
    shared = false;
    for (const NodePath& path : nodePaths(current)) {
      const NodeKind kind = current.nodeAt(path)->kind;
      if (kind != NodeKind::Union && kind != NodeKind::Difference) continue;
      std::optional<CsgTree> variant = joinOneSurface(current, path, spacing, minVolume);
      if (!variant && kind == NodeKind::Union)
        variant = shareOneCut(current, path, spacing, minVolume);
      if (variant) {
        current = std::move(*variant);
        shared = true;
        break;
      }
    }
  }
  return current;
}

CsgTree normalizeTree(const CsgTree& tree) {
  if (tree.empty()) return tree;
  const NodePtr root = normalizeNode(tree.root());
  return root ? CsgTree(root) : tree;
}

CsgTree withoutEmptySubtrees(const CsgTree& tree) {
  if (tree.empty()) return tree;
  const NodePtr root = pruneEmpty(tree.root());
  return root ? CsgTree(root) : tree;
}

CsgTree removeRedundancy(const CsgTree& tree, const FitnessModel& model) {
  CsgTree current = normalizeTree(withoutEmptySubtrees(tree));
  double best = model.evaluate(current).total;
  // The normalised tree is the same solid with fewer nodes: never worse.
  bool improved = true;
  while (improved) {
    improved = false;
    for (const NodePath& path : nodePaths(current)) {
      for (CsgTree& variant : simplerVariants(current, path)) {
        variant = normalizeTree(variant);
        const double f = model.evaluate(variant).total;
        if (f >= best) {
          current = std::move(variant);
          best = f;
          improved = true;
          break;
        }
      }
      if (improved) break;
    }
  }
  return current;
}

}  // namespace csgvox
