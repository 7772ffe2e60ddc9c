// A tree's primitives as functions of shared parameter blocks: direction
// classes and frames, plane offsets, axis lines, radii and centres.

#include "primitives/tree_parameters.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <numeric>
#include <stdexcept>
#include <unordered_map>
#include <utility>

#include "core/union_find.h"

namespace csgvox {
namespace {

using Kind = ParameterBlock::Kind;

// The parts of a leaf's primitive, as indices into its own block list.
struct LeafModel {
  PrimitiveType type = PrimitiveType::HalfSpace;
  std::vector<std::size_t> blocks;  // global block ids, distinct
  std::array<int, 3> cls = {-1, -1, -1};
  std::array<double, 3> sign = {1.0, 1.0, 1.0};
  int rotation = -1;
  std::array<std::array<int, 2>, 3> face = {{{-1, -1}, {-1, -1}, {-1, -1}}};  // low, high
  int line = -1;
  int offset = -1;  // half-space plane; torus centre along its axis
  std::array<int, 2> radius = {-1, -1};
  int centre = -1;
};

// One direction class: its unit direction, a basis across it, its frame,
// and the offsets and lines met so far along it.
struct DirectionClass {
  Vec3 d, u, v;
  int frame = -1;
  std::vector<std::pair<double, std::size_t>> offsets[3];  // by side: inward, none, outward
  std::vector<std::pair<Eigen::Vector2d, std::size_t>> lines;
};

Mat3 rotationOf(const double* w) {
  const Vec3 v(w[0], w[1], w[2]);
  const double angle = v.norm();
  if (angle == 0.0) return Mat3::Identity();
  return Eigen::AngleAxisd(angle, v / angle).toRotationMatrix();
}

}  // namespace

struct TreeParameters::Data {
  NodePtr root;
  Vec3 pivot;
  double lengthTolerance = 0.0;
  double angleTolerance = 0.0;
  bool rotate = true;
  std::vector<double> values;
  std::vector<ParameterBlock> blocks;
  std::vector<DirectionClass> classes;
  std::vector<std::ptrdiff_t> frameRotation;  // block of each frame root (-1: not made yet)
  std::vector<std::pair<double, std::size_t>> radii;
  std::vector<std::pair<Vec3, std::size_t>> centres;
  std::vector<const Node*> leaves;
  std::vector<int> polarities;  // per leaf
  std::vector<LeafModel> models;

  std::size_t addBlock(Kind kind, std::span<const double> start, bool constant = false) {
    ParameterBlock b;
    b.kind = kind;
    b.offset = values.size();
    b.size = int(start.size());
    b.constant = constant;
    values.insert(values.end(), start.begin(), start.end());
    blocks.push_back(b);
    return blocks.size() - 1;
  }

  // The class of a direction and the direction's sign in it.
  int classOf(const Vec3& direction, double& sign) {
    const Vec3 dir = direction.normalized();
    for (std::size_t k = 0; k < classes.size(); ++k) {
      if (classes[k].d.cross(dir).norm() <= angleTolerance) {
        sign = classes[k].d.dot(dir) < 0.0 ? -1.0 : 1.0;
        return int(k);
      }
    }
    DirectionClass c;
    c.d = dir;
    c.u = dir.unitOrthogonal();
    c.v = dir.cross(c.u);
    classes.push_back(std::move(c));
    sign = 1.0;
    return int(classes.size()) - 1;
  }

  std::size_t shared(std::vector<std::pair<double, std::size_t>>& seen, Kind kind, double value) {
    for (const auto& [x, b] : seen)
      if (std::abs(x - value) <= lengthTolerance) return b;
    const double start[1] = {value};
    const std::size_t b = addBlock(kind, start, kind == Kind::Radius && value <= lengthTolerance);
    seen.push_back({value, b});
    return b;
  }

  // `side`: +1 when the face's outward normal in the solid is +d, -1 when
  // it is -d, 0 for a torus centre. Faces share an offset only when they
  // face the same way: a cutter's cap exactly on the face it cuts through
  // would leave a surface of zero thickness.
  std::size_t offsetBlock(int k, double value, int side) {
    return shared(classes[std::size_t(k)].offsets[side + 1], Kind::Offset, value);
  }
  std::size_t radiusBlock(double value) { return shared(radii, Kind::Radius, value); }

  std::size_t lineBlock(int k, const Vec3& point) {
    DirectionClass& c = classes[std::size_t(k)];
    const Eigen::Vector2d ab(c.u.dot(point - pivot), c.v.dot(point - pivot));
    for (const auto& [x, b] : c.lines)
      if ((x - ab).norm() <= lengthTolerance) return b;
    const double start[2] = {ab.x(), ab.y()};
    const std::size_t b = addBlock(Kind::Line, start);
    c.lines.push_back({ab, b});
    return b;
  }

  std::size_t centreBlock(const Vec3& point) {
    for (const auto& [x, b] : centres)
      if ((x - point).norm() <= lengthTolerance) return b;
    const double start[3] = {point.x(), point.y(), point.z()};
    const std::size_t b = addBlock(Kind::Centre, start);
    centres.push_back({point, b});
    return b;
  }

  std::size_t rotationBlock(int k) {
    const int frame = classes[std::size_t(k)].frame;
    std::ptrdiff_t& b = frameRotation[std::size_t(frame)];
    if (b < 0) {
      const double zero[3] = {0.0, 0.0, 0.0};
      b = std::ptrdiff_t(addBlock(Kind::Rotation, zero, !rotate));
    }
    return std::size_t(b);
  }

  // Along class k: the offset of the point's projection.
  double along(int k, const Vec3& point) const {
    return classes[std::size_t(k)].d.dot(point - pivot);
  }

  LeafModel model(const Primitive& p, int polarity) {
    LeafModel m;
    m.type = p.type();
    const auto local = [&m](std::size_t block) {
      const auto it = std::find(m.blocks.begin(), m.blocks.end(), block);
      if (it != m.blocks.end()) return int(it - m.blocks.begin());
      m.blocks.push_back(block);
      return int(m.blocks.size()) - 1;
    };
    // A solid of revolution with caps: its axis's direction and line, and
    // the offsets of its two caps along the axis.
    const auto axial = [&](const Vec3& axis, const Vec3& center, double height) {
      const int k = m.cls[0] = classOf(axis, m.sign[0]);
      m.rotation = local(rotationBlock(k));
      m.line = local(lineBlock(k, center));
      const double mid = along(k, center);
      m.face[0][0] = local(offsetBlock(k, mid - 0.5 * height, -polarity));
      m.face[0][1] = local(offsetBlock(k, mid + 0.5 * height, polarity));
    };
    if (const auto* h = p.as<HalfSpace>()) {
      const int k = m.cls[0] = classOf(h->normal, m.sign[0]);
      m.rotation = local(rotationBlock(k));
      // normal·x = offset, normal = sign·d: d·(x − pivot) = sign·offset − d·pivot.
      m.offset = local(offsetBlock(k, m.sign[0] * h->offset - classes[std::size_t(k)].d.dot(pivot),
                                   polarity * int(m.sign[0])));
    } else if (const auto* b = p.as<Box>()) {
      for (int i = 0; i < 3; ++i)
        m.cls[std::size_t(i)] = classOf(b->axes.col(i), m.sign[std::size_t(i)]);
      m.rotation = local(rotationBlock(m.cls[0]));
      for (std::size_t i = 0; i < 3; ++i) {
        const double mid = along(m.cls[i], b->center);
        m.face[i][0] = local(offsetBlock(m.cls[i], mid - b->halfSize[int(i)], -polarity));
        m.face[i][1] = local(offsetBlock(m.cls[i], mid + b->halfSize[int(i)], polarity));
      }
    } else if (const auto* c = p.as<Cylinder>()) {
      axial(c->axis, c->center, c->height);
      m.radius[0] = local(radiusBlock(c->radius));
    } else if (const auto* c = p.as<Cone>()) {
      axial(c->axis, c->center, c->height);
      m.radius[0] = local(radiusBlock(c->radiusBottom));
      m.radius[1] = local(radiusBlock(c->radiusTop));
    } else if (const auto* s = p.as<Sphere>()) {
      m.centre = local(centreBlock(s->center));
      m.radius[0] = local(radiusBlock(s->radius));
    } else if (const auto* t = p.as<Torus>()) {
      const int k = m.cls[0] = classOf(t->axis, m.sign[0]);
      m.rotation = local(rotationBlock(k));
      m.line = local(lineBlock(k, t->center));
      m.offset = local(offsetBlock(k, along(k, t->center), 0));
      m.radius[0] = local(radiusBlock(t->majorRadius));
      m.radius[1] = local(radiusBlock(t->minorRadius));
    }
    return m;
  }
};

TreeParameters::TreeParameters(const CsgTree& tree, double scale, const Vec3& pivot,
                               const TreeParameterOptions& options)
    : data_(std::make_unique<Data>()) {
  if (tree.empty()) throw std::invalid_argument("TreeParameters: the tree is empty");
  if (!(scale > 0.0) || !std::isfinite(scale))
    throw std::invalid_argument("TreeParameters: the scale must be > 0");
  Data& d = *data_;
  d.root = tree.root();
  d.pivot = pivot;
  d.lengthTolerance = options.lengthTolerance * scale;
  d.angleTolerance = options.angleTolerance;
  d.rotate = options.rotate;
  d.leaves = tree.distinctLeaves();

  // Direction classes, then frames: classes that are orthogonal or axes of
  // one box turn together.
  std::vector<std::vector<int>> boxClasses;
  for (const Node* leaf : d.leaves) {
    std::vector<int> ks;
    double sign = 1.0;
    for (const Vec3& dir : leaf->primitive.directions()) ks.push_back(d.classOf(dir, sign));
    if (ks.size() == 3) boxClasses.push_back(ks);
  }
  std::vector<int> parent(d.classes.size());
  std::iota(parent.begin(), parent.end(), 0);
  const auto join = [&](int a, int b) {
    parent[std::size_t(findRoot(parent, a))] = findRoot(parent, b);
  };
  for (std::size_t a = 0; a < d.classes.size(); ++a)
    for (std::size_t b = a + 1; b < d.classes.size(); ++b)
      if (std::abs(d.classes[a].d.dot(d.classes[b].d)) <= d.angleTolerance) join(int(a), int(b));
  for (const std::vector<int>& ks : boxClasses) {
    join(ks[0], ks[1]);
    join(ks[0], ks[2]);
  }
  for (std::size_t k = 0; k < d.classes.size(); ++k) d.classes[k].frame = findRoot(parent, int(k));
  d.frameRotation.assign(d.classes.size(), -1);

  // Each leaf's polarity: -1 when it enters the solid complemented (a
  // cutter), as first met depth first.
  std::unordered_map<const Node*, int> polarity;
  const auto walk = [&polarity](const auto& self, const Node& node, int sign) -> void {
    if (node.kind == NodeKind::Primitive) {
      polarity.emplace(&node, sign);
      return;
    }
    for (std::size_t c = 0; c < node.children.size(); ++c) {
      const bool flips =
          node.kind == NodeKind::Complement || (node.kind == NodeKind::Difference && c > 0);
      self(self, *node.children[c], flips ? -sign : sign);
    }
  };
  walk(walk, *tree.root(), 1);
  for (const Node* leaf : d.leaves) {
    d.polarities.push_back(polarity.at(leaf));
    d.models.push_back(d.model(leaf->primitive, d.polarities.back()));
  }
  for (const LeafModel& m : d.models)
    for (const std::size_t b : m.blocks) ++d.blocks[b].users;
}

TreeParameters::~TreeParameters() = default;
TreeParameters::TreeParameters(TreeParameters&&) noexcept = default;
TreeParameters& TreeParameters::operator=(TreeParameters&&) noexcept = default;

const std::vector<double>& TreeParameters::values() const { return data_->values; }
const std::vector<ParameterBlock>& TreeParameters::blocks() const { return data_->blocks; }
std::size_t TreeParameters::leafCount() const { return data_->leaves.size(); }
std::span<const Node* const> TreeParameters::leaves() const { return data_->leaves; }

std::span<const int> TreeParameters::polarities() const { return data_->polarities; }

std::span<const std::size_t> TreeParameters::leafBlocks(std::size_t leaf) const {
  return data_->models.at(leaf).blocks;
}

std::size_t TreeParameters::sharedBlocks() const {
  return std::size_t(std::count_if(data_->blocks.begin(), data_->blocks.end(),
                                   [](const ParameterBlock& b) { return b.users > 1; }));
}

bool TreeParameters::leafPrimitive(std::size_t leaf, const double* const* block,
                                   Primitive& out) const {
  const Data& d = *data_;
  const LeafModel& m = d.models[leaf];
  const auto at = [&](int local, int i = 0) { return block[local][i]; };
  Mat3 rotation = Mat3::Identity();
  if (m.rotation >= 0) rotation = rotationOf(block[m.rotation]);
  const auto dir = [&](std::size_t i) {
    return Vec3(rotation * d.classes[std::size_t(m.cls[i])].d);
  };
  // The axis point of a line block at offset t along class cls[0].
  const auto axisPoint = [&](double t) {
    const DirectionClass& c = d.classes[std::size_t(m.cls[0])];
    return Vec3(d.pivot + rotation * (at(m.line, 0) * c.u + at(m.line, 1) * c.v + t * c.d));
  };
  switch (m.type) {
    case PrimitiveType::HalfSpace: {
      const Vec3 n = dir(0);
      out = HalfSpace{m.sign[0] * n, m.sign[0] * (at(m.offset) + n.dot(d.pivot))};
      return true;
    }
    case PrimitiveType::Box: {
      Box b;
      b.center = d.pivot;
      for (std::size_t i = 0; i < 3; ++i) {
        const double lo = at(m.face[i][0]), hi = at(m.face[i][1]);
        if (!(hi > lo)) return false;
        const Vec3 n = dir(i);
        b.center += 0.5 * (lo + hi) * n;
        b.axes.col(int(i)) = m.sign[i] * n;
        b.halfSize[int(i)] = 0.5 * (hi - lo);
      }
      out = b;
      return true;
    }
    case PrimitiveType::Cylinder: {
      const double lo = at(m.face[0][0]), hi = at(m.face[0][1]), r = at(m.radius[0]);
      if (!(hi > lo) || !(r > 0.0)) return false;
      out = Cylinder{axisPoint(0.5 * (lo + hi)), m.sign[0] * dir(0), r, hi - lo};
      return true;
    }
    case PrimitiveType::Cone: {
      const double lo = at(m.face[0][0]), hi = at(m.face[0][1]);
      const double r0 = at(m.radius[0]), r1 = at(m.radius[1]);
      if (!(hi > lo) || !(r0 >= 0.0) || !(r1 >= 0.0) || !(r0 + r1 > 0.0)) return false;
      out = Cone{axisPoint(0.5 * (lo + hi)), m.sign[0] * dir(0), r0, r1, hi - lo};
      return true;
    }
    case PrimitiveType::Sphere: {
      const double r = at(m.radius[0]);
      if (!(r > 0.0)) return false;
      out = Sphere{Vec3(at(m.centre, 0), at(m.centre, 1), at(m.centre, 2)), r};
      return true;
    }
    case PrimitiveType::Torus: {
      const double major = at(m.radius[0]), minor = at(m.radius[1]);
      if (!(minor > 0.0) || !(minor <= major)) return false;
      out = Torus{axisPoint(at(m.offset)), m.sign[0] * dir(0), major, minor};
      return true;
    }
  }
  return false;
}

bool TreeParameters::primitives(std::span<const double> values, std::vector<Primitive>& out) const {
  const Data& d = *data_;
  out.resize(d.leaves.size());
  std::vector<const double*> block;
  for (std::size_t l = 0; l < d.leaves.size(); ++l) {
    block.clear();
    for (const std::size_t b : d.models[l].blocks)
      block.push_back(values.data() + d.blocks[b].offset);
    if (!leafPrimitive(l, block.data(), out[l])) return false;
  }
  return true;
}

namespace {

NodePtr rebuilt(const NodePtr& node,
                const std::unordered_map<const Node*, const Primitive*>& leafOf,
                std::unordered_map<const Node*, NodePtr>& done) {
  if (const auto it = done.find(node.get()); it != done.end()) return it->second;
  NodePtr out;
  if (node->kind == NodeKind::Primitive) {
    out = std::make_shared<const Node>(*leafOf.at(node.get()), node->name);
  } else {
    std::vector<NodePtr> children;
    for (const NodePtr& c : node->children) children.push_back(rebuilt(c, leafOf, done));
    out = std::make_shared<const Node>(node->kind, std::move(children));
  }
  done.emplace(node.get(), out);
  return out;
}

}  // namespace

CsgTree TreeParameters::tree(std::span<const Primitive> primitives) const {
  const Data& d = *data_;
  if (primitives.size() != d.leaves.size())
    throw std::invalid_argument("TreeParameters::tree: one primitive per leaf expected");
  std::unordered_map<const Node*, const Primitive*> leafOf;
  for (std::size_t l = 0; l < d.leaves.size(); ++l) leafOf.emplace(d.leaves[l], &primitives[l]);
  std::unordered_map<const Node*, NodePtr> done;
  return CsgTree(rebuilt(d.root, leafOf, done));
}

}  // namespace csgvox
