// Ceres refinement of a tree's shared parameters on points through the
// tree's field.

#include "primitives/tree_fitting.h"

#include <ceres/cost_function.h>
#include <ceres/iteration_callback.h>
#include <ceres/loss_function.h>
#include <ceres/problem.h>
#include <ceres/solver.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <stdexcept>
#include <unordered_map>
#include <vector>

namespace csgvox {
namespace {

// The set operations with their partial derivatives, in the arithmetic of
// core/set_operations (the values are bit for bit CsgTree::value's).
struct Operations {
  SetOperationKind kind = SetOperationKind::Sardf;
  double radius = 1.0;

  SardfResult unite(double a, double b) const {
    switch (kind) {
      case SetOperationKind::MinMax:
        return b > a ? SardfResult{b, 0.0, 1.0} : SardfResult{a, 1.0, 0.0};
      case SetOperationKind::RFunction: {
        const double h = std::hypot(a, b);
        const double f = a + b + 1.0 * h;
        return h > 0.0 ? SardfResult{f, 1.0 + a / h, 1.0 + b / h} : SardfResult{f, 1.0, 1.0};
      }
      case SetOperationKind::Sardf:
        break;
    }
    return sardfUnite(a, b, radius);
  }
  SardfResult intersect(double a, double b) const {
    switch (kind) {
      case SetOperationKind::MinMax:
        return b < a ? SardfResult{b, 0.0, 1.0} : SardfResult{a, 1.0, 0.0};
      case SetOperationKind::RFunction: {
        const double h = std::hypot(a, b);
        const double f = a + b + -1.0 * h;
        return h > 0.0 ? SardfResult{f, 1.0 - a / h, 1.0 - b / h} : SardfResult{f, 1.0, 1.0};
      }
      case SetOperationKind::Sardf:
        break;
    }
    return sardfIntersect(a, b, radius);
  }
};

// Per-evaluation arrays of FlatTree.
struct Scratch {
  std::vector<double> value;  // per item
  std::vector<double> d1;     // per operand slot: ∂acc/∂acc_prev
  std::vector<double> d2;     // per operand slot: ∂acc/∂operand
  std::vector<double> leafValue;
  std::vector<double> leafAdjoint;
};

// The tree as items (one per node occurrence) over leaf slots, evaluated
// forward for the value and backward for ∂f/∂(each leaf's value).
class FlatTree {
 public:
  FlatTree(const CsgTree& tree, std::span<const Node* const> leaves) {
    std::unordered_map<const Node*, int> slot;
    for (std::size_t l = 0; l < leaves.size(); ++l) slot.emplace(leaves[l], int(l));
    leafCount_ = leaves.size();
    add(*tree.root(), slot);
  }

  void prepare(Scratch& s) const {
    s.value.resize(items_.size());
    s.d1.resize(kids_.size());
    s.d2.resize(kids_.size());
    s.leafValue.resize(leafCount_);
    s.leafAdjoint.resize(leafCount_);
  }

  // The field from s.leafValue (items' values and partials kept in s).
  double forward(const Operations& ops, Scratch& s) const { return forward(0, ops, s); }

  // s.leafAdjoint = ∂f/∂(leaf value), after forward().
  void backward(Scratch& s) const {
    std::fill(s.leafAdjoint.begin(), s.leafAdjoint.end(), 0.0);
    backward(0, 1.0, s);
  }

 private:
  struct Item {
    NodeKind kind = NodeKind::Primitive;
    int leaf = -1;
    int first = 0;  // first operand slot in kids_
    int count = 0;
  };

  int add(const Node& node, const std::unordered_map<const Node*, int>& slot) {
    const int i = int(items_.size());
    items_.push_back({node.kind, -1, 0, 0});
    if (node.kind == NodeKind::Primitive) {
      items_[std::size_t(i)].leaf = slot.at(&node);
      return i;
    }
    const int first = int(kids_.size());
    kids_.resize(kids_.size() + node.children.size());
    items_[std::size_t(i)].first = first;
    items_[std::size_t(i)].count = int(node.children.size());
    for (std::size_t c = 0; c < node.children.size(); ++c)
      kids_[std::size_t(first) + c] = add(*node.children[c], slot);
    return i;
  }

  double forward(int i, const Operations& ops, Scratch& s) const {
    const Item& it = items_[std::size_t(i)];
    double acc = 0.0;
    if (it.kind == NodeKind::Primitive) {
      acc = s.leafValue[std::size_t(it.leaf)];
    } else if (it.kind == NodeKind::Complement) {
      acc = -forward(kids_[std::size_t(it.first)], ops, s);
    } else {
      acc = forward(kids_[std::size_t(it.first)], ops, s);
      for (int j = 1; j < it.count; ++j) {
        const std::size_t k = std::size_t(it.first + j);
        const double v = forward(kids_[k], ops, s);
        const SardfResult r = it.kind == NodeKind::Union          ? ops.unite(acc, v)
                              : it.kind == NodeKind::Intersection ? ops.intersect(acc, v)
                                                                  : ops.intersect(acc, -v);
        acc = r.f;
        s.d1[k] = r.d1;
        s.d2[k] = it.kind == NodeKind::Difference ? -r.d2 : r.d2;
      }
    }
    s.value[std::size_t(i)] = acc;
    return acc;
  }

  void backward(int i, double adjoint, Scratch& s) const {
    if (adjoint == 0.0) return;
    const Item& it = items_[std::size_t(i)];
    if (it.kind == NodeKind::Primitive) {
      s.leafAdjoint[std::size_t(it.leaf)] += adjoint;
      return;
    }
    if (it.kind == NodeKind::Complement) {
      backward(kids_[std::size_t(it.first)], -adjoint, s);
      return;
    }
    double a = adjoint;
    for (int j = it.count - 1; j >= 1; --j) {
      const std::size_t k = std::size_t(it.first + j);
      backward(kids_[k], a * s.d2[k], s);
      a *= s.d1[k];
    }
    backward(kids_[std::size_t(it.first)], a, s);
  }

  std::vector<Item> items_;
  std::vector<int> kids_;
  std::size_t leafCount_ = 0;
};

// The faces of a primitive: a box's six (2·axis + 1 for the positive side),
// a cylinder's or cone's lateral surface (0) and caps (1 bottom, 2 top); the
// others are one face. A face's value is the signed distance to its whole
// surface (plane, infinite cylinder or cone), positive on the solid's side:
// a point is tied to the face it was scanned on, so a point just inside an
// edge is not read as lying on the other face (which would bias every face
// outwards on a noisy scan).
int faceCount(const Primitive& p) {
  switch (p.type()) {
    case PrimitiveType::Box:
      return 6;
    case PrimitiveType::Cylinder:
    case PrimitiveType::Cone:
      return 3;
    default:
      return 1;
  }
}

double faceValue(const Primitive& p, int face, const Vec3& x) {
  if (const auto* b = p.as<Box>()) {
    const int i = face / 2;
    const double local = b->axes.col(i).dot(x - b->center);
    return b->halfSize[i] + (face % 2 == 1 ? -local : local);
  }
  if (const auto* c = p.as<Cylinder>()) {
    const Vec3 w = x - c->center;
    const double z = c->axis.dot(w);
    if (face == 0) return c->radius - (w - z * c->axis).norm();
    return 0.5 * c->height + (face == 1 ? z : -z);
  }
  if (const auto* c = p.as<Cone>()) {
    const Vec3 w = x - c->center;
    const double z = c->axis.dot(w);
    if (face == 0) {
      const double slope = (c->radiusTop - c->radiusBottom) / c->height;
      const double r = c->radiusBottom + (z + 0.5 * c->height) * slope;
      return (r - (w - z * c->axis).norm()) / std::sqrt(1.0 + slope * slope);
    }
    return 0.5 * c->height + (face == 1 ? z : -z);
  }
  return p.value(x);
}

// The outward unit normal of a face at x (from its value's gradient).
Vec3 faceNormal(const Primitive& p, int face, const Vec3& x, double step) {
  Vec3 g;
  for (int k = 0; k < 3; ++k) {
    Vec3 d = Vec3::Zero();
    d[k] = step;
    g[k] = faceValue(p, face, x + d) - faceValue(p, face, x - d);
  }
  const double n = g.norm();
  return n > 0.0 ? Vec3(-g / n) : Vec3::Zero();
}

// The face of `p` a point with normal `n` (or none: zero) was scanned on: of
// the faces within `near` of it, the one whose normal agrees best, else the
// nearest.
int faceOf(const Primitive& p, const Vec3& x, const Vec3& n, double near, double step) {
  int best = 0;
  double bestScore = -std::numeric_limits<double>::infinity();
  for (int f = 0; f < faceCount(p); ++f) {
    const double v = std::abs(faceValue(p, f, x));
    const double score = v > near || n.isZero() ? -1e300 - v : faceNormal(p, f, x, step).dot(n);
    if (score > bestScore) {
      bestScore = score;
      best = f;
    }
  }
  return best;
}

// What every residual shares: the parameterisation, the tree, the current
// primitives (refreshed after each accepted step) and the scales.
struct FitContext {
  const TreeParameters* parameters = nullptr;
  const FlatTree* flat = nullptr;
  Operations ops;
  std::vector<Primitive> current;
  double invTolerance = 1.0;  // 1 / εd
  double lengthStep = 1e-6;   // central-difference step of lengths, units
  double angleStep = 1e-6;    // of rotation vectors, radians
};

Scratch& scratch(const FitContext& c) {
  thread_local Scratch s;
  c.flat->prepare(s);
  return s;
}

// The field at p (its leaves' values in s.leafValue) with `own` primitives
// for the active leaves.
double fieldAt(const FitContext& c, const Vec3& p, std::span<const int> active,
               std::span<const int> faces, std::span<const Primitive> own, Scratch& s) {
  for (std::size_t l = 0; l < c.current.size(); ++l) s.leafValue[l] = c.current[l].value(p);
  for (std::size_t a = 0; a < active.size(); ++a)
    s.leafValue[std::size_t(active[a])] = faceValue(own[a], faces[a], p);
  return c.flat->forward(c.ops, s);
}

// One point's residual: the field there / εd, each active leaf read on the
// face the point was scanned on. Its parameter blocks are those of the
// leaves the field depended on at the start (`active`); the other leaves
// hold the current state's primitives.
class PointResidual final : public ceres::CostFunction {
 public:
  PointResidual(const FitContext& context, const Vec3& point, std::vector<int> active,
                std::vector<int> faces, std::vector<std::size_t> blocks, double side)
      : c_(context),
        p_(point),
        side_(side),
        active_(std::move(active)),
        faces_(std::move(faces)),
        blocks_(std::move(blocks)) {
    set_num_residuals(1);
    for (const std::size_t b : blocks_)
      mutable_parameter_block_sizes()->push_back(c_.parameters->blocks()[b].size);
    // For each active leaf, the residual's index of each of its blocks.
    for (const int l : active_) {
      std::vector<int> where;
      for (const std::size_t b : c_.parameters->leafBlocks(std::size_t(l)))
        where.push_back(int(std::find(blocks_.begin(), blocks_.end(), b) - blocks_.begin()));
      where_.push_back(std::move(where));
    }
  }

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    Scratch& s = scratch(c_);
    std::array<Primitive, 8> ownStore;
    std::vector<Primitive> ownHeap;
    std::span<Primitive> own(ownStore.data(), std::min<std::size_t>(active_.size(), 8));
    if (active_.size() > 8) {
      ownHeap.resize(active_.size());
      own = ownHeap;
    }
    std::array<const double*, 16> ptr{};
    for (std::size_t a = 0; a < active_.size(); ++a) {
      for (std::size_t k = 0; k < where_[a].size(); ++k) ptr[k] = parameters[where_[a][k]];
      if (!c_.parameters->leafPrimitive(std::size_t(active_[a]), ptr.data(), own[a])) return false;
    }
    const double f = side_ != 0.0 ? side_ * faceValue(own[0], faces_[0], p_)
                                  : fieldAt(c_, p_, active_, faces_, own, s);
    residuals[0] = f * c_.invTolerance;
    if (jacobians == nullptr) return true;
    for (std::size_t r = 0; r < blocks_.size(); ++r) {
      if (jacobians[r] == nullptr) continue;
      std::fill(jacobians[r], jacobians[r] + c_.parameters->blocks()[blocks_[r]].size, 0.0);
    }
    if (side_ == 0.0) c_.flat->backward(s);
    // Central differences of each active leaf's distance in its parameters.
    std::array<double, 32> buffer{};
    for (std::size_t a = 0; a < active_.size(); ++a) {
      const double adjoint =
          (side_ != 0.0 ? side_ : s.leafAdjoint[std::size_t(active_[a])]) * c_.invTolerance;
      if (adjoint == 0.0) continue;
      const std::span<const std::size_t> leafBlocks =
          c_.parameters->leafBlocks(std::size_t(active_[a]));
      std::size_t used = 0;
      std::array<double*, 16> local{};
      for (std::size_t k = 0; k < leafBlocks.size(); ++k) {
        const int size = c_.parameters->blocks()[leafBlocks[k]].size;
        local[k] = buffer.data() + used;
        std::copy(parameters[where_[a][k]], parameters[where_[a][k]] + size, local[k]);
        used += std::size_t(size);
      }
      for (std::size_t k = 0; k < leafBlocks.size(); ++k) {
        double* jacobian = jacobians[where_[a][k]];
        if (jacobian == nullptr) continue;
        const ParameterBlock& block = c_.parameters->blocks()[leafBlocks[k]];
        const double h =
            block.kind == ParameterBlock::Kind::Rotation ? c_.angleStep : c_.lengthStep;
        for (int j = 0; j < block.size; ++j) {
          const double keep = local[k][j];
          Primitive plus, minus;
          local[k][j] = keep + h;
          const bool okPlus =
              c_.parameters->leafPrimitive(std::size_t(active_[a]), local.data(), plus);
          local[k][j] = keep - h;
          const bool okMinus =
              c_.parameters->leafPrimitive(std::size_t(active_[a]), local.data(), minus);
          local[k][j] = keep;
          double slope = 0.0;
          const int face = faces_[a];
          if (okPlus && okMinus) {
            slope = (faceValue(plus, face, p_) - faceValue(minus, face, p_)) / (2.0 * h);
          } else if (okPlus) {
            slope = (faceValue(plus, face, p_) - faceValue(own[a], face, p_)) / h;
          } else if (okMinus) {
            slope = (faceValue(own[a], face, p_) - faceValue(minus, face, p_)) / h;
          }
          jacobian[j] += adjoint * slope;
        }
      }
    }
    return true;
  }

 private:
  const FitContext& c_;
  Vec3 p_;
  double side_;  // ±1: the residual is the first active leaf's face value times this
  std::vector<int> active_;
  std::vector<int> faces_;
  std::vector<std::size_t> blocks_;
  std::vector<std::vector<int>> where_;
};

// Holds a block to its start: (value − start) / sigma · weight per value.
class PriorResidual final : public ceres::CostFunction {
 public:
  PriorResidual(const double* start, int size, double sigma, double weight)
      : start_(start, start + size), scale_(weight / sigma) {
    set_num_residuals(size);
    mutable_parameter_block_sizes()->push_back(size);
  }
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const int n = int(start_.size());
    for (int j = 0; j < n; ++j) residuals[j] = scale_ * (parameters[0][j] - start_[std::size_t(j)]);
    if (jacobians != nullptr && jacobians[0] != nullptr) {
      std::fill(jacobians[0], jacobians[0] + n * n, 0.0);
      for (int j = 0; j < n; ++j) jacobians[0][j * n + j] = scale_;
    }
    return true;
  }

 private:
  std::vector<double> start_;
  double scale_;
};

// Refreshes the context's current primitives after every accepted step.
class RefreshState final : public ceres::IterationCallback {
 public:
  RefreshState(FitContext& context, const std::vector<double>& values)
      : c_(context), values_(values) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary&) override {
    std::vector<Primitive> next;
    if (c_.parameters->primitives(values_, next)) c_.current = std::move(next);
    return ceres::SOLVER_CONTINUE;
  }

 private:
  FitContext& c_;
  const std::vector<double>& values_;
};

// Stops the solver when the run is cancelled (nothing usable) or past its
// deadline (the parameters reached so far are the result).
class StopWhenAsked final : public ceres::IterationCallback {
 public:
  explicit StopWhenAsked(const RunControl& control) : control_(control) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary&) override {
    if (control_.cancelled()) return ceres::SOLVER_ABORT;
    if (control_.pastDeadline()) return ceres::SOLVER_TERMINATE_SUCCESSFULLY;
    return ceres::SOLVER_CONTINUE;
  }

 private:
  const RunControl& control_;
};

// RMS of the field over the points with the given leaf primitives.
double rmsField(const FitContext& c, std::span<const Vec3> points,
                std::span<const Primitive> primitives) {
  std::vector<double> f(points.size());
  tbb::parallel_for(std::size_t{0}, points.size(), [&](std::size_t i) {
    Scratch& s = scratch(c);
    for (std::size_t l = 0; l < primitives.size(); ++l)
      s.leafValue[l] = primitives[l].value(points[i]);
    f[i] = c.flat->forward(c.ops, s);
  });
  double sum = 0.0;
  for (const double v : f) sum += v * v;
  return points.empty() ? 0.0 : std::sqrt(sum / double(points.size()));
}

// What the fit reads besides the problem: its context, the scan, the
// options, the leaves' primitives before the fit, and lengths in scan units.
struct FitInputs {
  const FitContext& c;
  const PointCloud& scan;
  const TreeFitOptions& options;
  std::span<const Primitive> input;
  double diagonal;
  double tolerance;                                            // εd
  std::span<const int> polarity = c.parameters->polarities();  // -1: a leaf enters complemented
  double exposed = 0.05 * tolerance;  // a face's foot this near the surface is on it
  double nearBand = options.nearDistance * tolerance;
  double cosLimit = std::cos(options.nearAngle * std::numbers::pi / 180.0);
};

// Where each point meets the tree: the leaves its residual depends on and
// the face each is read on (none: the point does not drive the fit), and
// side ≠ 0 where the residual is its first active leaf's face value times it.
struct PointLeaves {
  std::vector<std::vector<int>> active, faces;
  std::vector<double> side;
};

// The exposed face point i was scanned on: within the band, its normal (as
// the solid sees it) closest to the point's, and the tree's surface at the
// point's foot on it; none when no face is.
void chooseExposedFace(const FitInputs& in, std::size_t i, Scratch& s, PointLeaves& leaves) {
  const Vec3& p = in.scan.points[i];
  const Vec3& n = in.scan.normals[i];
  leaves.active[i].clear();
  leaves.faces[i].clear();
  double best = in.cosLimit;
  for (std::size_t l = 0; l < in.input.size(); ++l) {
    for (int k = 0; k < faceCount(in.input[l]); ++k) {
      const double v = faceValue(in.input[l], k, p);
      if (std::abs(v) > in.nearBand) continue;
      const Vec3 out = faceNormal(in.input[l], k, p, in.c.lengthStep);
      const double agree = in.polarity[l] * out.dot(n);
      if (agree <= best) continue;
      const Vec3 foot = p + v * out;
      for (std::size_t m = 0; m < in.input.size(); ++m) s.leafValue[m] = in.input[m].value(foot);
      if (std::abs(in.c.flat->forward(in.c.ops, s)) > in.exposed) continue;
      best = agree;
      leaves.active[i] = {int(l)};
      leaves.faces[i] = {k};
      leaves.side[i] = in.polarity[l];
    }
  }
}

// Point i must lie on its main leaf's face, its normal within nearAngle
// of the face's (a point just inside an edge, which the field reads on
// the other face, still counts on its own); else it has no leaves.
void keepOnMainFace(const FitInputs& in, std::size_t i, const Scratch& s, PointLeaves& leaves) {
  std::vector<int>& active = leaves.active[i];
  std::size_t main = 0;
  for (std::size_t a = 1; a < active.size(); ++a)
    if (std::abs(s.leafAdjoint[std::size_t(active[a])]) >
        std::abs(s.leafAdjoint[std::size_t(active[main])]))
      main = a;
  const std::size_t l = std::size_t(active[main]);
  const double side = s.leafAdjoint[l] < 0.0 ? -1.0 : 1.0;
  const Vec3& p = in.scan.points[i];
  if (side * faceNormal(in.input[l], leaves.faces[i][main], p, in.c.lengthStep)
                 .dot(in.scan.normals[i]) <
      in.cosLimit) {
    active.clear();
    leaves.faces[i].clear();
  }
}

// The points near the surface and the leaves the field depends on there.
PointLeaves pointLeaves(const FitInputs& in) {
  const std::span<const Vec3> points = in.scan.points;
  PointLeaves leaves{std::vector<std::vector<int>>(points.size()),
                     std::vector<std::vector<int>>(points.size()),
                     std::vector<double>(points.size(), 0.0)};
  const FlatTree& flat = *in.c.flat;
  tbb::parallel_for(std::size_t{0}, points.size(), [&](std::size_t i) {
    Scratch& s = scratch(in.c);
    for (std::size_t l = 0; l < in.input.size(); ++l) s.leafValue[l] = in.input[l].value(points[i]);
    if (std::abs(flat.forward(in.c.ops, s)) > in.options.nearDistance * in.tolerance) return;
    flat.backward(s);
    const Vec3 n = in.scan.hasNormals() ? in.scan.normals[i] : Vec3::Zero();
    for (std::size_t l = 0; l < in.input.size(); ++l) {
      if (std::abs(s.leafAdjoint[l]) <= 1e-9) continue;
      leaves.active[i].push_back(int(l));
      // The leaf's value is read on its face from here on.
      leaves.faces[i].push_back(faceOf(in.input[l], points[i],
                                       s.leafAdjoint[l] < 0.0 ? Vec3(-n) : n, in.nearBand,
                                       in.c.lengthStep));
    }
    if (leaves.active[i].empty() || !in.scan.hasNormals()) return;
    if (!in.options.throughField) {
      chooseExposedFace(in, i, s, leaves);
    } else {
      keepOnMainFace(in, i, s, leaves);
    }
  });
  return leaves;
}

// The points with leaves, thinned to an even subset of `maxPoints` at most.
std::vector<std::size_t> nearPoints(const PointLeaves& leaves, std::size_t maxPoints) {
  std::vector<std::size_t> near;
  for (std::size_t i = 0; i < leaves.active.size(); ++i)
    if (!leaves.active[i].empty()) near.push_back(i);
  if (near.size() > maxPoints) {
    std::vector<std::size_t> thinned(maxPoints);
    for (std::size_t k = 0; k < thinned.size(); ++k) thinned[k] = near[k * near.size() / maxPoints];
    near = std::move(thinned);
  }
  return near;
}

// The least-squares problem over the tree's parameter values.
struct FitProblem {
  std::vector<double> values;  // the blocks' values, moved by the solver
  ceres::HuberLoss loss;       // of the point residuals
  ceres::Problem problem;
};

// One residual per point of `near` over its active leaves' blocks.
void addPointResiduals(const FitInputs& in, const PointLeaves& leaves,
                       std::span<const std::size_t> near, FitProblem& fit) {
  const TreeParameters& parameters = *in.c.parameters;
  const std::vector<ParameterBlock>& blocks = parameters.blocks();
  for (const std::size_t i : near) {
    std::vector<std::size_t> pointBlocks;
    for (const int l : leaves.active[i])
      for (const std::size_t b : parameters.leafBlocks(std::size_t(l)))
        if (std::find(pointBlocks.begin(), pointBlocks.end(), b) == pointBlocks.end())
          pointBlocks.push_back(b);
    std::vector<double*> data;
    for (const std::size_t b : pointBlocks) data.push_back(fit.values.data() + blocks[b].offset);
    fit.problem.AddResidualBlock(
        new PointResidual(in.c, in.scan.points[i], leaves.active[i], leaves.faces[i],
                          std::move(pointBlocks), leaves.side[i]),
        &fit.loss, data);
  }
}

// The blocks the residuals use: constant ones held, radii kept above the
// length tolerance and, with a prior weight, each free block held to its
// start; the free values are counted in `out`.
void constrainBlocks(const FitInputs& in, FitProblem& fit, TreeFitResult& out) {
  const TreeParameters& parameters = *in.c.parameters;
  const TreeFitOptions& options = in.options;
  for (const ParameterBlock& b : parameters.blocks()) {
    double* data = fit.values.data() + b.offset;
    if (!fit.problem.HasParameterBlock(data)) continue;
    if (b.constant) {
      fit.problem.SetParameterBlockConstant(data);
    } else {
      out.parameters += std::size_t(b.size);
      if (b.kind == ParameterBlock::Kind::Radius)
        fit.problem.SetParameterLowerBound(data, 0,
                                           options.parameters.lengthTolerance * in.diagonal);
      if (options.priorWeight > 0.0) {
        // A turn moving the far end of the part by εd weighs as a shift by εd.
        const double sigma = b.kind == ParameterBlock::Kind::Rotation
                                 ? 2.0 * options.distanceTolerance
                                 : in.tolerance;
        fit.problem.AddResidualBlock(
            new PriorResidual(parameters.values().data() + b.offset, b.size, sigma,
                              std::sqrt(options.priorWeight)),
            nullptr, data);
      }
    }
  }
}

// The solver's settings: sparse, single-threaded, silent, the state
// refreshed every iteration.
ceres::Solver::Options solverOptions(const TreeFitOptions& options) {
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  so.max_num_iterations = options.maxIterations;
  so.num_threads = 1;
  so.logging_type = ceres::SILENT;
  so.minimizer_progress_to_stdout = false;
  so.function_tolerance = 1e-8;
  so.parameter_tolerance = 1e-10;
  so.update_state_every_iteration = true;
  return so;
}

}  // namespace

TreeFitResult fitTreeParameters(const PointCloud& scan, const CsgTree& tree,
                                const TreeFitOptions& options) {
  if (tree.empty()) throw std::invalid_argument("fitTreeParameters: the tree is empty");
  if (scan.empty()) throw std::invalid_argument("fitTreeParameters: no points");
  const std::span<const Vec3> points = scan.points;
  const double diagonal = scan.diagonal();
  if (!(diagonal > 0.0) || !std::isfinite(diagonal))
    throw std::invalid_argument("fitTreeParameters: the points span no volume");
  TreeFitResult out;
  out.tree = tree;

  Vec3 pivot = Vec3::Zero();
  for (const Vec3& p : points) pivot += p;
  pivot /= double(points.size());
  const TreeParameters parameters(tree, diagonal, pivot, options.parameters);
  const FlatTree flat(tree, parameters.leaves());
  FitContext c;
  c.parameters = &parameters;
  c.flat = &flat;
  c.ops = {options.operations, options.sardfRadius * diagonal};
  const double tolerance = options.distanceTolerance * diagonal;
  c.invTolerance = 1.0 / tolerance;
  c.lengthStep = 1e-6 * diagonal;
  for (const Node* leaf : parameters.leaves()) c.current.push_back(leaf->primitive);
  const std::vector<Primitive> input = c.current;
  out.sharedBlocks = parameters.sharedBlocks();
  const FitInputs in{.c = c,
                     .scan = scan,
                     .options = options,
                     .input = input,
                     .diagonal = diagonal,
                     .tolerance = tolerance};

  const PointLeaves leaves = pointLeaves(in);
  const std::vector<std::size_t> near = nearPoints(leaves, options.maxPoints);
  out.points = near.size();
  std::vector<Vec3> used;
  for (const std::size_t i : near) used.push_back(points[i]);
  out.rmsBefore = out.rmsAfter = rmsField(c, used, input);
  if (near.size() < 10) return out;
  if (options.control.cancelled()) {
    out.cancelled = true;
    return out;
  }

  // The problem: one residual per point over its active leaves' blocks.
  ceres::Problem::Options po;
  po.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  FitProblem fit{parameters.values(), ceres::HuberLoss(options.lossScale), ceres::Problem(po)};
  addPointResiduals(in, leaves, near, fit);
  constrainBlocks(in, fit, out);

  RefreshState refresh(c, fit.values);
  ceres::Solver::Options so = solverOptions(options);
  StopWhenAsked stop(options.control);
  so.callbacks.push_back(&refresh);
  so.callbacks.push_back(&stop);
  ceres::Solver::Summary summary;
  ceres::Solve(so, &fit.problem, &summary);
  out.iterations = int(summary.iterations.size()) - 1;
  out.converged = summary.termination_type == ceres::CONVERGENCE;
  if (options.control.cancelled()) {
    out.cancelled = true;
    return out;
  }

  std::vector<Primitive> fitted;
  if (!summary.IsSolutionUsable() || !parameters.primitives(fit.values, fitted)) return out;
  for (const Primitive& p : fitted) {
    try {
      p.validate();
    } catch (const std::invalid_argument&) {
      return out;
    }
  }
  out.tree = parameters.tree(fitted);
  out.rmsAfter = rmsField(c, used, fitted);
  for (std::size_t l = 0; l < fitted.size(); ++l)
    if (!fitted[l].approxEqual(input[l], 1e-6 * diagonal)) ++out.primitivesChanged;
  return out;
}

}  // namespace csgvox
