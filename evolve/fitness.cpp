#include "evolve/fitness.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>

#include "evolve/field_kernels.h"
#include "voxel/description_sets.h"

namespace csgvox {

using fitness_detail::Instr;
using fitness_detail::Op;
using fitness_detail::Program;

struct FitnessModel::Data {
  PrimitiveLibrary library;
  FitnessOptions options;
  std::size_t n = 0;                       // points
  std::size_t p = 0;                       // primitives
  double epsilon = 0.0;                    // εd, scan units
  double alpha = 0.0;                      // α, radians
  double lambda = 0.0;                     // λ per node
  double radius = 0.0;                     // SARDF radius, scan units
  std::vector<float> values;               // [p][n] field of each primitive
  std::vector<float> gradX, gradY, gradZ;  // [p][n], smooth operations only
  std::vector<float> normX, normY, normZ;  // [n] scan normals, smooth operations only
  std::vector<float> distanceTerm;         // [p][n] exp(−(f/εd)²)
  std::vector<float> normalTerm;           // [2p][n] exp(−(θ/α)²) for +f and −f
  double diagonal = 0.0;                   // D, scan units
  // The voxel term (null without it); models of one library on other points
  // share it.
  struct Voxels {
    std::size_t words = 0;                  // words per voxel set
    std::uint64_t lastWordMask = ~0ull;     // valid bits of the last word
    std::vector<std::uint64_t> insideSets;  // [p][words]
    std::vector<std::uint64_t> labels;      // [words]
    std::size_t labelCount = 0;
  };
  std::shared_ptr<const Voxels> voxels;
};

namespace {

float normalTermOf(double cosAngle, double alpha) {
  const double theta = std::acos(std::clamp(cosAngle, -1.0, 1.0)) / alpha;
  return float(std::exp(-theta * theta));
}

}  // namespace

FitnessModel::FitnessModel(std::span<const Vec3> points, std::span<const Vec3> normals,
                           double diagonal, const PrimitiveLibrary& library,
                           const FitnessOptions& options, const VoxelTarget* target) {
  if (!(diagonal > 0.0) || !std::isfinite(diagonal)) {
    throw std::invalid_argument("FitnessModel: the diagonal must be > 0");
  }
  if (!(options.distanceTolerance > 0.0) || !(options.angleTolerance > 0.0)) {
    throw std::invalid_argument("FitnessModel: the tolerances must be > 0");
  }
  if (options.voxelWeight > 0.0 && target == nullptr) {
    throw std::invalid_argument("FitnessModel: the voxel term needs voxel labels");
  }
  std::unique_ptr<Data> data = pointData(points, normals, diagonal, library, options);
  if (options.voxelWeight > 0.0) {
    const std::size_t voxels = target->grid.voxelCount();
    if (target->inside.size() != voxels) {
      throw std::invalid_argument("FitnessModel: the voxel labels do not match their grid");
    }
    auto v = std::make_shared<Data::Voxels>();
    v->words = (voxels + 63) / 64;
    v->lastWordMask = voxels % 64 == 0 ? ~0ull : (std::uint64_t(1) << (voxels % 64)) - 1;
    v->labels.assign(target->inside.words().begin(), target->inside.words().end());
    v->labelCount = target->inside.count();
    v->insideSets.resize(data->p * v->words);
    tbb::parallel_for(std::size_t(0), data->p, [&](std::size_t q) {
      const VoxelSet inside = solidVoxels(library.leafTree(q), target->grid);
      std::copy(inside.words().begin(), inside.words().end(), v->insideSets.begin() + q * v->words);
    });
    data->voxels = std::move(v);
  }
  data_ = std::move(data);
}

FitnessModel::FitnessModel(std::span<const Vec3> points, std::span<const Vec3> normals,
                           const FitnessModel& other) {
  const Data& o = *other.data_;
  std::unique_ptr<Data> data = pointData(points, normals, o.diagonal, o.library, o.options);
  data->voxels = o.voxels;
  data_ = std::move(data);
}

std::unique_ptr<FitnessModel::Data> FitnessModel::pointData(std::span<const Vec3> points,
                                                            std::span<const Vec3> normals,
                                                            double diagonal,
                                                            const PrimitiveLibrary& library,
                                                            const FitnessOptions& options) {
  if (points.size() != normals.size()) {
    throw std::invalid_argument("FitnessModel: " + std::to_string(points.size()) + " points but " +
                                std::to_string(normals.size()) + " normals");
  }
  if (points.empty()) throw std::invalid_argument("FitnessModel: no points");
  auto data = std::make_unique<Data>();
  Data& d = *data;
  d.library = library;
  d.options = options;
  d.diagonal = diagonal;
  d.n = points.size();
  d.p = library.size();
  d.epsilon = options.distanceTolerance * diagonal;
  d.alpha = options.angleTolerance * std::numbers::pi / 180.0;
  d.lambda = options.sizeWeight >= 0.0 ? options.sizeWeight : std::log(double(d.n));
  d.radius = options.sardfRadius * diagonal;
  const bool smooth = options.operations != SetOperationKind::MinMax;
  const std::size_t n = d.n;
  d.values.resize(d.p * n);
  d.distanceTerm.resize(d.p * n);
  d.normalTerm.resize(2 * d.p * n);
  if (smooth) {
    d.gradX.resize(d.p * n);
    d.gradY.resize(d.p * n);
    d.gradZ.resize(d.p * n);
    d.normX.resize(n);
    d.normY.resize(n);
    d.normZ.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      d.normX[i] = float(normals[i].x());
      d.normY[i] = float(normals[i].y());
      d.normZ[i] = float(normals[i].z());
    }
  }
  tbb::parallel_for(std::size_t(0), d.p, [&](std::size_t q) {
    const Primitive& primitive = library.primitive(q);
    for (std::size_t i = 0; i < n; ++i) {
      Vec3 g;
      const double f = primitive.valueAndGradient(points[i], g);
      const double r = f / d.epsilon;
      d.values[q * n + i] = float(f);
      d.distanceTerm[q * n + i] = float(std::exp(-r * r));
      const double gn = g.norm();
      // ∇f points inwards, the scan normal outwards: the angle between ∇f
      // and −n; for −f, between −∇f and −n.
      const double c = gn > 0.0 ? -g.dot(normals[i]) / gn : 0.0;
      d.normalTerm[2 * q * n + i] = normalTermOf(c, d.alpha);
      d.normalTerm[(2 * q + 1) * n + i] = normalTermOf(-c, d.alpha);
      if (smooth) {
        d.gradX[q * n + i] = float(g.x());
        d.gradY[q * n + i] = float(g.y());
        d.gradZ[q * n + i] = float(g.z());
      }
    }
  });
  return data;
}

FitnessModel::~FitnessModel() = default;
FitnessModel::FitnessModel(FitnessModel&&) noexcept = default;
FitnessModel& FitnessModel::operator=(FitnessModel&&) noexcept = default;

std::size_t FitnessModel::pointCount() const { return data_->n; }
const PrimitiveLibrary& FitnessModel::library() const { return data_->library; }
const FitnessOptions& FitnessModel::options() const { return data_->options; }
double FitnessModel::sizeWeight() const { return data_->lambda; }

Fitness FitnessModel::evaluate(const CsgTree& tree) const {
  const CsgTree* one = &tree;
  return evaluate(std::span<const CsgTree* const>(&one, 1)).front();
}

std::vector<Fitness> FitnessModel::evaluate(std::span<const CsgTree* const> trees) const {
  const Data& d = *data_;
  std::vector<Program> programs;
  programs.reserve(trees.size());
  for (const CsgTree* tree : trees) programs.push_back(fitness_detail::compile(*tree, d.library));
  const fitness_detail::PointTables tables{d.n,
                                           d.values.data(),
                                           d.gradX.data(),
                                           d.gradY.data(),
                                           d.gradZ.data(),
                                           d.normX.data(),
                                           d.normY.data(),
                                           d.normZ.data(),
                                           d.distanceTerm.data(),
                                           d.normalTerm.data(),
                                           d.epsilon,
                                           d.alpha,
                                           d.radius};
  // Min/max, SARDF and the voxel term run the fused programs, R-functions
  // the plain ones.
  const SetOperationKind ops = d.options.operations;
  std::vector<Program> fused;
  if (ops != SetOperationKind::RFunction || d.voxels) {
    fused.reserve(programs.size());
    for (const Program& p : programs) fused.push_back(fitness_detail::fused(p));
  }
  const std::vector<fitness_detail::TermSums> sums =
      ops == SetOperationKind::MinMax  ? fitness_detail::minMaxTerms(fused, tables)
      : ops == SetOperationKind::Sardf ? fitness_detail::sardfTerms(fused, tables)
                                       : fitness_detail::smoothTerms(programs, tables, ops);
  std::vector<std::size_t> mismatch;
  if (d.voxels) {
    const Data::Voxels& v = *d.voxels;
    mismatch = fitness_detail::voxelMismatch(fused, v.insideSets.data(), v.labels.data(),
                                             v.labelCount, v.words, v.lastWordMask);
  }
  std::vector<Fitness> out(trees.size());
  for (std::size_t j = 0; j < trees.size(); ++j) {
    Fitness& f = out[j];
    f.nodes = trees[j]->nodeCount();
    f.distanceTerm = sums[j].distance;
    f.normalTerm = sums[j].normal;
    f.sizePenalty = d.lambda * double(f.nodes);
    if (!mismatch.empty()) {
      f.voxelMismatch = mismatch[j];
      f.voxelPenalty = d.options.voxelWeight * double(d.n) * double(f.voxelMismatch) /
                       double(std::max<std::size_t>(d.voxels->labelCount, 1));
    }
    f.total = f.distanceTerm + f.normalTerm - f.sizePenalty - f.voxelPenalty;
  }
  return out;
}

Fitness treeFitness(const CsgTree& tree, std::span<const Vec3> points,
                    std::span<const Vec3> normals, double diagonal,
                    const FitnessOptions& options) {
  if (points.size() != normals.size()) {
    throw std::invalid_argument("treeFitness: " + std::to_string(points.size()) + " points but " +
                                std::to_string(normals.size()) + " normals");
  }
  if (points.empty()) throw std::invalid_argument("treeFitness: no points");
  if (!(diagonal > 0.0) || !std::isfinite(diagonal)) {
    throw std::invalid_argument("treeFitness: the diagonal must be > 0");
  }
  if (tree.empty()) throw std::invalid_argument("treeFitness: the tree is empty");
  if (options.voxelWeight > 0.0) {
    throw std::invalid_argument("treeFitness: the voxel term needs a FitnessModel");
  }
  const SardfOperations sardf(options.sardfRadius * diagonal);
  const SetOperations& ops =
      options.operations == SetOperationKind::Sardf ? sardf : setOperations(options.operations);
  const double epsilon = options.distanceTolerance * diagonal;
  const double alpha = options.angleTolerance * std::numbers::pi / 180.0;
  // Fixed blocks summed in order: the same sums on any number of threads.
  constexpr std::size_t kBlock = 4096;
  const std::size_t n = points.size();
  const std::size_t blocks = (n + kBlock - 1) / kBlock;
  std::vector<double> distance(blocks, 0.0), normal(blocks, 0.0);
  tbb::parallel_for(std::size_t(0), blocks, [&](std::size_t b) {
    double sd = 0.0, sn = 0.0;
    for (std::size_t i = b * kBlock; i < std::min(n, (b + 1) * kBlock); ++i) {
      const FieldValue v = tree.evaluate(points[i], ops);
      const double r = v.f / epsilon;
      sd += float(std::exp(-r * r));  // the model's float terms
      const double gn = v.gradient.norm();
      // As the model's terms: the angle between ∇f (inwards) and −n.
      sn += normalTermOf(gn > 0.0 ? -v.gradient.dot(normals[i]) / gn : 0.0, alpha);
    }
    distance[b] = sd;
    normal[b] = sn;
  });
  Fitness f;
  for (std::size_t b = 0; b < blocks; ++b) {
    f.distanceTerm += distance[b];
    f.normalTerm += normal[b];
  }
  f.nodes = tree.nodeCount();
  const double lambda = options.sizeWeight >= 0.0 ? options.sizeWeight : std::log(double(n));
  f.sizePenalty = lambda * double(f.nodes);
  f.total = f.distanceTerm + f.normalTerm - f.sizePenalty;
  return f;
}

std::vector<std::uint32_t> spreadSample(std::size_t n, std::size_t count, std::uint64_t seed) {
  std::vector<std::uint32_t> all(n);
  for (std::size_t i = 0; i < n; ++i) all[i] = std::uint32_t(i);
  if (count >= n) return all;
  std::mt19937_64 rng(seed);
  // Fisher–Yates with our own index draw: the same on every standard library.
  for (std::size_t i = n - 1; i > 0; --i) {
    const std::size_t j = std::size_t(rng() % (i + 1));
    std::swap(all[i], all[j]);
  }
  all.resize(count);
  std::sort(all.begin(), all.end());
  return all;
}

std::optional<FitnessModel> roughModel(const FitnessModel& full, std::span<const Vec3> points,
                                       std::span<const Vec3> normals, std::size_t count,
                                       std::uint64_t seed) {
  if (count == 0 || points.size() <= count) return std::nullopt;
  std::vector<Vec3> p, n;
  p.reserve(count);
  n.reserve(count);
  for (const std::uint32_t i : spreadSample(points.size(), count, seed)) {
    p.push_back(points[i]);
    n.push_back(normals[i]);
  }
  return std::optional<FitnessModel>(std::in_place, p, n, full);
}

}  // namespace csgvox
