#include "evolve/field_kernels.h"

#include <tbb/blocked_range2d.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "core/cpu_features.h"
#include "core/sardf.h"
#include "evolve/minmax_chunk.h"
#include "voxel/bitset_kernels.h"

namespace csgvox::fitness_detail {
namespace {

// Each program's sums over its chunks' partial (distance, normal) pairs, in
// chunk order (the same sums whatever the number of threads).
std::vector<TermSums> sumChunkPartials(const std::vector<double>& partial, std::size_t count,
                                       std::size_t chunks) {
  std::vector<TermSums> out(count);
  for (std::size_t j = 0; j < count; ++j) {
    const double* s = partial.data() + 2 * j * chunks;
    for (std::size_t c = 0; c < chunks; ++c) {
      out[j].distance += s[2 * c];
      out[j].normal += s[2 * c + 1];
    }
  }
  return out;
}


// The last instruction's value negated: a leaf flips its sign, anything
// else gets a Negate.
void negateLast(std::vector<Instr>& code) {
  if (code.back().op == Op::Leaf) {
    code.back().op = Op::LeafNeg;
  } else if (code.back().op == Op::LeafNeg) {
    code.back().op = Op::Leaf;
  } else {
    code.push_back({Op::Negate, 0});
  }
}

void emit(const Node& node, const PrimitiveLibrary& library, std::vector<Instr>& code) {
  switch (node.kind) {
    case NodeKind::Primitive: {
      const auto index = library.indexOf(node);
      if (!index) {
        throw std::invalid_argument("leaf '" + node.name +
                                    "' is not one of the search's primitives");
      }
      code.push_back({Op::Leaf, std::uint16_t(*index)});
      return;
    }
    case NodeKind::Complement:
      emit(*node.children.front(), library, code);
      negateLast(code);
      return;
    case NodeKind::Union:
    case NodeKind::Intersection:
    case NodeKind::Difference: {
      const Op op = node.kind == NodeKind::Union ? Op::Max : Op::Min;
      emit(*node.children.front(), library, code);
      for (std::size_t k = 1; k < node.children.size(); ++k) {
        emit(*node.children[k], library, code);
        if (node.kind == NodeKind::Difference) negateLast(code);
        code.push_back({op, 0});
      }
      return;
    }
  }
}

// ---- min/max: the field at a point is one leaf's ±field; carry its id ----

}  // namespace

MinMaxChunkKernel minMaxKernel(SimdLevel level) {
  static const auto table =
      kernelsByLevel(portableMinMaxChunk(), avx2MinMaxChunk, avx512MinMaxChunk);
  return table[std::size_t(std::clamp(int(level), 0, int(table.size()) - 1))];
}

namespace {

struct MinMaxScratch {
  std::vector<float> values;
  std::vector<std::int32_t> ids;
};

// Chunks a task takes at once, and programs: a chunk's rows of the cached
// arrays (a few hundred kB for every primitive) stay in the core's cache
// while the programs run over them.
constexpr std::size_t kChunksPerTask = 4;
constexpr std::size_t kProgramsPerTask = 32;

// body(c, j) for every chunk c < chunks and program j < programs, in
// parallel, each task chunk by chunk.
template <class Body>
void eachChunkOfEachProgram(std::size_t chunks, std::size_t programs, const Body& body) {
  tbb::parallel_for(
      tbb::blocked_range2d<std::size_t>(0, chunks, kChunksPerTask, 0, programs, kProgramsPerTask),
      [&](const tbb::blocked_range2d<std::size_t>& r) {
        for (std::size_t c = r.rows().begin(); c != r.rows().end(); ++c) {
          for (std::size_t j = r.cols().begin(); j != r.cols().end(); ++j) body(c, j);
        }
      });
}

}  // namespace

// Each chunk's sums are kept apart and added up in chunk order afterwards,
// as one program run chunk after chunk would: the sums do not depend on how
// the work was split.
std::vector<TermSums> minMaxTerms(std::span<const Program> programs, const PointTables& t) {
  const std::size_t count = programs.size();
  const std::size_t chunks = (t.n + kChunk - 1) / kChunk;
  std::size_t depth = 1;
  for (const Program& p : programs) depth = std::max(depth, p.stackDepth);
  std::vector<double> partial(2 * count * chunks, 0.0);  // [program][chunk][2]
  const MinMaxChunkKernel kernel = minMaxKernel(simdLevel());
  eachChunkOfEachProgram(chunks, count, [&](std::size_t c, std::size_t j) {
    thread_local MinMaxScratch scratch;
    if (scratch.values.size() < depth * kChunk) {
      scratch.values.resize(depth * kChunk);
      scratch.ids.resize(depth * kChunk);
    }
    MinMaxChunk k;
    k.code = programs[j].code.data();
    k.codeSize = programs[j].code.size();
    k.values = t.values;
    k.distanceTerm = t.distanceTerm;
    k.normalTerm = t.normalTerm;
    k.n = t.n;
    k.stackValues = scratch.values.data();
    k.stackIds = scratch.ids.data();
    const std::size_t start = c * kChunk;
    kernel(k, start, std::min(kChunk, t.n - start), partial.data() + 2 * (j * chunks + c));
  });
  return sumChunkPartials(partial, count, chunks);
}

namespace {

// ---- smooth operations: values and gradients blend near the bisector ----

struct Partials {
  double f, d1, d2;
};

struct RFunctionPartials {
  static Partials unite(double a, double b) { return blend(a, b, 1.0); }
  static Partials intersect(double a, double b) { return blend(a, b, -1.0); }
  static Partials blend(double a, double b, double sign) {
    const double h = std::hypot(a, b);
    if (h == 0.0) return {0.0, 0.5, 0.5};
    return {a + b + sign * h, 1.0 + sign * a / h, 1.0 + sign * b / h};
  }
};

struct SardfPartials {
  double radius;
  Partials unite(double a, double b) const {
    const SardfResult r = sardfUnite(a, b, radius);
    return {r.f, r.d1, r.d2};
  }
  Partials intersect(double a, double b) const {
    const SardfResult r = sardfIntersect(a, b, radius);
    return {r.f, r.d1, r.d2};
  }
};

struct SmoothStack {
  std::vector<float> f, gx, gy, gz;
  std::vector<std::int32_t> ids;  // as min/max; −1 where the operands blend
};

template <class Ops>
void combineSmooth(SmoothStack& s, std::size_t a, std::size_t b, std::size_t m, bool intersect,
                   const Ops& ops) {
  for (std::size_t i = 0; i < m; ++i) {
    const double fa = s.f[a + i], fb = s.f[b + i];
    const Partials r = intersect ? ops.intersect(fa, fb) : ops.unite(fa, fb);
    if (r.d1 == 1.0 && r.d2 == 0.0) {
      s.f[a + i] = float(r.f);  // a alone: keep its gradient and id
    } else if (r.d1 == 0.0 && r.d2 == 1.0) {
      s.f[a + i] = float(r.f);
      s.gx[a + i] = s.gx[b + i];
      s.gy[a + i] = s.gy[b + i];
      s.gz[a + i] = s.gz[b + i];
      s.ids[a + i] = s.ids[b + i];
    } else {
      s.f[a + i] = float(r.f);
      s.gx[a + i] = float(r.d1 * s.gx[a + i] + r.d2 * s.gx[b + i]);
      s.gy[a + i] = float(r.d1 * s.gy[a + i] + r.d2 * s.gy[b + i]);
      s.gz[a + i] = float(r.d1 * s.gz[a + i] + r.d2 * s.gz[b + i]);
      s.ids[a + i] = -1;
    }
  }
}

template <class Ops>
TermSums smoothProgramTerms(const Program& program, const PointTables& t, const Ops& ops) {
  thread_local SmoothStack s;
  const std::size_t need = program.stackDepth * kChunk;
  if (s.f.size() < need) {
    s.f.resize(need);
    s.gx.resize(need);
    s.gy.resize(need);
    s.gz.resize(need);
    s.ids.resize(need);
  }
  TermSums sums;
  for (std::size_t start = 0; start < t.n; start += kChunk) {
    const std::size_t m = std::min(kChunk, t.n - start);
    std::size_t top = 0;
    for (const Instr& ins : program.code) {
      const std::size_t at = top * kChunk;
      switch (ins.op) {
        case Op::Leaf:
        case Op::LeafNeg: {
          const std::size_t from = std::size_t(ins.leaf) * t.n + start;
          const float sign = ins.op == Op::LeafNeg ? -1.0f : 1.0f;
          const std::int32_t code = 2 * std::int32_t(ins.leaf) + (ins.op == Op::LeafNeg ? 1 : 0);
          for (std::size_t i = 0; i < m; ++i) {
            s.f[at + i] = sign * t.values[from + i];
            s.gx[at + i] = sign * t.gradX[from + i];
            s.gy[at + i] = sign * t.gradY[from + i];
            s.gz[at + i] = sign * t.gradZ[from + i];
            s.ids[at + i] = code;
          }
          ++top;
          break;
        }
        case Op::Negate: {
          const std::size_t last = at - kChunk;
          for (std::size_t i = 0; i < m; ++i) {
            s.f[last + i] = -s.f[last + i];
            s.gx[last + i] = -s.gx[last + i];
            s.gy[last + i] = -s.gy[last + i];
            s.gz[last + i] = -s.gz[last + i];
            if (s.ids[last + i] >= 0) s.ids[last + i] ^= 1;
          }
          break;
        }
        case Op::Min:
        case Op::Max:
          combineSmooth(s, at - 2 * kChunk, at - kChunk, m, ins.op == Op::Min, ops);
          --top;
          break;
        default:
          throw std::logic_error("smooth fitness: fused instruction");
      }
    }
    double distance = 0.0, normal = 0.0;
    for (std::size_t i = 0; i < m; ++i) {
      const std::int32_t id = s.ids[i];
      if (id >= 0) {
        distance += t.distanceTerm[(std::size_t(id) >> 1) * t.n + start + i];
        normal += t.normalTerm[std::size_t(id) * t.n + start + i];
        continue;
      }
      const double r = s.f[i] / t.epsilon;
      distance += std::exp(-r * r);
      const double gx = s.gx[i], gy = s.gy[i], gz = s.gz[i];
      const double gn = std::sqrt(gx * gx + gy * gy + gz * gz);
      const std::size_t p = start + i;
      const double c = gn > 0.0 ? -(gx * t.normX[p] + gy * t.normY[p] + gz * t.normZ[p]) / gn : 0.0;
      const double theta = std::acos(std::clamp(c, -1.0, 1.0)) / t.alpha;
      normal += std::exp(-theta * theta);
    }
    sums.distance += distance;
    sums.normal += normal;
  }
  return sums;
}

}  // namespace

Program compile(const CsgTree& tree, const PrimitiveLibrary& library) {
  if (tree.empty()) throw std::invalid_argument("the fitness of an empty tree is undefined");
  Program program;
  emit(*tree.root(), library, program.code);
  std::size_t depth = 0;
  for (const Instr& ins : program.code) {
    if (ins.op == Op::Leaf || ins.op == Op::LeafNeg) {
      program.stackDepth = std::max(program.stackDepth, ++depth);
    } else if (ins.op == Op::Min || ins.op == Op::Max) {
      --depth;
    }
  }
  return program;
}

Program fused(const Program& program) {
  Program out;
  out.stackDepth = program.stackDepth;
  const std::vector<Instr>& code = program.code;
  for (std::size_t k = 0; k < code.size(); ++k) {
    const bool leaf = code[k].op == Op::Leaf || code[k].op == Op::LeafNeg;
    if (leaf && k + 1 < code.size() && (code[k + 1].op == Op::Min || code[k + 1].op == Op::Max)) {
      const bool neg = code[k].op == Op::LeafNeg;
      const Op op = code[k + 1].op == Op::Min ? (neg ? Op::MinLeafNeg : Op::MinLeaf)
                                              : (neg ? Op::MaxLeafNeg : Op::MaxLeaf);
      out.code.push_back({op, code[k].leaf});
      ++k;
    } else {
      out.code.push_back(code[k]);
    }
  }
  return out;
}

std::vector<TermSums> smoothTerms(std::span<const Program> programs, const PointTables& tables,
                                  SetOperationKind ops) {
  if (ops != SetOperationKind::RFunction && ops != SetOperationKind::Sardf) {
    throw std::invalid_argument("smooth terms: not a smooth set operation");
  }
  std::vector<TermSums> out(programs.size());
  tbb::parallel_for(std::size_t(0), programs.size(), [&](std::size_t j) {
    out[j] = ops == SetOperationKind::RFunction
                 ? smoothProgramTerms(programs[j], tables, RFunctionPartials{})
                 : smoothProgramTerms(programs[j], tables, SardfPartials{tables.radius});
  });
  return out;
}

namespace {

// ---- SARDF: min/max's chunks, the arcs computed where the operands blend ----

struct SardfScratch {
  std::vector<float> values, gradients, dense, terms;
  std::vector<std::int32_t> ids, flags, denseIds;
  std::vector<std::uint8_t> blended;
};

// R as a float no smaller than R: the kernel's band test may flag more
// points than blend, never fewer.
float bandOf(double radius) {
  float band = float(radius);
  if (double(band) < radius) band = std::nextafter(band, std::numeric_limits<float>::infinity());
  return band;
}

}  // namespace

SardfChunkKernel sardfKernel(SimdLevel level) {
  static const auto table =
      kernelsByLevel(portableSardfChunk(), avx2SardfChunk, avx512SardfChunk);
  return table[std::size_t(std::clamp(int(level), 0, int(table.size()) - 1))];
}

std::vector<TermSums> sardfTerms(std::span<const Program> programs, const PointTables& t) {
  const std::size_t count = programs.size();
  const std::size_t chunks = (t.n + kChunk - 1) / kChunk;
  std::size_t depth = 1;
  for (const Program& p : programs) depth = std::max(depth, p.stackDepth);
  std::vector<double> partial(2 * count * chunks, 0.0);  // [program][chunk][2]
  const SardfChunkKernel kernel = sardfKernel(simdLevel());
  const float radius = float(t.radius), invEpsilon = float(1.0 / t.epsilon),
              invAlpha = float(1.0 / t.alpha);
  const float band = bandOf(t.radius);
  eachChunkOfEachProgram(chunks, count, [&](std::size_t c, std::size_t j) {
    thread_local SardfScratch scratch;
    if (scratch.values.size() < depth * kChunk) {
      scratch.values.resize(depth * kChunk);
      scratch.ids.resize(depth * kChunk);
      scratch.gradients.resize(3 * depth * kChunk);
      scratch.blended.resize(depth);
      scratch.flags.resize(kChunk);
      scratch.dense.resize(10 * kChunk);
      scratch.denseIds.resize(3 * kChunk);
      scratch.terms.resize(2 * kChunk);
    }
    SardfChunk k;
    k.code = programs[j].code.data();
    k.codeSize = programs[j].code.size();
    k.values = t.values;
    k.gradX = t.gradX;
    k.gradY = t.gradY;
    k.gradZ = t.gradZ;
    k.normX = t.normX;
    k.normY = t.normY;
    k.normZ = t.normZ;
    k.distanceTerm = t.distanceTerm;
    k.normalTerm = t.normalTerm;
    k.n = t.n;
    k.exactRadius = t.radius;
    k.radius = radius;
    k.band = band;
    k.invEpsilon = invEpsilon;
    k.invAlpha = invAlpha;
    k.stackValues = scratch.values.data();
    k.stackIds = scratch.ids.data();
    k.stackGradients = scratch.gradients.data();
    k.stackBlended = scratch.blended.data();
    k.flags = scratch.flags.data();
    k.dense = scratch.dense.data();
    k.denseIds = scratch.denseIds.data();
    k.blendedTerms = scratch.terms.data();
    const std::size_t start = c * kChunk;
    kernel(k, start, std::min(kChunk, t.n - start), partial.data() + 2 * (j * chunks + c));
  });
  return sumChunkPartials(partial, count, chunks);
}

namespace {

// Words of a voxel set a task takes at once (2 kB): a program's stack of
// chunks stays in the core's cache.
constexpr std::size_t kWordChunk = 256;

// One (fused) program over the words [start, start + m) of the inside sets:
// its solid's words in stack[0, m).
void solidChunk(const Program& program, const std::uint64_t* insideSets, std::size_t words,
                std::size_t start, std::size_t m, std::uint64_t* stack) {
  std::size_t top = 0;  // entries on the stack
  const auto entry = [&](std::size_t k) { return stack + k * kWordChunk; };
  for (const Instr& ins : program.code) {
    const std::uint64_t* src = insideSets + std::size_t(ins.leaf) * words + start;
    switch (ins.op) {
      case Op::Leaf:
        std::copy(src, src + m, entry(top++));
        break;
      case Op::LeafNeg: {
        std::uint64_t* w = entry(top++);
        for (std::size_t i = 0; i < m; ++i) w[i] = ~src[i];
        break;
      }
      case Op::Negate: {
        std::uint64_t* w = entry(top - 1);
        for (std::size_t i = 0; i < m; ++i) w[i] = ~w[i];
        break;
      }
      case Op::Min:
      case Op::Max: {
        std::uint64_t* w = entry(top - 2);
        const std::uint64_t* b = entry(top - 1);
        if (ins.op == Op::Min) {
          for (std::size_t i = 0; i < m; ++i) w[i] &= b[i];
        } else {
          for (std::size_t i = 0; i < m; ++i) w[i] |= b[i];
        }
        --top;
        break;
      }
      case Op::MinLeaf:
      case Op::MinLeafNeg: {
        std::uint64_t* w = entry(top - 1);
        const std::uint64_t flip = ins.op == Op::MinLeafNeg ? ~0ull : 0ull;
        for (std::size_t i = 0; i < m; ++i) w[i] &= src[i] ^ flip;
        break;
      }
      case Op::MaxLeaf:
      case Op::MaxLeafNeg: {
        std::uint64_t* w = entry(top - 1);
        const std::uint64_t flip = ins.op == Op::MaxLeafNeg ? ~0ull : 0ull;
        for (std::size_t i = 0; i < m; ++i) w[i] |= src[i] ^ flip;
        break;
      }
    }
  }
}

}  // namespace

std::vector<std::size_t> voxelMismatch(std::span<const Program> programs,
                                       const std::uint64_t* insideSets, const std::uint64_t* labels,
                                       std::size_t labelCount, std::size_t words,
                                       std::uint64_t lastWordMask) {
  const std::size_t count = programs.size();
  const std::size_t chunks = (words + kWordChunk - 1) / kWordChunk;
  std::size_t depth = 1;
  for (const Program& p : programs) depth = std::max(depth, p.stackDepth);
  const BitsetKernels& bits = activeBitsetKernels();
  // |T △ L| = |L| + Σ over chunks of |T| − 2 |T ∩ L|, with the hardware's
  // popcount; T's bits past the last voxel are masked off (L has none).
  std::vector<std::ptrdiff_t> partial(count * chunks);  // [program][chunk]
  eachChunkOfEachProgram(chunks, count, [&](std::size_t c, std::size_t j) {
    thread_local std::vector<std::uint64_t> stack;
    if (stack.size() < depth * kWordChunk) stack.resize(depth * kWordChunk);
    const std::size_t start = c * kWordChunk, m = std::min(kWordChunk, words - start);
    solidChunk(programs[j], insideSets, words, start, m, stack.data());
    if (start + m == words) stack[m - 1] &= lastWordMask;
    partial[j * chunks + c] = std::ptrdiff_t(bits.count(stack.data(), m)) -
                              2 * std::ptrdiff_t(bits.countAnd(stack.data(), labels + start, m));
  });
  std::vector<std::size_t> out(count);
  for (std::size_t j = 0; j < count; ++j) {
    std::ptrdiff_t sum = std::ptrdiff_t(labelCount);
    for (std::size_t c = 0; c < chunks; ++c) sum += partial[j * chunks + c];
    out[j] = std::size_t(sum);
  }
  return out;
}

}  // namespace csgvox::fitness_detail
