#include "core/tree_program.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <unordered_map>

namespace csgvox {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr std::size_t kChunk = 256;      // points per batch: the scratch stack stays in cache
constexpr std::size_t kChunksPerTask = 8;  // batches a thread takes at once in values()
constexpr double kRoundingSlack = 1e-9;  // relative slack on computed bounds

// Euclidean distance between two boxes (0 when they overlap).
double boxDistance(const Aabb& a, const Aabb& b) {
  const Vec3 gap = (b.min - a.max).cwiseMax(a.min - b.max).cwiseMax(0.0);
  return gap.norm();
}

// A stack of values held in a local array for programs of depth up to kLocal.
template <class T, std::size_t kLocal>
class ValueStack {
 public:
  explicit ValueStack(std::size_t depth) {
    if (depth > kLocal) heap_.resize(depth);
    data_ = depth > kLocal ? heap_.data() : local_.data();
    data_[0] = T{};  // a program always sets it; this keeps the compiler sure of it
  }
  T* data() { return data_; }

 private:
  std::array<T, kLocal> local_;
  std::vector<T> heap_;
  T* data_;
};

// a[i] = op(a[i], b[i]) for i < n.
template <class Op>
void combine(double* a, const double* b, std::size_t n, Op op) {
  for (std::size_t i = 0; i < n; ++i) a[i] = op(a[i], b[i]);
}

}  // namespace

// Most values a program holds at once.
std::size_t TreeProgram::depthOf(const std::vector<Step>& steps) {
  std::size_t depth = 0, most = 1;
  for (const Step& s : steps) {
    if (s.op == Op::Leaf || s.op == Op::Constant) most = std::max(most, ++depth);
    if (s.op == Op::Unite || s.op == Op::Intersect) --depth;
  }
  return most;
}

namespace {}  // namespace

TreeProgram::TreeProgram() : leaves_(std::make_shared<Leaves>()), threshold_(kInf) {
  steps_.push_back({Op::Constant, 0, -kInf});
}

TreeProgram::TreeProgram(const CsgTree& tree) : TreeProgram() {
  if (tree.empty()) return;
  steps_.clear();
  auto leaves = std::make_shared<Leaves>();
  compile(*tree.root(), *leaves);
  leaves_ = std::move(leaves);
  stackDepth_ = depthOf(steps_);
}

void TreeProgram::compile(const Node& node, Leaves& leaves) {
  switch (node.kind) {
    case NodeKind::Primitive: {
      steps_.push_back({Op::Leaf, static_cast<std::uint32_t>(leaves.primitives.size()), 0.0});
      leaves.primitives.push_back(node.primitive);
      leaves.bounds.push_back(node.primitive.bounds());
      return;
    }
    case NodeKind::Complement:
      compile(*node.children.front(), leaves);
      steps_.push_back({Op::Negate, 0, 0.0});
      return;
    case NodeKind::Union:
    case NodeKind::Intersection:
    case NodeKind::Difference: {
      compile(*node.children.front(), leaves);
      for (std::size_t i = 1; i < node.children.size(); ++i) {
        compile(*node.children[i], leaves);
        if (node.kind == NodeKind::Difference) steps_.push_back({Op::Negate, 0, 0.0});
        steps_.push_back({node.kind == NodeKind::Union ? Op::Unite : Op::Intersect, 0, 0.0});
      }
      return;
    }
  }
}

std::size_t TreeProgram::leafCount() const {
  return static_cast<std::size_t>(
      std::count_if(steps_.begin(), steps_.end(), [](const Step& s) { return s.op == Op::Leaf; }));
}

double TreeProgram::value(const Vec3& p) const {
  ValueStack<double, 64> stack(stackDepth_);
  double* s = stack.data();
  std::size_t top = 0;  // number of values on the stack
  for (const Step& step : steps_) {
    switch (step.op) {
      case Op::Leaf:
        s[top++] = leaves_->primitives[step.leaf].value(p);
        break;
      case Op::Constant:
        s[top++] = step.constant;
        break;
      case Op::Negate:
        s[top - 1] = -s[top - 1];
        break;
      case Op::Unite:
        --top;
        s[top - 1] = MinMaxValues::unite(s[top - 1], s[top]);
        break;
      case Op::Intersect:
        --top;
        s[top - 1] = MinMaxValues::intersect(s[top - 1], s[top]);
        break;
    }
  }
  return s[0];
}

FieldValue TreeProgram::evaluate(const Vec3& p) const {
  ValueStack<FieldValue, 16> stack(stackDepth_);
  FieldValue* s = stack.data();
  std::size_t top = 0;
  for (const Step& step : steps_) {
    switch (step.op) {
      case Op::Leaf: {
        FieldValue& v = s[top++];
        v.f = leaves_->primitives[step.leaf].valueAndGradient(p, v.gradient);
        break;
      }
      case Op::Constant:
        s[top].f = step.constant;
        s[top++].gradient = Vec3::Zero();
        break;
      case Op::Negate:
        s[top - 1].f = -s[top - 1].f;
        s[top - 1].gradient = -s[top - 1].gradient;
        break;
      case Op::Unite:
        --top;
        if (s[top].f > s[top - 1].f) s[top - 1] = s[top];
        break;
      case Op::Intersect:
        --top;
        if (s[top].f < s[top - 1].f) s[top - 1] = s[top];
        break;
    }
  }
  return s[0];
}

template <class Ops>
void TreeProgram::runValues(std::span<const Vec3> points, std::span<double> out,
                            const Ops& ops) const {
  const auto unite = [&ops](double a, double b) { return ops.unite(a, b); };
  const auto intersect = [&ops](double a, double b) { return ops.intersect(a, b); };
  // Chunks [c0, c1) with a scratch stack of their own: every value is its
  // point's alone, so splitting the chunks among threads changes nothing.
  const auto run = [&](std::size_t c0, std::size_t c1) {
    std::vector<double> scratch(stackDepth_ * kChunk);
    const auto array = [&](std::size_t i) { return scratch.data() + i * kChunk; };
    for (std::size_t start = c0 * kChunk; start < std::min(c1 * kChunk, points.size());
         start += kChunk) {
      const std::size_t n = std::min(kChunk, points.size() - start);
      const std::span<const Vec3> chunk = points.subspan(start, n);
      std::size_t top = 0;  // number of arrays on the stack
      for (const Step& step : steps_) {
        switch (step.op) {
          case Op::Leaf:
            leaves_->primitives[step.leaf].values(chunk, std::span<double>(array(top++), n));
            break;
          case Op::Constant:
            std::fill_n(array(top++), n, step.constant);
            break;
          case Op::Negate: {
            double* a = array(top - 1);
            for (std::size_t i = 0; i < n; ++i) a[i] = -a[i];
            break;
          }
          case Op::Unite:
            --top;
            combine(array(top - 1), array(top), n, unite);
            break;
          case Op::Intersect:
            --top;
            combine(array(top - 1), array(top), n, intersect);
            break;
        }
      }
      std::copy_n(array(0), n, out.begin() + static_cast<std::ptrdiff_t>(start));
    }
  };
  const std::size_t chunks = (points.size() + kChunk - 1) / kChunk;
  if (chunks < 2 * kChunksPerTask) {
    run(0, chunks);
    return;
  }
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, chunks, kChunksPerTask),
                    [&](const tbb::blocked_range<std::size_t>& r) { run(r.begin(), r.end()); });
}

void TreeProgram::values(std::span<const Vec3> points, std::span<double> out,
                         SetOperationKind ops) const {
  if (points.size() != out.size()) {
    throw std::invalid_argument("values: points and out differ in size");
  }
  switch (ops) {
    case SetOperationKind::MinMax:
      return runValues(points, out, MinMaxValues{});
    case SetOperationKind::RFunction:
      return runValues(points, out, RFunctionValues{});
    case SetOperationKind::Sardf:
      break;
  }
  throw std::invalid_argument("values: SARDF needs a radius (pass its SardfOperations)");
}

void TreeProgram::values(std::span<const Vec3> points, std::span<double> out,
                         const SetOperations& ops) const {
  if (ops.kind() != SetOperationKind::Sardf) return values(points, out, ops.kind());
  const auto* sardf = dynamic_cast<const SardfOperations*>(&ops);
  if (!sardf) throw std::invalid_argument("values: a SARDF kind must be a SardfOperations");
  if (points.size() != out.size()) {
    throw std::invalid_argument("values: points and out differ in size");
  }
  runValues(points, out, sardf->values());
}

TreeProgram TreeProgram::restricted(const Aabb& region, double threshold) const {
  if (!(threshold > 0.0) || threshold > threshold_) {
    throw std::invalid_argument("restricted: the threshold must be > 0 and within the program's");
  }
  if (!region.isBounded()) throw std::invalid_argument("restricted: the region is not bounded");
  const double t = threshold;
  const Vec3 centre = region.center();
  const double radius = 0.5 * region.diagonal();
  const double scale = radius + centre.cwiseAbs().maxCoeff();

  TreeProgram result;
  result.leaves_ = leaves_;
  result.threshold_ = t;
  result.steps_.clear();
  std::vector<Step>& code = result.steps_;
  // One entry per value on the evaluation stack: bounds of its values over
  // the region (values clamped to [-t, t]), whether it is the constant -t or
  // t, and where its code starts.
  struct Entry {
    double lo, hi;
    bool constant;
    std::size_t start;
  };
  std::vector<Entry> stack;
  const auto push = [&](double lo, double hi, const Step& step) {
    const std::size_t start = code.size();
    if (hi <= -t || lo >= t) {
      const double c = hi <= -t ? -t : t;
      code.push_back({Op::Constant, 0, c});
      stack.push_back({c, c, true, start});
    } else {
      code.push_back(step);
      stack.push_back({lo, hi, false, start});
    }
  };
  for (const Step& step : steps_) {
    switch (step.op) {
      case Op::Leaf: {
        const double f = leaves_->primitives[step.leaf].value(centre);
        const double slack = kRoundingSlack * (scale + std::abs(f));
        // 1-Lipschitz around the centre; outside the primitive's bounds the
        // value is at most minus the distance to them.
        const double lo = f - radius - slack;
        const double hi =
            std::min(f + radius, -boxDistance(region, leaves_->bounds[step.leaf])) + slack;
        push(lo, hi, step);
        break;
      }
      case Op::Constant:
        push(step.constant, step.constant, step);
        break;
      case Op::Negate: {
        Entry& e = stack.back();
        std::swap(e.lo, e.hi);
        e.lo = -e.lo;
        e.hi = -e.hi;
        if (e.constant) {
          code.back().constant = -code.back().constant;
        } else {
          code.push_back(step);
        }
        break;
      }
      case Op::Unite:
      case Op::Intersect: {
        const Entry b = stack.back();
        stack.pop_back();
        Entry& a = stack.back();
        const bool unite = step.op == Op::Unite;
        const double lo = unite ? std::max(a.lo, b.lo) : std::min(a.lo, b.lo);
        const double hi = unite ? std::max(a.hi, b.hi) : std::min(a.hi, b.hi);
        // The operand that leaves the other unchanged: -t for max, t for min.
        const double neutral = unite ? -t : t;
        if (hi <= -t || lo >= t) {
          code.resize(a.start);
          const double c = hi <= -t ? -t : t;
          code.push_back({Op::Constant, 0, c});
          a = {c, c, true, a.start};
        } else if (b.constant && b.lo == neutral) {
          code.resize(b.start);
        } else if (a.constant && a.lo == neutral) {
          code.erase(code.begin() + static_cast<std::ptrdiff_t>(a.start),
                     code.begin() + static_cast<std::ptrdiff_t>(b.start));
          a = {b.lo, b.hi, b.constant, a.start};
        } else {
          code.push_back(step);
          a = {lo, hi, false, a.start};
        }
        break;
      }
    }
  }
  result.stackDepth_ = depthOf(code);
  return result;
}

}  // namespace csgvox
