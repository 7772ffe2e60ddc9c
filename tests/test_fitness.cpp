// The point fitness (evolve/fitness.h): Eq. 7 and the voxel term against a
// direct per-point computation with CsgTree::evaluate.

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <numbers>
#include <optional>
#include <random>
#include <string>

#include "core/cpu_features.h"
#include "evolve/field_kernels.h"
#include "evolve/fitness.h"
#include "evolve/tree_variation.h"
#include "evolve_fixtures.h"
#include "test_helpers.h"

namespace csgvox {
namespace {

// Eq. 7's point terms computed point by point from the tree's own field.
std::pair<double, double> directTerms(const CsgTree& tree, const test::OrientedPoints& in,
                                      double epsilon, double alphaRadians,
                                      const SetOperations& ops) {
  double distance = 0.0, normal = 0.0;
  for (std::size_t i = 0; i < in.points.size(); ++i) {
    const FieldValue v = tree.evaluate(in.points[i], ops);
    const double r = v.f / epsilon;
    distance += std::exp(-r * r);
    const double gn = v.gradient.norm();
    const double c = gn > 0 ? -v.gradient.dot(in.normals[i]) / gn : 0.0;
    const double theta = std::acos(std::clamp(c, -1.0, 1.0)) / alphaRadians;
    normal += std::exp(-theta * theta);
  }
  return {distance, normal};
}

// Points near the cube's faces, pushed off by up to 3 % of its size, with
// normals tilted: every term is strictly between 0 and 1.
test::OrientedPoints noisyCube(std::uint64_t seed) {
  test::OrientedPoints in = test::cubeFacePoints(12);
  test::Rng rng(seed);
  std::uniform_real_distribution<double> u(-0.03, 0.03);
  for (std::size_t i = 0; i < in.points.size(); ++i) {
    in.points[i] += Vec3(u(rng), u(rng), u(rng));
    in.normals[i] = (in.normals[i] + 3.0 * Vec3(u(rng), u(rng), u(rng))).normalized();
  }
  return in;
}

constexpr double kDiagonal = 2.0 * 1.7320508075688772;

// The model's point terms of each tree against directTerms with the model's
// own tolerances; tables are floats, so they agree to float rounding.
void expectTermsMatchDirect(const FitnessModel& model, const test::OrientedPoints& in,
                            const SetOperations& ops, const std::vector<CsgTree>& trees) {
  const FitnessOptions& o = model.options();
  const double n = double(in.points.size());
  for (std::size_t t = 0; t < trees.size(); ++t) {
    const auto [distance, normal] = directTerms(trees[t], in, o.distanceTolerance * kDiagonal,
                                                o.angleTolerance * std::numbers::pi / 180.0, ops);
    const Fitness f = model.evaluate(trees[t]);
    EXPECT_NEAR(f.distanceTerm, distance, 1e-4 * n) << ops.name() << " tree " << t;
    EXPECT_NEAR(f.normalTerm, normal, 1e-4 * n) << ops.name() << " tree " << t;
  }
}

// `count` random trees over the library.
std::vector<CsgTree> randomTrees(const PrimitiveLibrary& library, std::uint64_t seed, int count,
                                 std::size_t depth, double operationProbability) {
  EvolveRng rng(seed);
  std::vector<CsgTree> trees;
  for (int t = 0; t < count; ++t) {
    trees.push_back(randomTree(rng, library, depth, operationProbability));
  }
  return trees;
}

TEST(Fitness, ExactCubeScoresEveryPoint) {
  const test::OrientedPoints in = test::cubeFacePoints(20);
  const PrimitiveLibrary library = test::cubePlanes();
  const FitnessModel model(in.points, in.normals, kDiagonal, library);
  const Fitness f = model.evaluate(test::cubeTree(library));
  const double n = double(in.points.size());
  EXPECT_NEAR(f.distanceTerm, n, 1e-9 * n);
  EXPECT_NEAR(f.normalTerm, n, 1e-3 * n);  // normals exact; float tables
  EXPECT_EQ(f.nodes, 7u);
  EXPECT_DOUBLE_EQ(model.sizeWeight(), std::log(n));
  EXPECT_NEAR(f.total, f.distanceTerm + f.normalTerm - 7 * std::log(n), 1e-9);
  // Five faces explain five sixths of the points (and the sixth face only
  // within a few εd of its edges).
  std::vector<CsgTree> five;
  for (std::size_t i = 0; i < 5; ++i) five.push_back(library.leafTree(i));
  EXPECT_LT(model.evaluate(CsgTree::intersect(five)).distanceTerm, (5.0 / 6.0 + 0.01) * n);
}

TEST(Fitness, MinMaxMatchesDirectComputationOnRandomTrees) {
  const test::OrientedPoints in = noisyCube(3);
  const PrimitiveLibrary library = test::cubePlanes(
      {Sphere{Vec3(0.3, 0.1, 0.0), 0.7}, Cylinder{Vec3::Zero(), Vec3::UnitX(), 0.4, 3.0}});
  FitnessOptions options;
  options.angleTolerance = 20.0;
  const FitnessModel model(in.points, in.normals, kDiagonal, library, options);
  std::vector<CsgTree> trees = randomTrees(library, 7, 40, 5, 0.8);
  for (std::size_t t = 0; t < trees.size(); t += 5) trees[t] = CsgTree::complement(trees[t]);
  expectTermsMatchDirect(model, in, minMaxOperations(), trees);
}

TEST(Fitness, EveryInstructionSetGivesTheSameSums) {
  const test::OrientedPoints in = noisyCube(21);  // 864 points: 3 full chunks and a partial one
  const PrimitiveLibrary library = test::cubePlanes({Sphere{Vec3(0.3, 0.1, 0.0), 0.7}});
  EvolveRng rng(17);
  std::vector<CsgTree> trees;
  for (int t = 0; t < 30; ++t) trees.push_back(randomTree(rng, library, 6, 0.8));
  for (const SetOperationKind ops : {SetOperationKind::MinMax, SetOperationKind::Sardf}) {
    FitnessOptions options;
    options.operations = ops;
    const FitnessModel model(in.points, in.normals, kDiagonal, library, options);
    std::vector<Fitness> reference;
    {
      const ScopedSimdLevel portable(SimdLevel::Portable);
      for (const CsgTree& t : trees) reference.push_back(model.evaluate(t));
    }
    for (const SimdLevel level : supportedSimdLevels()) {
      const ScopedSimdLevel scoped(level);
      // The level in force picks its own kernels.
      const fitness_detail::MinMaxChunkKernel own =
          level == SimdLevel::Avx512 ? fitness_detail::avx512MinMaxChunk()
          : level == SimdLevel::Avx2 ? fitness_detail::avx2MinMaxChunk()
                                     : fitness_detail::portableMinMaxChunk();
      const fitness_detail::SardfChunkKernel ownSardf =
          level == SimdLevel::Avx512 ? fitness_detail::avx512SardfChunk()
          : level == SimdLevel::Avx2 ? fitness_detail::avx2SardfChunk()
                                     : fitness_detail::portableSardfChunk();
      ASSERT_NE(own, nullptr) << simdLevelName(level);
      ASSERT_NE(ownSardf, nullptr) << simdLevelName(level);
      EXPECT_EQ(fitness_detail::minMaxKernel(simdLevel()), own) << simdLevelName(level);
      EXPECT_EQ(fitness_detail::sardfKernel(simdLevel()), ownSardf) << simdLevelName(level);
      for (std::size_t t = 0; t < trees.size(); ++t) {
        const Fitness f = model.evaluate(trees[t]);
        EXPECT_EQ(f.distanceTerm, reference[t].distanceTerm)
            << int(ops) << " " << simdLevelName(level) << " " << t;
        EXPECT_EQ(f.normalTerm, reference[t].normalTerm)
            << int(ops) << " " << simdLevelName(level) << " " << t;
      }
    }
  }
}

// Trees evaluated together score as each does alone, bit for bit, whatever
// the other trees, their order and the number of threads: each chunk's sums
// are kept apart and added in chunk order. 70 trees (more than one task's
// share) over 864 points (3 full chunks and a partial one), with the voxel
// term, with min/max, SARDF and R-functions.
TEST(Fitness, TreesEvaluatedTogetherScoreAsAlone) {
  const test::OrientedPoints in = noisyCube(23);
  const PrimitiveLibrary library = test::cubePlanes(
      {Sphere{Vec3(0.3, 0.1, 0.0), 0.7}, Cylinder{Vec3::Zero(), Vec3::UnitX(), 0.4, 3.0}});
  VoxelTarget target;
  target.grid = VoxelGrid(Vec3::Constant(-1.5), Mat3::Identity(), 0.25, {12, 12, 12});
  target.inside = VoxelSet(target.grid.voxelCount());
  for (std::size_t v = 0; v < target.grid.voxelCount(); ++v) {
    if (target.grid.center(v).cwiseAbs().maxCoeff() < 1.0) target.inside.set(v);
  }
  std::vector<CsgTree> trees = randomTrees(library, 29, 70, 6, 0.8);
  for (std::size_t t = 0; t < trees.size(); t += 7) trees[t] = CsgTree::complement(trees[t]);
  for (const SetOperationKind ops :
       {SetOperationKind::MinMax, SetOperationKind::Sardf, SetOperationKind::RFunction}) {
    FitnessOptions options;
    options.operations = ops;
    options.voxelWeight = 0.5;
    const FitnessModel model(in.points, in.normals, kDiagonal, library, options, &target);
    std::vector<Fitness> alone;
    {
      const tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
      for (const CsgTree& t : trees) alone.push_back(model.evaluate(t));
    }
    std::vector<const CsgTree*> forward, backward;
    for (const CsgTree& t : trees) forward.push_back(&t);
    backward.assign(forward.rbegin(), forward.rend());
    const std::vector<Fitness> together = model.evaluate(forward);
    const std::vector<Fitness> reversed = model.evaluate(backward);
    ASSERT_EQ(together.size(), trees.size());
    ASSERT_EQ(reversed.size(), trees.size());
    for (std::size_t t = 0; t < trees.size(); ++t) {
      const Fitness& r = reversed[trees.size() - 1 - t];
      for (const Fitness* f : {&together[t], &r}) {
        EXPECT_EQ(f->distanceTerm, alone[t].distanceTerm) << int(ops) << " tree " << t;
        EXPECT_EQ(f->normalTerm, alone[t].normalTerm) << int(ops) << " tree " << t;
        EXPECT_EQ(f->voxelMismatch, alone[t].voxelMismatch) << int(ops) << " tree " << t;
        EXPECT_EQ(f->nodes, alone[t].nodes) << int(ops) << " tree " << t;
        EXPECT_EQ(f->total, alone[t].total) << int(ops) << " tree " << t;
      }
    }
    EXPECT_TRUE(model.evaluate(std::span<const CsgTree* const>()).empty());
  }
  // Still checked against the point-by-point computation.
  const FitnessModel model(in.points, in.normals, kDiagonal, library);
  std::vector<const CsgTree*> all;
  for (const CsgTree& t : trees) all.push_back(&t);
  const std::vector<Fitness> together = model.evaluate(all);
  const double n = double(in.points.size());
  const FitnessOptions& o = model.options();
  for (std::size_t t = 0; t < trees.size(); t += 5) {
    const auto [distance, normal] =
        directTerms(trees[t], in, o.distanceTolerance * kDiagonal,
                    o.angleTolerance * std::numbers::pi / 180.0, minMaxOperations());
    EXPECT_NEAR(together[t].distanceTerm, distance, 1e-4 * n) << t;
    EXPECT_NEAR(together[t].normalTerm, normal, 1e-4 * n) << t;
  }
}

// The vector kernels are compiled with their level's flags wherever the
// build gives them (x86-64 with GCC or Clang): without them their exports
// are null and every level runs the portable kernel.
TEST(Fitness, TheVectorKernelsAreBuiltForTheirLevel) {
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
  EXPECT_NE(fitness_detail::avx2MinMaxChunk(), nullptr);
  EXPECT_NE(fitness_detail::avx512MinMaxChunk(), nullptr);
  EXPECT_NE(fitness_detail::avx2SardfChunk(), nullptr);
  EXPECT_NE(fitness_detail::avx512SardfChunk(), nullptr);
#else
  GTEST_SKIP() << "the build has no vector flags for this processor or compiler";
#endif
}

TEST(Fitness, RFunctionsMatchDirectComputation) {
  const test::OrientedPoints in = noisyCube(5);
  const PrimitiveLibrary library = test::cubePlanes({Sphere{Vec3(0.5, 0.5, 0.5), 0.8}});
  FitnessOptions options;
  options.operations = SetOperationKind::RFunction;
  options.distanceTolerance = 0.05;
  const FitnessModel model(in.points, in.normals, kDiagonal, library, options);
  expectTermsMatchDirect(model, in, rFunctionOperations(), randomTrees(library, 11, 20, 4, 0.9));
}

TEST(Fitness, SardfMatchesDirectComputation) {
  const test::OrientedPoints in = noisyCube(8);
  const PrimitiveLibrary library = test::cubePlanes(
      {Sphere{Vec3(0.5, 0.5, 0.5), 0.8}, Cylinder{Vec3::Zero(), Vec3::UnitY(), 0.5, 3}});
  FitnessOptions options;
  options.operations = SetOperationKind::Sardf;
  options.sardfRadius = 0.1;
  const FitnessModel model(in.points, in.normals, kDiagonal, library, options);
  expectTermsMatchDirect(model, in, SardfOperations(0.1 * kDiagonal),
                         randomTrees(library, 13, 20, 4, 0.9));
  // The solid is min/max's: the exact cube scores every point on its faces.
  const test::OrientedPoints faces = test::cubeFacePoints(10);
  const FitnessModel onFaces(faces.points, faces.normals, kDiagonal, library, options);
  EXPECT_NEAR(onFaces.evaluate(test::cubeTree(library)).distanceTerm, double(faces.points.size()),
              1e-6);
}

// Cached arrays of `n` points over `p` primitives filled the way the fitness
// fills them, from given values and random unit gradients and normals.
struct SyntheticTables {
  std::size_t n = 0, p = 0;
  std::vector<float> values, gradX, gradY, gradZ, normX, normY, normZ, distanceTerm, normalTerm;
  double epsilon = 0.0, alpha = 0.0, radius = 0.0;

  SyntheticTables(std::size_t points, std::size_t primitives, std::uint64_t seed)
      : n(points), p(primitives) {
    values.assign(p * n, 0.0f);
    test::Rng rng(seed);
    std::normal_distribution<double> g;
    const auto unit = [&] { return Vec3(g(rng), g(rng), g(rng)).normalized(); };
    for (std::size_t q = 0; q < p * n; ++q) {
      const Vec3 d = unit();
      gradX.push_back(float(d.x()));
      gradY.push_back(float(d.y()));
      gradZ.push_back(float(d.z()));
    }
    for (std::size_t i = 0; i < n; ++i) {
      const Vec3 d = unit();
      normX.push_back(float(d.x()));
      normY.push_back(float(d.y()));
      normZ.push_back(float(d.z()));
    }
  }

  // The terms of every primitive's ±field (as FitnessModel computes them).
  fitness_detail::PointTables tables() {
    distanceTerm.assign(p * n, 0.0f);
    normalTerm.assign(2 * p * n, 0.0f);
    const auto term = [&](double c) {
      const double t = std::acos(std::clamp(c, -1.0, 1.0)) / alpha;
      return float(std::exp(-t * t));
    };
    for (std::size_t q = 0; q < p; ++q) {
      for (std::size_t i = 0; i < n; ++i) {
        const std::size_t k = q * n + i;
        const double r = values[k] / epsilon;
        distanceTerm[k] = float(std::exp(-r * r));
        const double c = -(double(gradX[k]) * normX[i] + double(gradY[k]) * normY[i] +
                           double(gradZ[k]) * normZ[i]);
        normalTerm[2 * q * n + i] = term(c);
        normalTerm[(2 * q + 1) * n + i] = term(-c);
      }
    }
    return {n,
            values.data(),
            gradX.data(),
            gradY.data(),
            gradZ.data(),
            normX.data(),
            normY.data(),
            normZ.data(),
            distanceTerm.data(),
            normalTerm.data(),
            epsilon,
            alpha,
            radius};
  }

  // The same point alone.
  SyntheticTables point(std::size_t i) const {
    SyntheticTables one(1, p, 0);
    for (std::size_t q = 0; q < p; ++q) {
      one.values[q] = values[q * n + i];
      one.gradX[q] = gradX[q * n + i];
      one.gradY[q] = gradY[q * n + i];
      one.gradZ[q] = gradZ[q * n + i];
    }
    one.normX[0] = normX[i];
    one.normY[0] = normY[i];
    one.normZ[0] = normZ[i];
    one.epsilon = epsilon;
    one.alpha = alpha;
    one.radius = radius;
    return one;
  }
};

// Programs over a library of `size` leaves: every binary operation on two
// leaves (and on a leaf and a negated leaf), and random trees.
std::vector<fitness_detail::Program> sardfPrograms(std::size_t size, std::uint64_t seed) {
  std::vector<Primitive> spheres;
  std::vector<std::string> names;
  for (std::size_t q = 0; q < size; ++q) {
    spheres.push_back(Sphere{Vec3(double(q), 0.0, 0.0), 0.5});
    names.push_back("s" + std::to_string(q));
  }
  const PrimitiveLibrary library(std::move(spheres), std::move(names));
  std::vector<CsgTree> trees;
  const CsgTree a = library.leafTree(0), b = library.leafTree(1);
  for (const CsgTree& x : {a, CsgTree::complement(a)}) {
    for (const CsgTree& y : {b, CsgTree::complement(b)}) {
      trees.push_back(CsgTree::unite({x, y}));
      trees.push_back(CsgTree::intersect({x, y}));
      trees.push_back(CsgTree::subtract({x, y}));
    }
  }
  // Two operations on the stack, and a negated operation.
  trees.push_back(CsgTree::unite({CsgTree::intersect({a, b}), CsgTree::subtract({b, a})}));
  trees.push_back(CsgTree::intersect({CsgTree::complement(CsgTree::unite({a, b})), a}));
  std::vector<CsgTree> random = randomTrees(library, seed, 40, 5, 0.9);
  for (std::size_t t = 0; t < random.size(); t += 4) random[t] = CsgTree::complement(random[t]);
  trees.insert(trees.end(), random.begin(), random.end());
  std::vector<fitness_detail::Program> programs;
  for (const CsgTree& t : trees) programs.push_back(fitness_detail::compile(t, library));
  return programs;
}

// The chunk kernel's terms against the point-by-point SARDF (core/sardf.h
// through smoothTerms()), program by program and point by point.
void expectSardfKernelMatches(SyntheticTables& data,
                              const std::vector<fitness_detail::Program>& programs,
                              bool pointByPoint, double tolerance) {
  std::vector<fitness_detail::Program> fused;
  for (const fitness_detail::Program& p : programs) fused.push_back(fitness_detail::fused(p));
  const fitness_detail::PointTables all = data.tables();
  const auto fast = fitness_detail::sardfTerms(fused, all);
  const auto reference = fitness_detail::smoothTerms(programs, all, SetOperationKind::Sardf);
  ASSERT_EQ(fast.size(), programs.size());
  const double n = double(data.n);
  for (std::size_t j = 0; j < programs.size(); ++j) {
    EXPECT_TRUE(std::isfinite(fast[j].distance) && std::isfinite(fast[j].normal)) << j;
    EXPECT_NEAR(fast[j].distance, reference[j].distance, tolerance * n) << "program " << j;
    EXPECT_NEAR(fast[j].normal, reference[j].normal, tolerance * n) << "program " << j;
  }
  if (!pointByPoint) return;
  for (std::size_t i = 0; i < data.n; ++i) {
    SyntheticTables one = data.point(i);
    const fitness_detail::PointTables t = one.tables();
    const auto f = fitness_detail::sardfTerms(fused, t);
    const auto r = fitness_detail::smoothTerms(programs, t, SetOperationKind::Sardf);
    for (std::size_t j = 0; j < programs.size(); ++j) {
      ASSERT_NEAR(f[j].distance, r[j].distance, tolerance)
          << "program " << j << " point " << i << " values " << one.values[0] << " "
          << one.values[1];
      ASSERT_NEAR(f[j].normal, r[j].normal, tolerance)
          << "program " << j << " point " << i << " values " << one.values[0] << " "
          << one.values[1];
    }
  }
}

// Pairs of values on and around the edges of SARDF's blend band (R = 0.25,
// so that R, 2R and their neighbours are exact floats): opposite signs,
// zeros of both signs, a difference of exactly R and one float either side,
// a ratio of exactly 2 and one float either side, equal values, the zone
// boundaries (c = 2R, c = −R), far and tiny values.
TEST(Fitness, SardfKernelMatchesPointByPointSardfAtTheBandEdges) {
  const float r = 0.25f;
  std::vector<std::pair<float, float>> pairs;
  const auto up = [](float x) { return std::nextafter(x, 1e30f); };
  const auto down = [](float x) { return std::nextafter(x, -1e30f); };
  for (const float s : {1.0f, -1.0f}) {
    for (const float x :
         {0.0f, 1e-30f, 1e-3f, 0.05f, 0.1f, 0.2f, 0.25f, 0.3f, 0.5f, 0.75f, 1.0f, 3.0f, 1e3f}) {
      const float a = s * x;
      for (const float b :
           {a, s * (x + r), up(s * (x + r)), down(s * (x + r)), 2.0f * a, up(2.0f * a),
            down(2.0f * a), -a, 0.0f, -0.0f, s * (x + 0.5f * r), 0.5f * a, s * (x + 2.0f * r)}) {
        pairs.emplace_back(a, b);
        pairs.emplace_back(b, a);
      }
    }
  }
  // Around and on the zone boundary circles, of centre (R, R) and
  // (−2R, −2R) and radius R.
  for (int k = 0; k <= 16; ++k) {
    const double t = std::numbers::pi * (0.5 + k / 16.0);
    pairs.emplace_back(float(r + r * std::cos(t) + 0.5), float(r + r * std::sin(t) + 0.5));
    pairs.emplace_back(float(r * (1.0 + std::cos(t / 2))), float(r * (1.0 + std::sin(t / 2))));
    pairs.emplace_back(float(-2 * r + r * std::cos(t / 2)), float(-2 * r + r * std::sin(t / 2)));
  }
  SyntheticTables data(pairs.size(), 2, 41);
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    data.values[i] = pairs[i].first;
    data.values[data.n + i] = pairs[i].second;
  }
  data.radius = r;
  data.epsilon = 0.3;  // the distance term still changes with the value out to the band's edge
  data.alpha = 20.0 * std::numbers::pi / 180.0;
  expectSardfKernelMatches(data, sardfPrograms(2, 43), true, 2e-5);
}

// Random values over a few radii around zero, over more than one chunk.
TEST(Fitness, SardfKernelMatchesPointByPointSardfOnRandomValues) {
  SyntheticTables data(3000, 6, 47);
  test::Rng rng(53);
  std::uniform_real_distribution<double> u(-0.6, 0.6);
  for (float& v : data.values) v = float(u(rng));
  data.radius = 0.2;
  data.epsilon = 0.1;
  data.alpha = 15.0 * std::numbers::pi / 180.0;
  expectSardfKernelMatches(data, sardfPrograms(6, 59), false, 2e-6);
}

// On real trees' fields: the fitness with SARDF against the point-by-point
// reference on the same model's arrays, and against the tree's own field.
TEST(Fitness, SardfKernelMatchesPointByPointSardfOnTrees) {
  const test::OrientedPoints in = noisyCube(61);
  const PrimitiveLibrary library = test::cubePlanes({Sphere{Vec3(0.5, 0.5, 0.5), 0.8},
                                                     Cylinder{Vec3::Zero(), Vec3::UnitY(), 0.5, 3},
                                                     HalfSpace{Vec3(1, 1, 0).normalized(), 0.9}});
  FitnessOptions options;
  options.operations = SetOperationKind::Sardf;
  const FitnessModel model(in.points, in.normals, kDiagonal, library, options);
  std::vector<CsgTree> trees = randomTrees(library, 67, 60, 6, 0.85);
  for (std::size_t t = 0; t < trees.size(); t += 6) trees[t] = CsgTree::complement(trees[t]);
  trees.push_back(test::cubeTree(library));
  // The model's own arrays, rebuilt the way it builds them.
  SyntheticTables data(in.points.size(), library.size(), 0);
  for (std::size_t q = 0; q < library.size(); ++q) {
    for (std::size_t i = 0; i < in.points.size(); ++i) {
      Vec3 g;
      data.values[q * data.n + i] = float(library.primitive(q).valueAndGradient(in.points[i], g));
      data.gradX[q * data.n + i] = float(g.x());
      data.gradY[q * data.n + i] = float(g.y());
      data.gradZ[q * data.n + i] = float(g.z());
    }
  }
  for (std::size_t i = 0; i < in.points.size(); ++i) {
    data.normX[i] = float(in.normals[i].x());
    data.normY[i] = float(in.normals[i].y());
    data.normZ[i] = float(in.normals[i].z());
  }
  data.radius = options.sardfRadius * kDiagonal;
  data.epsilon = options.distanceTolerance * kDiagonal;
  data.alpha = options.angleTolerance * std::numbers::pi / 180.0;
  std::vector<fitness_detail::Program> programs;
  for (const CsgTree& t : trees) programs.push_back(fitness_detail::compile(t, library));
  expectSardfKernelMatches(data, programs, false, 2e-6);
  // The model runs the kernel.
  const fitness_detail::PointTables tables = data.tables();
  const auto ref = fitness_detail::smoothTerms(programs, tables, SetOperationKind::Sardf);
  const double n = double(in.points.size());
  for (std::size_t t = 0; t < trees.size(); ++t) {
    const Fitness f = model.evaluate(trees[t]);
    EXPECT_NEAR(f.distanceTerm, ref[t].distance, 2e-6 * n) << t;
    EXPECT_NEAR(f.normalTerm, ref[t].normal, 2e-6 * n) << t;
  }
  expectTermsMatchDirect(model, in, SardfOperations(options.sardfRadius * kDiagonal), trees);
}

TEST(Fitness, VoxelTermCountsDisagreeingVoxelCentres) {
  const test::OrientedPoints in = test::cubeFacePoints(8);
  const PrimitiveLibrary library = test::cubePlanes({Sphere{Vec3(1, 1, 1), 1.2}});
  VoxelTarget target;
  target.grid = VoxelGrid(Vec3::Constant(-1.5), Mat3::Identity(), 0.1, {30, 30, 31});
  target.inside = VoxelSet(target.grid.voxelCount());
  const CsgTree cube = test::cubeTree(library);
  for (std::size_t v = 0; v < target.grid.voxelCount(); ++v) {
    if (cube.contains(target.grid.center(v))) target.inside.set(v);
  }
  FitnessOptions options;
  options.voxelWeight = 1.0;
  const FitnessModel model(in.points, in.normals, kDiagonal, library, options, &target);
  EXPECT_EQ(model.evaluate(cube).voxelMismatch, 0u);
  EvolveRng rng(5);
  for (int t = 0; t < 20; ++t) {
    CsgTree tree = randomTree(rng, library, 4, 0.8);
    if (t % 4 == 0) tree = CsgTree::complement(tree);
    std::size_t mismatch = 0;
    for (std::size_t v = 0; v < target.grid.voxelCount(); ++v) {
      mismatch += tree.contains(target.grid.center(v)) != target.inside.test(v);
    }
    const Fitness f = model.evaluate(tree);
    EXPECT_EQ(f.voxelMismatch, mismatch) << t;
    EXPECT_NEAR(f.voxelPenalty,
                double(in.points.size()) * double(mismatch) / double(target.inside.count()), 1e-9);
  }
}

TEST(Fitness, RefusesForeignLeavesAndBadInput) {
  const test::OrientedPoints in = test::cubeFacePoints(4);
  const PrimitiveLibrary library = test::cubePlanes();
  const FitnessModel model(in.points, in.normals, kDiagonal, library);
  EXPECT_THROW(model.evaluate(CsgTree::leaf(Sphere{})), std::invalid_argument);
  EXPECT_THROW(model.evaluate(CsgTree()), std::invalid_argument);
  // A leaf equal to a library primitive is that primitive.
  EXPECT_NO_THROW(model.evaluate(CsgTree::leaf(HalfSpace{Vec3::UnitX(), 1.0})));
  const std::vector<Vec3> none;
  EXPECT_THROW(FitnessModel(none, none, 1.0, library), std::invalid_argument);
  EXPECT_THROW(FitnessModel(in.points, none, 1.0, library), std::invalid_argument);
  FitnessOptions voxels;
  voxels.voxelWeight = 1.0;
  EXPECT_THROW(FitnessModel(in.points, in.normals, 1.0, library, voxels), std::invalid_argument);
}

// treeFitness (point by point, no tables) against the model on the same
// points, for each kind of operations; the sizes and totals too.
TEST(Fitness, TreeFitnessIsTheModelsWithoutItsTables) {
  const test::OrientedPoints in = noisyCube(17);
  const PrimitiveLibrary library = test::cubePlanes(
      {Sphere{Vec3(0.3, 0.1, 0.0), 0.7}, Cylinder{Vec3::Zero(), Vec3::UnitX(), 0.4, 3.0}});
  const double n = double(in.points.size());
  for (const SetOperationKind kind :
       {SetOperationKind::MinMax, SetOperationKind::Sardf, SetOperationKind::RFunction}) {
    FitnessOptions options;
    options.angleTolerance = 20.0;
    options.operations = kind;
    const FitnessModel model(in.points, in.normals, kDiagonal, library, options);
    std::vector<CsgTree> trees = randomTrees(library, 19, 12, 5, 0.8);
    trees.push_back(CsgTree::complement(trees.front()));
    for (std::size_t t = 0; t < trees.size(); ++t) {
      const Fitness expected = model.evaluate(trees[t]);
      const Fitness got = treeFitness(trees[t], in.points, in.normals, kDiagonal, options);
      // Both sums are of float terms; R-functions' tables round f itself.
      const double tolerance = (kind == SetOperationKind::RFunction ? 1e-4 : 1e-6) * n;
      EXPECT_NEAR(got.distanceTerm, expected.distanceTerm, tolerance) << int(kind) << " " << t;
      EXPECT_NEAR(got.normalTerm, expected.normalTerm, tolerance) << int(kind) << " " << t;
      EXPECT_EQ(got.nodes, expected.nodes);
      EXPECT_DOUBLE_EQ(got.sizePenalty, expected.sizePenalty);
      EXPECT_NEAR(got.total, expected.total, 2 * tolerance);
    }
  }
  // A tree that misses every point scores (almost) nothing.
  const CsgTree far = CsgTree::leaf(Sphere{Vec3(10.0, 10.0, 10.0), 0.1});
  EXPECT_LT(treeFitness(far, in.points, in.normals, kDiagonal).distanceTerm, 1e-6);
}

TEST(Fitness, TreeFitnessIsTheSameOnAnyNumberOfThreads) {
  // More points than one block, so the blocks are summed.
  const test::OrientedPoints in = test::cubeFacePoints(60);
  ASSERT_GT(in.points.size(), 3 * 4096u);
  const PrimitiveLibrary library = test::cubePlanes({Sphere{Vec3(0.5, 0.5, 0.5), 0.8}});
  const CsgTree tree =
      CsgTree::subtract({test::cubeTree(library), library.leafTree(library.size() - 1)});
  Fitness one, two;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    one = treeFitness(tree, in.points, in.normals, kDiagonal);
  }
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
    two = treeFitness(tree, in.points, in.normals, kDiagonal);
  }
  EXPECT_EQ(one.total, two.total);
  EXPECT_EQ(one.distanceTerm, two.distanceTerm);
  EXPECT_EQ(one.normalTerm, two.normalTerm);
  EXPECT_GT(one.distanceTerm, 0.5 * double(in.points.size()));
}

TEST(Fitness, TreeFitnessRefusesBadInput) {
  const test::OrientedPoints in = test::cubeFacePoints(4);
  const PrimitiveLibrary library = test::cubePlanes();
  const CsgTree tree = test::cubeTree(library);
  const std::vector<Vec3> none;
  EXPECT_THROW(treeFitness(tree, none, none, 1.0), std::invalid_argument);
  EXPECT_THROW(treeFitness(tree, in.points, none, 1.0), std::invalid_argument);
  EXPECT_THROW(treeFitness(tree, in.points, in.normals, 0.0), std::invalid_argument);
  EXPECT_THROW(treeFitness(CsgTree(), in.points, in.normals, 1.0), std::invalid_argument);
  FitnessOptions voxels;
  voxels.voxelWeight = 1.0;
  EXPECT_THROW(treeFitness(tree, in.points, in.normals, 1.0, voxels), std::invalid_argument);
}

TEST(Fitness, SpreadSampleIsSortedDistinctAndSeeded) {
  const auto a = spreadSample(1000, 100, 3), b = spreadSample(1000, 100, 3);
  EXPECT_EQ(a, b);
  ASSERT_EQ(a.size(), 100u);
  EXPECT_TRUE(std::is_sorted(a.begin(), a.end()));
  EXPECT_EQ(std::adjacent_find(a.begin(), a.end()), a.end());
  EXPECT_NE(a, spreadSample(1000, 100, 4));
  EXPECT_EQ(spreadSample(10, 50, 1).size(), 10u);
}

// The rough model is the full one on the sampled points: the same fitness,
// bit for bit, as a model built on those points from scratch (λ = ln of
// their number, the voxel term shared with the full model).
TEST(Fitness, TheRoughModelIsTheFullOneOnTheSample) {
  const test::OrientedPoints in = noisyCube(31);
  const PrimitiveLibrary library = test::cubePlanes({Sphere{Vec3(1, 1, 1), 1.2}});
  VoxelTarget target;
  target.grid = VoxelGrid(Vec3::Constant(-1.5), Mat3::Identity(), 0.1, {30, 30, 31});
  target.inside = VoxelSet(target.grid.voxelCount());
  for (std::size_t v = 0; v < target.grid.voxelCount(); ++v) {
    if (target.grid.center(v).cwiseAbs().maxCoeff() < 1.0) target.inside.set(v);
  }
  FitnessOptions options;
  options.voxelWeight = 0.7;
  options.angleTolerance = 25.0;
  const FitnessModel full(in.points, in.normals, kDiagonal, library, options, &target);
  const std::size_t count = in.points.size() / 3;
  const std::optional<FitnessModel> rough = roughModel(full, in.points, in.normals, count, 9);
  ASSERT_TRUE(rough.has_value());
  EXPECT_EQ(rough->pointCount(), count);
  EXPECT_DOUBLE_EQ(rough->sizeWeight(), std::log(double(count)));
  std::vector<Vec3> p, n;
  for (const std::uint32_t i : spreadSample(in.points.size(), count, 9)) {
    p.push_back(in.points[i]);
    n.push_back(in.normals[i]);
  }
  const FitnessModel scratch(p, n, kDiagonal, library, options, &target);
  std::vector<CsgTree> trees = randomTrees(library, 37, 20, 5, 0.8);
  trees.push_back(test::cubeTree(library));
  for (const CsgTree& t : trees) {
    const Fitness a = rough->evaluate(t), b = scratch.evaluate(t);
    EXPECT_EQ(a.distanceTerm, b.distanceTerm);
    EXPECT_EQ(a.normalTerm, b.normalTerm);
    EXPECT_EQ(a.voxelMismatch, b.voxelMismatch);
    EXPECT_EQ(a.total, b.total);
  }
  EXPECT_GT(rough->evaluate(trees.front()).voxelMismatch, 0u);
  EXPECT_FALSE(roughModel(full, in.points, in.normals, 0, 9).has_value());
  EXPECT_FALSE(roughModel(full, in.points, in.normals, in.points.size(), 9).has_value());
}

}  // namespace
}  // namespace csgvox
