#include "design/designed_tree.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <optional>
#include <set>
#include <stdexcept>

#include "core/decimal.h"
#include "core/export_cutters.h"
#include "core/export_extent.h"
#include "design/pattern_detection.h"
#include "design/point_support.h"
#include "design/role_names.h"

namespace csgvox {
namespace {

constexpr double kDeg = 180.0 / std::numbers::pi;
constexpr double kInf = std::numeric_limits<double>::infinity();
const char* const kAxisLetter[3] = {"x", "y", "z"};
// A point lies on a cap (not on the side) of a cylinder or cone when its
// gradient is this close to the axis: caps' gradients are the axis itself,
// sides' are across it (a cone's tilted by its half-angle).
constexpr double kCapCosine = 0.99;

// What a value measures, for grouping: values of one category and close
// values are one parameter.
enum class Category { PositionX, PositionY, PositionZ, Radius, Step, Angle, Count };

Category positionAlong(int axis) { return Category(axis); }

// One value of the fitted tree before grouping.
struct Slot {
  Category category = Category::Step;
  double value = 0.0;
  double support = 0.0;  // points holding it (kInf: exact, e.g. a count)
  double lever = 1.0;    // Angle: radius the angle is read at (its uncertainty is u / lever)
  std::string name;      // owner_field
  std::set<int> leaves;  // designed leaves using it
  std::string owner;     // a pattern's name, when a pattern owns it
};

// A field of a leaf: the expression to fill and where its value lives.
struct Field {
  Expression* expression;
  Category category;
  std::string name;  // "x0", "r", ...
  double value;
  bool crossPosition = false;  // Axial/Sphere position across z (moved by a circular pattern)
  int positionAxis = -1;       // a position along this frame axis (moved by rows), else -1
};

bool aligned(const Vec3& d, double tol, int& axis) {
  d.cwiseAbs().maxCoeff(&axis);
  return std::abs(d[axis]) >= std::cos(tol);
}

std::vector<const Node*> uniqueLeaves(const CsgTree& tree) {
  std::vector<const Node*> out;
  for (const Node* leaf : tree.leaves()) {
    if (std::find(out.begin(), out.end(), leaf) == out.end()) out.push_back(leaf);
  }
  return out;
}

// The leaf's form from its frame-coordinate primitive.
void classify(DesignedLeaf& leaf, const Primitive& p, double tol) {
  leaf.type = p.type();
  leaf.local = p;
  leaf.form = LeafForm::Free;
  int a = 2;
  if (const auto* b = p.as<Box>()) {
    bool all = true;
    for (int j = 0; j < 3; ++j) all = all && aligned(b->axes.col(j), tol, a);
    if (all) {
      leaf.form = LeafForm::AlignedBox;
    } else {
      for (int j = 0; j < 3; ++j) {
        if (std::abs(b->axes(2, j)) >= std::cos(tol)) leaf.form = LeafForm::TurnedBox;
      }
    }
  } else if (const auto* h = p.as<HalfSpace>()) {
    if (aligned(h->normal, tol, a)) {
      leaf.form = LeafForm::AlignedHalfSpace;
      leaf.axis = a;
      leaf.flipped = h->normal[a] < 0.0;
    } else {
      leaf.form = LeafForm::TiltedHalfSpace;
    }
  } else if (p.type() == PrimitiveType::Sphere) {
    leaf.form = LeafForm::Sphere;
  } else {
    Vec3 axis;
    if (const auto* c = p.as<Cylinder>()) axis = c->axis;
    if (const auto* c = p.as<Cone>()) axis = c->axis;
    if (const auto* t = p.as<Torus>()) axis = t->axis;
    if (aligned(axis, tol, a)) {
      leaf.form = LeafForm::Axial;
      leaf.axis = a;
    }
  }
}

// The fields of a classified leaf, with their fitted values.
std::vector<Field> fieldsOf(DesignedLeaf& leaf) {
  std::vector<Field> f;
  const Primitive& p = leaf.local;
  const int a = leaf.axis;
  const auto pos = [&](Expression& e, int axis, const std::string& name, double v, bool cross) {
    f.push_back({&e, positionAlong(axis), name, v, cross, axis});
  };
  switch (leaf.form) {
    case LeafForm::AlignedBox: {
      const Box& b = *p.as<Box>();
      for (int j = 0; j < 3; ++j) {
        int k = 0;
        aligned(b.axes.col(j), 1.0, k);
        const std::string l = kAxisLetter[k];
        pos(leaf.lo[std::size_t(k)], k, l + "0", b.center[k] - b.halfSize[j], false);
        pos(leaf.hi[std::size_t(k)], k, l + "1", b.center[k] + b.halfSize[j], false);
      }
      break;
    }
    case LeafForm::TurnedBox: {
      const Box& b = *p.as<Box>();
      int j = 0;
      b.axes.row(2).cwiseAbs().maxCoeff(&j);
      const int u = (j + 1) % 3, w = (j + 2) % 3;  // its own x and y, right-handed about z
      Vec3 ax = b.axes.col(u);
      double width = 2 * b.halfSize[u], depth = 2 * b.halfSize[w];
      if (b.axes(2, j) < 0) std::swap(width, depth), ax = b.axes.col(w);
      double turn = std::atan2(ax.y(), ax.x()) * kDeg;
      // The turn in (-45, 45]: a quarter turn swaps the sizes.
      while (turn > 45.0) turn -= 90.0, std::swap(width, depth);
      while (turn <= -45.0) turn += 90.0, std::swap(width, depth);
      pos(leaf.at[0], 0, "x", b.center.x(), false);
      pos(leaf.at[1], 1, "y", b.center.y(), false);
      pos(leaf.lo[2], 2, "z0", b.center.z() - b.halfSize[j], false);
      pos(leaf.hi[2], 2, "z1", b.center.z() + b.halfSize[j], false);
      f.push_back({&leaf.radius, Category::Step, "width", width});
      f.push_back({&leaf.radius2, Category::Step, "depth", depth});
      f.push_back({&leaf.angle, Category::Angle, "turn", turn});
      break;
    }
    case LeafForm::Axial: {
      Vec3 c;
      double h = 0.0;
      if (const auto* s = p.as<Cylinder>()) c = s->center, h = s->height;
      if (const auto* s = p.as<Cone>()) c = s->center, h = s->height;
      if (const auto* s = p.as<Torus>()) c = s->center;
      for (int k = 0; k < 3; ++k) {
        if (k != a) pos(leaf.at[std::size_t(k)], k, kAxisLetter[k], c[k], true);
      }
      const std::string l = kAxisLetter[a];
      if (const auto* t = p.as<Torus>()) {
        pos(leaf.at[std::size_t(a)], a, l, c[a], false);
        f.push_back({&leaf.radius, Category::Radius, "major_r", t->majorRadius});
        f.push_back({&leaf.radius2, Category::Radius, "minor_r", t->minorRadius});
        break;
      }
      pos(leaf.lo[std::size_t(a)], a, l + "0", c[a] - 0.5 * h, false);
      pos(leaf.hi[std::size_t(a)], a, l + "1", c[a] + 0.5 * h, false);
      if (const auto* s = p.as<Cylinder>()) {
        f.push_back({&leaf.radius, Category::Radius, "r", s->radius});
      } else if (const auto* s = p.as<Cone>()) {
        const bool up = s->axis[a] > 0.0;
        f.push_back({&leaf.radius, Category::Radius, "r0", up ? s->radiusBottom : s->radiusTop});
        f.push_back({&leaf.radius2, Category::Radius, "r1", up ? s->radiusTop : s->radiusBottom});
      }
      break;
    }
    case LeafForm::Sphere: {
      const auto& s = *p.as<Sphere>();
      for (int k = 0; k < 3; ++k) pos(leaf.at[std::size_t(k)], k, kAxisLetter[k], s.center[k], k < 2);
      f.push_back({&leaf.radius, Category::Radius, "r", s.radius});
      break;
    }
    case LeafForm::AlignedHalfSpace: {
      const auto& h = *p.as<HalfSpace>();
      const std::string l = kAxisLetter[a];
      if (leaf.flipped) {
        pos(leaf.lo[std::size_t(a)], a, l + "0", -h.offset, false);
      } else {
        pos(leaf.hi[std::size_t(a)], a, l + "1", h.offset, false);
      }
      break;
    }
    case LeafForm::TiltedHalfSpace: {
      const auto& h = *p.as<HalfSpace>();
      const double tilt = std::acos(std::clamp(h.normal.z(), -1.0, 1.0)) * kDeg;
      const double turn = std::atan2(h.normal.y(), h.normal.x()) * kDeg;
      f.push_back({&leaf.radius, Category::Step, "offset", h.offset});
      f.push_back({&leaf.angle, Category::Angle, "tilt", tilt});
      f.push_back({&leaf.angle2, Category::Angle, "turn", turn});
      break;
    }
    case LeafForm::Free:
      break;
  }
  return f;
}

// Points supporting each field of a leaf (indices as fieldsOf()), from the
// local gradients of the points on it.
std::vector<double> fieldSupport(const DesignedLeaf& leaf, const std::vector<Field>& fields,
                                 const std::vector<Vec3>& gradients) {
  std::vector<double> n(fields.size(), 0.0);
  const auto add = [&](const Expression* e) {
    for (std::size_t i = 0; i < fields.size(); ++i) {
      if (fields[i].expression == e) n[i] += 1.0;
    }
  };
  const auto addAll = [&]() {
    for (double& x : n) x += 1.0;
  };
  for (const Vec3& g : gradients) {
    const int a = leaf.axis;
    switch (leaf.form) {
      case LeafForm::AlignedBox: {
        int k = 0;
        g.cwiseAbs().maxCoeff(&k);
        add(g[k] > 0.0 ? &leaf.lo[std::size_t(k)] : &leaf.hi[std::size_t(k)]);
        break;
      }
      case LeafForm::TurnedBox:
        if (std::abs(g.z()) > kCapCosine) {
          add(g.z() > 0.0 ? &leaf.lo[2] : &leaf.hi[2]);
        } else {
          add(&leaf.at[0]), add(&leaf.at[1]), add(&leaf.radius), add(&leaf.radius2), add(&leaf.angle);
        }
        break;
      case LeafForm::Axial:
        if (leaf.type != PrimitiveType::Torus && std::abs(g[a]) > kCapCosine) {
          add(g[a] > 0.0 ? &leaf.lo[std::size_t(a)] : &leaf.hi[std::size_t(a)]);
        } else if (leaf.type == PrimitiveType::Torus) {
          addAll();
        } else {
          for (int k = 0; k < 3; ++k) {
            if (k != a) add(&leaf.at[std::size_t(k)]);
          }
          add(&leaf.radius);
          add(&leaf.radius2);
        }
        break;
      default:
        addAll();
    }
  }
  return n;
}

// A cone's cap that no point holds can slide along the cone: moved to the
// nearest whole unit along the axis (its radius following the slope), its
// numbers become the ones the cone was drawn with when it was drawn there.
void slideFreeConeCaps(const DesignedLeaf& leaf, std::vector<Field>& fields,
                       const std::vector<double>& support) {
  if (leaf.form != LeafForm::Axial || leaf.type != PrimitiveType::Cone) return;
  const auto find = [&](const Expression* e) {
    for (std::size_t k = 0; k < fields.size(); ++k) {
      if (fields[k].expression == e) return k;
    }
    return fields.size();
  };
  const std::size_t lo = find(&leaf.lo[std::size_t(leaf.axis)]),
                    hi = find(&leaf.hi[std::size_t(leaf.axis)]), r0 = find(&leaf.radius),
                    r1 = find(&leaf.radius2);
  if (hi >= fields.size() || r1 >= fields.size()) return;
  const double z0 = fields[lo].value, z1 = fields[hi].value;
  const double slope = (fields[r1].value - fields[r0].value) / (z1 - z0);
  const auto slide = [&](std::size_t z, std::size_t r) {
    if (support[z] > 0.0) return;
    const double to = std::round(fields[z].value);
    const double radius = fields[r].value + slope * (to - fields[z].value);
    if (!(radius >= 0.0)) return;
    fields[z].value = to;
    fields[r].value = radius;
  };
  slide(lo, r0);
  slide(hi, r1);
  if (!(fields[hi].value > fields[lo].value)) {  // undo: the cone would vanish
    fields[lo].value = z0;
    fields[hi].value = z1;
    fields[r0].value = fields[r1].value - slope * (z1 - z0);
  }
}

std::string plural(const std::string& role, int n) {
  if (n == 1) return "1 " + role;
  if (!role.empty() && (role.back() == 's' || role.back() == 'h')) return std::to_string(n) + " " + role + "es";
  return std::to_string(n) + " " + role + "s";
}

// The grid the IoU against the fitted tree is measured on, and the fitted
// tree's inside flags on it.
struct IouGrid {
  std::vector<Vec3> points;
  std::vector<char> fittedInside;
  int fittedCount = 0;
};

IouGrid iouGrid(const CsgTree& local, int resolution) {
  IouGrid g;
  const Aabb e = exportExtent(local);
  const Aabb box = e.grown(0.01 * e.diagonal());
  const double cell = box.size().maxCoeff() / std::max(resolution, 4);
  const Vec3 size = box.size();
  const int nx = std::max(1, int(std::ceil(size.x() / cell)));
  const int ny = std::max(1, int(std::ceil(size.y() / cell)));
  const int nz = std::max(1, int(std::ceil(size.z() / cell)));
  g.points.reserve(std::size_t(nx) * ny * nz);
  for (int i = 0; i < nx; ++i)
    for (int j = 0; j < ny; ++j)
      for (int k = 0; k < nz; ++k)
        g.points.push_back(box.min + cell * Vec3(i + 0.5, j + 0.5, k + 0.5));
  std::vector<double> f(g.points.size());
  local.values(g.points, f);
  g.fittedInside.resize(f.size());
  for (std::size_t i = 0; i < f.size(); ++i) {
    g.fittedInside[i] = f[i] >= 0.0;
    g.fittedCount += g.fittedInside[i];
  }
  return g;
}

bool validPrimitive(const Primitive& p) {
  try {
    p.validate();
  } catch (const std::invalid_argument&) {
    return false;
  }
  return true;
}

// Rebuilds `node` with each leaf replaced by make(leaf): its primitive and name.
template <class Make>
NodePtr rebuilt(const NodePtr& node, const Make& make, std::unordered_map<const Node*, NodePtr>& done) {
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
      const Vec3 n(std::sin(tilt) * std::cos(turn), std::sin(tilt) * std::sin(turn), std::cos(tilt));
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

namespace {

// Builds the designed tree; the parts of designTree() in order.
class Designer {
 public:
  Designer(const CsgTree& fitted, const PartFrame& frame, std::span<const Vec3> points,
           const DesignOptions& options)
      : options_(options), points_(points) {
    d_.fitted = fitted;
    d_.frame = frame;
    local_ = treeInFrame(fitted, frame);
    localPoints_.reserve(points.size());
    for (const Vec3& p : points) localPoints_.push_back(frame.toLocal(p));
    diagonal_ = exportExtent(local_).diagonal();
  }

  // `reshape`: find patterns and slide free cone caps (kept only when the
  // tree keeps its shape with them).
  DesignedTree run(bool reshape = true) {
    slide_ = reshape;
    makeLeaves();
    if (reshape) findLeafPatterns();
    makeSlots();
    groupSlots();
    if (reshape && !keepsShape()) {
      return Designer(d_.fitted, d_.frame, points_, options_).run(false);
    }
    chooseUnits();
    if (options_.snap) snap();
    mergeEqualSnapped();
    nameParameters();
    measure();
    return std::move(d_);
  }

 private:
  void makeLeaves() {
    const std::vector<const Node*> world = uniqueLeaves(d_.fitted);
    const std::vector<const Node*> local = uniqueLeaves(local_);
    const LeafRoles roles = leafRoles(d_.fitted);
    d_.leaves.resize(world.size());
    std::map<std::string, int> roleCount, roleSeen;
    for (std::size_t i = 0; i < world.size(); ++i) {
      DesignedLeaf& l = d_.leaves[i];
      l.node = world[i];
      localIndex_[local[i]] = int(i);
      l.cuts = roles.removing.count(world[i]) > 0;
      l.adds = roles.adding.count(world[i]) > 0 || !l.cuts;
      l.role = roleName(local[i]->primitive, l.cuts && !l.adds, diagonal_);
      classify(l, local[i]->primitive, options_.alignTolerance);
      ++roleCount[l.role];
    }
    for (DesignedLeaf& l : d_.leaves) {
      l.name = roleCount[l.role] == 1 ? l.role : l.role + "_" + std::to_string(++roleSeen[l.role]);
    }
    // Points on each leaf, with their local gradients.
    gradients_.resize(d_.leaves.size());
    if (!localPoints_.empty()) {
      const PointSupport support = pointSupport(local_, localPoints_);
      d_.noise = support.noise;
      for (std::size_t i = 0; i < localPoints_.size(); ++i) {
        if (support.leaf[i]) gradients_[std::size_t(localIndex_.at(support.leaf[i]))].push_back(support.gradient[i]);
      }
    }
  }

  // Sibling leaves on the same side of one operation, used once each.
  void findLeafPatterns() {
    std::map<const Node*, int> uses;
    for (const Node* leaf : local_.leaves()) ++uses[leaf];
    std::vector<std::vector<int>> groups;
    std::vector<const Node*> stack = {local_.root().get()};
    while (!stack.empty()) {
      const Node* n = stack.back();
      stack.pop_back();
      if (n->kind == NodeKind::Primitive) continue;
      std::vector<int> first, rest;
      for (std::size_t i = 0; i < n->children.size(); ++i) {
        const Node* c = n->children[i].get();
        if (c->kind != NodeKind::Primitive) {
          stack.push_back(c);
          continue;
        }
        if (uses[c] != 1) continue;
        const int index = localIndex_.at(c);
        if (d_.leaves[std::size_t(index)].form == LeafForm::Free) continue;
        (n->kind == NodeKind::Difference && i == 0 ? first : rest).push_back(index);
      }
      groups.push_back(first);
      groups.push_back(rest);
    }
    PatternOptions po;
    po.tolerance = options_.patternTolerance * diagonal_;
    for (const auto& group : groups) {
      if (group.size() < 2) continue;
      std::vector<PatternCandidate> prims;
      for (int i : group) prims.push_back({d_.leaves[std::size_t(i)].local, looseCaps(i)});
      for (const FoundPattern& f : findPatterns(prims, po)) {
        found_.push_back(f);
        for (int& m : found_.back().members) m = group[std::size_t(m)];
      }
    }
    // Tree order of their first members.
    std::sort(found_.begin(), found_.end(), [](const FoundPattern& a, const FoundPattern& b) {
      return *std::min_element(a.members.begin(), a.members.end()) <
             *std::min_element(b.members.begin(), b.members.end());
    });
  }

  // The radius an angle of the leaf is read at: half a turned box's width.
  double leverOf(const DesignedLeaf& l) const {
    if (l.form == LeafForm::TiltedHalfSpace) return 0.5 * diagonal_;
    if (l.form != LeafForm::TurnedBox) return 1.0;
    const Box& b = *l.local.as<Box>();
    return std::max(b.halfSize.maxCoeff(), 1e-12);
  }

  // A cylinder that only cuts and whose caps no point holds (it goes
  // through): its length past the part is free.
  bool looseCaps(int i) {
    DesignedLeaf& l = d_.leaves[std::size_t(i)];
    if (localPoints_.empty() || l.type != PrimitiveType::Cylinder || l.form != LeafForm::Axial ||
        l.adds || !l.cuts) {
      return false;
    }
    const std::vector<Field> fields = fieldsOf(l);
    const std::vector<double> n = fieldSupport(l, fields, gradients_[std::size_t(i)]);
    for (std::size_t k = 0; k < fields.size(); ++k) {
      if ((fields[k].expression == &l.lo[std::size_t(l.axis)] ||
           fields[k].expression == &l.hi[std::size_t(l.axis)]) && n[k] > 0.0) {
        return false;
      }
    }
    return true;
  }

  int addSlot(Category c, double value, double support, const std::string& name, int leaf,
              double lever = 1.0) {
    Slot s;
    s.category = c;
    s.value = value;
    s.support = support;
    s.lever = lever;
    s.name = name;
    if (leaf >= 0) s.leaves.insert(leaf);
    slots_.push_back(s);
    return int(slots_.size()) - 1;
  }

  void makeSlots() {
    std::vector<int> patternOf(d_.leaves.size(), -1);
    for (std::size_t p = 0; p < found_.size(); ++p) {
      for (int m : found_[p].members) patternOf[std::size_t(m)] = int(p);
    }
    std::vector<char> done(d_.leaves.size(), 0);
    for (std::size_t i = 0; i < d_.leaves.size(); ++i) {
      if (done[i]) continue;
      if (patternOf[i] >= 0) {
        makePatternSlots(found_[std::size_t(patternOf[i])]);
        for (int m : found_[std::size_t(patternOf[i])].members) done[std::size_t(m)] = 1;
        continue;
      }
      DesignedLeaf& l = d_.leaves[i];
      std::vector<Field> fields = fieldsOf(l);
      const std::vector<double> n = fieldSupport(l, fields, gradients_[i]);
      if (!localPoints_.empty() && slide_) slideFreeConeCaps(l, fields, n);
      for (std::size_t k = 0; k < fields.size(); ++k) {
        *fields[k].expression = Expression::of(addSlot(fields[k].category, fields[k].value, n[k],
                                                       l.name + "_" + fields[k].name, int(i),
                                                       leverOf(l)));
      }
    }
  }

  void makePatternSlots(const FoundPattern& f) {
    // Members named in the pattern's order (the names they had, sorted).
    {
      std::vector<std::string> names;
      for (int m : f.members) names.push_back(d_.leaves[std::size_t(m)].name);
      std::sort(names.begin(), names.end(), [](const std::string& a, const std::string& b) {
        return a.size() != b.size() ? a.size() < b.size() : a < b;
      });
      for (std::size_t i = 0; i < names.size(); ++i) {
        d_.leaves[std::size_t(f.members[i])].name = names[i];
      }
    }
    DesignedPattern p;
    const DesignedLeaf& first = d_.leaves[std::size_t(f.members.front())];
    p.kind = f.kind == FoundPatternKind::Circular  ? PatternKind::Circular
             : f.kind == FoundPatternKind::Lattice ? PatternKind::Lattice
                                                   : PatternKind::Row;
    const std::string base = first.role == "hole" ? "bolt" : first.role;
    p.name = base + (p.kind == PatternKind::Circular ? "_circle"
                     : p.kind == PatternKind::Lattice ? "_grid" : "_row");
    for (const DesignedPattern& other : d_.patterns) {
      if (other.name == p.name) p.name += "_" + std::to_string(d_.patterns.size() + 1);
    }
    p.members = f.members;
    const int index = int(d_.patterns.size());
    const int n = int(f.members.size());
    // Member fields: one slot each, the members' mean (positions less their
    // offsets in the pattern), supported by every member's points.
    std::vector<std::vector<Field>> fields;
    std::vector<std::vector<double>> support;
    for (int m : f.members) {
      fields.push_back(fieldsOf(d_.leaves[std::size_t(m)]));
      support.push_back(fieldSupport(d_.leaves[std::size_t(m)], fields.back(), gradients_[std::size_t(m)]));
      if (!localPoints_.empty() && slide_) {
        slideFreeConeCaps(d_.leaves[std::size_t(m)], fields.back(), support.back());
      }
    }
    double crossSupport = 0.0;
    for (std::size_t k = 0; k < fields.front().size(); ++k) {
      const Field& f0 = fields.front()[k];
      double sum = 0.0, n_k = 0.0;
      for (int i = 0; i < n; ++i) {
        double value = fields[std::size_t(i)][k].value;
        if (f.kind != FoundPatternKind::Circular && f0.positionAxis >= 0) {
          const int a = f0.positionAxis;
          const int ii = i % f.count, jj = i / f.count;
          value -= ii * f.step[a] + jj * f.step2[a];
        }
        sum += value;
        n_k += support[std::size_t(i)][k];
      }
      if (f.kind == FoundPatternKind::Circular && f0.crossPosition) {
        crossSupport += n_k / 2;
        continue;  // placed by the pattern
      }
      const int s = addSlot(f0.category, sum / n, n_k, first.name + "_" + f0.name, f.members.front());
      for (int m : f.members) slots_[std::size_t(s)].leaves.insert(m);
      for (int i = 0; i < n; ++i) *fields[std::size_t(i)][k].expression = Expression::of(s);
    }
    const auto own = [&](int slot) {
      slots_[std::size_t(slot)].owner = p.name;
      return Expression::of(slot);
    };
    countSlots_.push_back(addSlot(Category::Count, f.count, kInf, p.name + "_count", -1));
    p.count = countSlots_.back();
    slots_[std::size_t(p.count)].owner = p.name;
    if (p.kind == PatternKind::Circular) {
      p.centerX = own(addSlot(Category::PositionX, f.center.x(), crossSupport, p.name + "_x", -1));
      p.centerY = own(addSlot(Category::PositionY, f.center.y(), crossSupport, p.name + "_y", -1));
      p.radius = own(addSlot(Category::Step, f.radius, crossSupport, p.name + "_r", -1));
      p.phase = own(addSlot(Category::Angle, f.phase, crossSupport, p.name + "_phase", -1, f.radius));
    } else {
      for (int a = 0; a < 3; ++a) {
        const double tol = options_.patternTolerance * diagonal_;
        if (std::abs(f.step[a]) > tol) {
          p.step[std::size_t(a)] = own(addSlot(Category::Step, f.step[a], kInf, p.name + "_d" + kAxisLetter[a], -1));
        }
        if (std::abs(f.step2[a]) > tol) {
          p.step2[std::size_t(a)] = own(addSlot(Category::Step, f.step2[a], kInf, p.name + "_d" + kAxisLetter[a], -1));
        }
      }
      if (p.kind == PatternKind::Lattice) {
        countSlots_.push_back(addSlot(Category::Count, f.count2, kInf, p.name + "_count2", -1));
        p.count2 = countSlots_.back();
        slots_[std::size_t(p.count2)].owner = p.name;
      }
    }
    for (int i = 0; i < n; ++i) {
      DesignedLeaf& l = d_.leaves[std::size_t(f.members[std::size_t(i)])];
      l.pattern = index;
      l.member = i;
    }
    d_.patterns.push_back(p);
  }

  // Slots of one category within groupTolerance become one parameter.
  void groupSlots() {
    const double tol = options_.groupTolerance * diagonal_;
    std::vector<int> order(slots_.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = int(i);
    std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
      const Slot &x = slots_[std::size_t(a)], &y = slots_[std::size_t(b)];
      if (x.category != y.category) return x.category < y.category;
      return x.value < y.value;
    });
    std::vector<int> paramOf(slots_.size(), -1);
    std::vector<std::vector<int>> members;
    for (std::size_t k = 0; k < order.size(); ++k) {
      const Slot& s = slots_[std::size_t(order[k])];
      const bool joins = k > 0 && s.category != Category::Count && s.category != Category::Step &&
                         slots_[std::size_t(order[k - 1])].category == s.category &&
                         s.value - slots_[std::size_t(order[k - 1])].value <= tol;
      if (!joins) members.emplace_back();
      members.back().push_back(order[k]);
    }
    // Parameters in order of their first slot (tree order).
    std::sort(members.begin(), members.end(), [](const auto& a, const auto& b) {
      return *std::min_element(a.begin(), a.end()) < *std::min_element(b.begin(), b.end());
    });
    for (auto& group : members) {
      std::sort(group.begin(), group.end());
      const int index = int(d_.parameters.size());
      DesignParameter p;
      const Slot& first = slots_[std::size_t(group.front())];
      p.name = first.name;
      p.kind = first.category == Category::Angle   ? ParameterKind::Angle
               : first.category == Category::Count ? ParameterKind::Count
                                                   : ParameterKind::Length;
      double sum = 0.0, support = 0.0;
      Slot merged = first;
      for (int s : group) {
        sum += slots_[std::size_t(s)].value;
        support += slots_[std::size_t(s)].support;
        paramOf[std::size_t(s)] = index;
        merged.leaves.insert(slots_[std::size_t(s)].leaves.begin(), slots_[std::size_t(s)].leaves.end());
      }
      p.fitted = sum / double(group.size());
      p.value = p.fitted;
      p.uncertainty = uncertainty(support, first.lever, p.kind);
      merged.support = support;
      d_.parameters.push_back(p);
      paramSlots_.push_back(merged);
    }
    remap(paramOf);
  }

  double uncertainty(double support, double lever, ParameterKind kind) const {
    if (kind == ParameterKind::Count) return 0.0;
    double u = 0.0;
    if (localPoints_.empty()) {
      u = options_.treeUncertainty * diagonal_;
    } else {
      u = support > 0.0 ? options_.confidence * d_.noise / std::sqrt(support) : kInf;
      u = std::max(u, 1e-9 * diagonal_);
    }
    return kind == ParameterKind::Angle ? u / std::max(lever, 1e-12) * kDeg : u;
  }

  // Rewrites every expression through `map` (old index -> new index).
  void remap(const std::vector<int>& map) {
    const auto fix = [&](Expression& e) {
      for (auto& t : e.terms) t.second = map[std::size_t(t.second)];
      // Terms on one parameter add up.
      std::map<int, double> sum;
      for (const auto& t : e.terms) sum[t.second] += t.first;
      if (sum.size() != e.terms.size()) {
        e.terms.clear();
        for (const auto& [p, c] : sum) {
          if (c != 0.0) e.terms.emplace_back(c, p);
        }
      }
    };
    for (DesignedLeaf& l : d_.leaves) {
      for (auto* arr : {&l.lo, &l.hi, &l.at}) {
        for (Expression& e : *arr) fix(e);
      }
      fix(l.radius);
      fix(l.radius2);
      fix(l.angle);
      fix(l.angle2);
    }
    for (DesignedPattern& p : d_.patterns) {
      for (Expression* e : {&p.centerX, &p.centerY, &p.radius, &p.phase}) fix(*e);
      for (auto* arr : {&p.step, &p.step2}) {
        for (Expression& e : *arr) fix(e);
      }
      if (p.count >= 0) p.count = map[std::size_t(p.count)];
      if (p.count2 >= 0) p.count2 = map[std::size_t(p.count2)];
    }
  }

  void chooseUnits() {
    int mm = 0, inch = 0;
    for (const DesignParameter& p : d_.parameters) {
      if (p.kind != ParameterKind::Length || !std::isfinite(p.uncertainty)) continue;
      if (const auto v = simplestLength(p.fitted, p.uncertainty, UnitSystem::Millimetre)) {
        mm += ladderRung(*v, UnitSystem::Millimetre) <= 1;
      }
      if (const auto v = simplestLength(p.fitted, p.uncertainty, UnitSystem::Inch)) {
        inch += ladderRung(*v, UnitSystem::Inch) <= 4;
      }
    }
    d_.units = inch > mm ? UnitSystem::Inch : UnitSystem::Millimetre;
  }

  // The leaves whose primitives depend on parameter p.
  std::set<int> leavesOf(int p) const {
    std::set<int> out;
    const auto uses = [&](const Expression& e) {
      return std::any_of(e.terms.begin(), e.terms.end(), [&](const auto& t) { return t.second == p; });
    };
    for (std::size_t i = 0; i < d_.leaves.size(); ++i) {
      const DesignedLeaf& l = d_.leaves[i];
      bool u = uses(l.radius) || uses(l.radius2) || uses(l.angle) || uses(l.angle2);
      for (int k = 0; k < 3; ++k) u = u || uses(l.lo[k]) || uses(l.hi[k]) || uses(l.at[k]);
      if (l.pattern >= 0) {
        const DesignedPattern& pat = d_.patterns[std::size_t(l.pattern)];
        u = u || uses(pat.centerX) || uses(pat.centerY) || uses(pat.radius) || uses(pat.phase) ||
            pat.count == p || pat.count2 == p;
        for (int k = 0; k < 3; ++k) u = u || uses(pat.step[k]) || uses(pat.step2[k]);
      }
      if (u) out.insert(int(i));
    }
    return out;
  }

  // A pattern shares its members' values (their means), a cone's free cap
  // slides: the tree must keep its shape with them.
  bool keepsShape() {
    grid_ = iouGrid(local_, options_.iouResolution);
    if (!localPoints_.empty()) baseDistance_ = meanDistance(local_, true);
    std::vector<int> all(d_.parameters.size());
    for (std::size_t i = 0; i < all.size(); ++i) all[i] = int(i);
    return check(all) >= 0.0;
  }

  // The test a set of values must pass: valid primitives, IoU against the
  // fitted tree, the points' mean distance. Returns the IoU (-1: fails).
  double check(const std::vector<int>& changed) {
    const IouGrid& grid = grid_;
    std::set<int> affected;
    for (int p : changed) {
      const std::set<int> l = leavesOf(p);
      affected.insert(l.begin(), l.end());
    }
    Aabb region;
    for (int i : affected) {
      const Primitive now = d_.localPrimitive(i);
      if (!validPrimitive(now)) return -1.0;
      region.extend(now.bounds());
      region.extend(d_.leaves[std::size_t(i)].local.bounds());
    }
    if (affected.empty()) return 1.0;
    region = region.grown(1e-9 * diagonal_);
    const CsgTree tree = d_.localTree();
    // IoU: only grid points in the region can change.
    std::vector<Vec3> pts;
    std::vector<std::size_t> idx;
    for (std::size_t i = 0; i < grid.points.size(); ++i) {
      if (region.contains(grid.points[i])) {
        pts.push_back(grid.points[i]);
        idx.push_back(i);
      }
    }
    std::vector<double> f(pts.size());
    tree.values(pts, f);
    long inter = grid.fittedCount, uni = grid.fittedCount;
    for (std::size_t k = 0; k < pts.size(); ++k) {
      const bool a = grid.fittedInside[idx[k]], b = f[k] >= 0.0;
      inter += (a && b) - a;
      uni += (a || b) - a;
    }
    const double iou = uni > 0 ? double(inter) / double(uni) : 1.0;
    if (iou < options_.minIou) return -1.0;
    if (!localPoints_.empty()) {
      // Only points near the changed primitives move: those in their bounds
      // grown by 2 % of D are measured again, the others keep their distance.
      const Aabb near = region.grown(0.02 * diagonal_);
      std::vector<Vec3> moved;
      double before = 0.0;
      for (std::size_t i = 0; i < localPoints_.size(); ++i) {
        if (!near.contains(localPoints_[i])) continue;
        moved.push_back(localPoints_[i]);
        before += baseAbs_[i];
      }
      std::vector<double> g(moved.size());
      tree.values(moved, g);
      double after = 0.0;
      for (double x : g) after += std::abs(x);
      const double mean = baseDistance_ + (after - before) / double(localPoints_.size());
      const double noise = std::max(d_.noise, options_.minNoise * diagonal_);
      if (mean > baseDistance_ + options_.fitnessSlack * noise) return -1.0;
    }
    return iou;
  }

  void snap() {
    if (grid_.points.empty()) grid_ = iouGrid(local_, options_.iouResolution);
    if (!localPoints_.empty()) baseDistance_ = meanDistance(local_, true);
    std::vector<std::optional<double>> candidate(d_.parameters.size());
    std::vector<int> all;
    for (std::size_t i = 0; i < d_.parameters.size(); ++i) {
      const DesignParameter& p = d_.parameters[i];
      if (p.kind == ParameterKind::Count) continue;
      candidate[i] = p.kind == ParameterKind::Angle ? simplestAngle(p.fitted, p.uncertainty)
                                                    : simplestLength(p.fitted, p.uncertainty, d_.units);
      if (candidate[i] && *candidate[i] != p.fitted) all.push_back(int(i));
      if (candidate[i] && *candidate[i] == p.fitted) d_.parameters[i].snapped = true;
    }
    const auto apply = [&](const std::vector<int>& set, bool on) {
      for (int i : set) {
        d_.parameters[std::size_t(i)].value = on ? *candidate[std::size_t(i)] : d_.parameters[std::size_t(i)].fitted;
      }
    };
    apply(all, true);
    if (check(all) < 0.0) {
      apply(all, false);
      // One group at a time; then the ones that pass, together, dropping the
      // costliest until they pass.
      std::vector<std::pair<double, int>> passing;
      for (int i : all) {
        apply({i}, true);
        const double iou = check({i});
        apply({i}, false);
        if (iou >= 0.0) passing.emplace_back(iou, i);
      }
      std::stable_sort(passing.begin(), passing.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
      all.clear();
      for (const auto& [iou, i] : passing) all.push_back(i);
      apply(all, true);
      while (!all.empty() && check(all) < 0.0) {
        apply({all.back()}, false);
        all.pop_back();
      }
    }
    for (int i : all) d_.parameters[std::size_t(i)].snapped = true;
  }

  // The points' mean |f| to `tree`; `keep`: also remember each point's |f|
  // as the fitted tree's.
  double meanDistance(const CsgTree& tree, bool keep = false) {
    std::vector<double> g(localPoints_.size());
    tree.values(localPoints_, g);
    double mean = 0.0;
    for (double& x : g) {
      x = std::abs(x);
      mean += x;
    }
    if (keep) baseAbs_ = g;
    return g.empty() ? 0.0 : mean / double(g.size());
  }

  // Snapped parameters of one kind of position or radius with one value
  // become one (coplanar faces, coaxial axes, equal radii the fit left apart).
  void mergeEqualSnapped() {
    std::vector<int> map(d_.parameters.size());
    std::vector<DesignParameter> kept;
    std::vector<Slot> keptSlots;
    std::map<std::pair<int, double>, int> seen;
    for (std::size_t i = 0; i < d_.parameters.size(); ++i) {
      const DesignParameter& p = d_.parameters[i];
      const Slot& s = paramSlots_[i];
      const bool mergeable = p.snapped && s.category <= Category::Radius && s.owner.empty();
      const auto key = std::make_pair(int(s.category), p.value);
      if (mergeable) {
        if (const auto it = seen.find(key); it != seen.end()) {
          map[i] = it->second;
          Slot& into = keptSlots[std::size_t(it->second)];
          into.leaves.insert(s.leaves.begin(), s.leaves.end());
          continue;
        }
        seen[key] = int(kept.size());
      }
      map[i] = int(kept.size());
      kept.push_back(p);
      keptSlots.push_back(s);
    }
    d_.parameters = std::move(kept);
    paramSlots_ = std::move(keptSlots);
    remap(map);
  }

  void nameParameters() {
    std::set<std::string> used;
    for (std::size_t i = 0; i < d_.parameters.size(); ++i) {
      DesignParameter& p = d_.parameters[i];
      std::string name = p.name;
      for (int k = 2; used.count(name); ++k) name = p.name + "_" + std::to_string(k);
      used.insert(name);
      p.name = name;
      const Slot& s = paramSlots_[i];
      if (!s.owner.empty() && s.leaves.empty()) {
        p.usedBy = s.owner;
        continue;
      }
      std::map<std::string, int> roles;
      std::vector<std::string> order;
      for (int l : s.leaves) {
        const std::string& r = d_.leaves[std::size_t(l)].role;
        if (!roles.count(r)) order.push_back(r);
        ++roles[r];
      }
      for (const std::string& r : order) {
        if (!p.usedBy.empty()) p.usedBy += ", ";
        p.usedBy += plural(r, roles[r]);
      }
    }
  }

  void measure() {
    if (!options_.snap || d_.snappedCount() == 0) {
      d_.iouToFitted = 1.0;
    } else {
      if (grid_.points.empty()) grid_ = iouGrid(local_, options_.iouResolution);
      std::vector<int> allParams(d_.parameters.size());
      for (std::size_t i = 0; i < allParams.size(); ++i) allParams[i] = int(i);
      const double minIou = options_.minIou;
      const double slack = options_.fitnessSlack;
      options_.minIou = -1.0;
      options_.fitnessSlack = kInf;
      d_.iouToFitted = check(allParams);
      options_.minIou = minIou;
      options_.fitnessSlack = slack;
    }
    if (!localPoints_.empty()) {
      d_.meanDistanceFitted = meanDistance(local_);
      d_.meanDistanceDesigned = meanDistance(d_.localTree());
    }
  }

  DesignOptions options_;
  bool slide_ = true;
  std::span<const Vec3> points_;
  DesignedTree d_;
  CsgTree local_;
  std::vector<Vec3> localPoints_;
  double diagonal_ = 1.0;
  std::unordered_map<const Node*, int> localIndex_;
  std::vector<std::vector<Vec3>> gradients_;
  std::vector<FoundPattern> found_;
  std::vector<Slot> slots_;
  std::vector<Slot> paramSlots_;
  std::vector<int> countSlots_;
  IouGrid grid_;
  double baseDistance_ = 0.0;
  std::vector<double> baseAbs_;  // each point's |f| to the fitted tree
};

}  // namespace

DesignedTree designTree(const CsgTree& fitted, const PartFrame& frame,
                        std::span<const Vec3> points, const DesignOptions& options) {
  if (fitted.empty()) throw std::invalid_argument("designTree: empty tree");
  return Designer(fitted, frame, points, options).run();
}

DesignedTree designTree(const CsgTree& fitted, std::span<const Vec3> points,
                        const DesignOptions& options) {
  if (fitted.empty()) throw std::invalid_argument("designTree: empty tree");
  PartFrame frame = partFrame(fitted, points, options.frame);
  DesignedTree d = designTree(fitted, frame, points, options);
  if (!frame.spinFree) return d;
  // A turned part: x through the first member of a bolt circle about the
  // main axis, so that a turned copy of the part gives the same values.
  const double tol = options.patternTolerance * exportExtent(fitted).diagonal();
  for (const DesignedPattern& p : d.patterns) {
    const auto fittedOf = [&](const Expression& e) {
      double v = 0.0;
      for (const auto& [c, i] : e.terms) v += c * d.parameters[std::size_t(i)].fitted;
      return v;
    };
    if (p.kind != PatternKind::Circular || std::abs(fittedOf(p.centerX)) > tol ||
        std::abs(fittedOf(p.centerY)) > tol) {
      continue;
    }
    const double phase = fittedOf(p.phase) / kDeg;
    if (std::abs(phase) < 1e-12) return d;
    Mat3 spin = Mat3::Identity();
    spin << std::cos(phase), -std::sin(phase), 0, std::sin(phase), std::cos(phase), 0, 0, 0, 1;
    frame.rotation = nearestWorldAxes(frame.rotation * spin, options.frame.worldTolerance);
    frame.spinFree = false;
    return designTree(fitted, frame, points, options);
  }
  return d;
}

}  // namespace csgvox
