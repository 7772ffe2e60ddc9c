// The finish: the Ceres fit of a tree's shared parameters on the points
// (primitives/tree_parameters.h, primitives/tree_fitting.h), its acceptance
// (pipeline/finish.h) and its place in the hybrid method and the CLI.

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "cli_helpers.h"
#include "core/solid_sampling.h"
#include "io/scan_reader.h"
#include "io/tree_json.h"
#include "mesh/surface_sampler.h"
#include "part_list.h"
#include "pipeline/finish.h"
#include "pipeline/reconstruct.h"
#include "primitives/tree_fitting.h"
#include "primitives/tree_parameters.h"
#include "voxel/description_sets.h"

namespace csgvox {
namespace {

// A plate with a boss standing on it, a coaxial hole through both and a
// slot: parallel and orthogonal faces, a coaxial boss and hole, the boss'
// bottom on the plate's top. `shift` moves the plate, boss
// and hole, `grow` changes their sizes.
CsgTree bracket(double shift = 0.0, double grow = 0.0) {
  const Box plate{Vec3(shift, 0, 0), Mat3::Identity(), Vec3(20 + grow, 12, 3)};
  const Cylinder boss{Vec3(8, shift, 6), Vec3::UnitZ(), 4 + grow, 6};
  const Cylinder hole{Vec3(8, shift, 3), Vec3::UnitZ(), 2 - 0.5 * grow, 14};
  const Box slot{Vec3(-10 + shift, 0, 3), Mat3::Identity(), Vec3(2 + grow, 20, 1.5)};
  return CsgTree::subtract(
      {CsgTree::unite({CsgTree::leaf(plate, "plate"), CsgTree::leaf(boss, "boss")}),
       CsgTree::leaf(hole, "hole"), CsgTree::leaf(slot, "slot")});
}

PointCloud sampled(const CsgTree& tree, double noise) {
  SampleOptions so;
  so.points = 20000;
  so.noise = noise;
  so.seed = 3;
  return sampleSurface(tree, so).cloud;
}

const Primitive& leafNamed(const CsgTree& tree, const std::string& name) {
  for (const Node* leaf : tree.leaves())
    if (leaf->name == name) return leaf->primitive;
  throw std::invalid_argument("no leaf " + name);
}

TEST(TreeParameters, SharesTheRelationsAndRebuildsTheTree) {
  const CsgTree tree = bracket();
  const TreeParameters p(tree, 50.0, Vec3(1, 2, 3));
  ASSERT_EQ(p.leafCount(), 4u);
  // One frame (one rotation) for the boxes and the axes; the boss and the
  // hole share their axis line. The boss' bottom lies on the plate's top
  // but faces the other way: not shared (two coincident faces of opposite
  // sides would make a surface of zero thickness).
  std::size_t rotations = 0, lines = 0;
  for (const ParameterBlock& b : p.blocks()) {
    rotations += b.kind == ParameterBlock::Kind::Rotation;
    lines += b.kind == ParameterBlock::Kind::Line;
  }
  EXPECT_EQ(rotations, 1u);
  EXPECT_EQ(lines, 1u);
  EXPECT_EQ(p.sharedBlocks(), 2u);
  // Two boxes side by side: their tops, bottoms, fronts and backs are
  // coplanar and face the same way (4 shared offsets, and the rotation);
  // the faces where they touch face each other (not shared).
  const CsgTree pair =
      CsgTree::unite({CsgTree::leaf(Box{Vec3(5, 5, 2.5), Mat3::Identity(), Vec3(5, 5, 2.5)}),
                      CsgTree::leaf(Box{Vec3(15, 5, 2.5), Mat3::Identity(), Vec3(5, 5, 2.5)})});
  EXPECT_EQ(TreeParameters(pair, 30.0, Vec3::Zero()).sharedBlocks(), 5u);
  std::vector<Primitive> rebuilt;
  ASSERT_TRUE(p.primitives(p.values(), rebuilt));
  const CsgTree again = p.tree(rebuilt);
  EXPECT_TRUE(again.structurallyEqual(tree, 1e-9));
  EXPECT_EQ(again.leaves()[0]->name, "plate");
  EXPECT_THROW(TreeParameters(CsgTree(), 1.0, Vec3::Zero()), std::invalid_argument);
  EXPECT_THROW(TreeParameters(tree, 0.0, Vec3::Zero()), std::invalid_argument);
}

TEST(TreeFitting, RecoversPerturbedParametersOnACleanScan) {
  const CsgTree truth = bracket();
  const PointCloud scan = sampled(truth, 0.0);
  const CsgTree perturbed = bracket(0.3, 0.2);
  const TreeFitResult r = fitTreeParameters(scan, perturbed);
  EXPECT_GT(r.points, 15000u);
  EXPECT_GT(r.rmsBefore, 0.05);
  EXPECT_LT(r.rmsAfter, 0.01 * r.rmsBefore);
  EXPECT_EQ(r.primitivesChanged, 4u);
  for (const char* name : {"plate", "boss", "hole", "slot"})
    EXPECT_TRUE(leafNamed(r.tree, name).approxEqual(leafNamed(truth, name), 0.002)) << name;
}

// A cancel request stops the fit (nothing fitted) and the finish (input kept);
// a deadline already past stops the solver at its first check with the
// parameters it has.
TEST(TreeFitting, ACancelStopsTheFitAndADeadlineKeepsWhatItReached) {
  const CsgTree truth = bracket();
  const PointCloud scan = sampled(truth, 0.0);
  const CsgTree perturbed = bracket(0.3, 0.2);
  TreeFitOptions cancelled;
  cancelled.control.cancel();
  const TreeFitResult stopped = fitTreeParameters(scan, perturbed, cancelled);
  EXPECT_TRUE(stopped.cancelled);
  EXPECT_EQ(stopped.primitivesChanged, 0u);
  EXPECT_EQ(stopped.tree, perturbed);

  TreeFitOptions late;
  late.control = RunControl(1e-9);
  const TreeFitResult first = fitTreeParameters(scan, perturbed, late);
  EXPECT_FALSE(first.cancelled);
  EXPECT_LE(first.iterations, 1);
  EXPECT_GT(fitTreeParameters(scan, perturbed).iterations, 1);

  FinishOptions fo;
  fo.control.cancel();
  const FinishResult f = finishTree(scan, perturbed, nullptr, fo);
  EXPECT_TRUE(f.cancelled);
  EXPECT_FALSE(f.accepted);
  EXPECT_EQ(f.tree, perturbed);
}

TEST(TreeFitting, ReducesTheResidualOfAPerturbedTreeOnANoisyScan) {
  const CsgTree truth = bracket();
  // Noise 0.5 % of D, as the bundled noisy scans.
  const PointCloud scan = sampled(truth, 0.005);
  const CsgTree perturbed = bracket(0.3, 0.2);
  const TreeFitResult r = fitTreeParameters(scan, perturbed);
  EXPECT_LT(r.rmsAfter, 0.9 * r.rmsBefore);
  const double before = volumetricIou(perturbed, truth, 150);
  const double after = volumetricIou(r.tree, truth, 150);
  EXPECT_LT(before, 0.975);
  EXPECT_GT(after, 0.993);
  // Sizes back within a few hundredths (the noise is 0.24).
  EXPECT_NEAR(leafNamed(r.tree, "plate").as<Box>()->halfSize.x(), 20.0, 0.03);
  EXPECT_NEAR(leafNamed(r.tree, "boss").as<Cylinder>()->radius, 4.0, 0.03);
  EXPECT_NEAR(leafNamed(r.tree, "hole").as<Cylinder>()->radius, 2.0, 0.03);
}

TEST(TreeFitting, KeepsParallelPlanesAndCoaxialAxesExact) {
  // A block cut by a tilted slab (two parallel half-spaces) with a hole
  // whose axis is the slab's normal; everything perturbed alike, so the
  // relations hold at the start.
  const Vec3 n = Vec3(0.3, 0.1, 1.0).normalized();
  const auto part = [&](double d) {
    const Box block{Vec3::Zero(), Mat3::Identity(), Vec3(15, 10, 8)};
    const HalfSpace below{n, 3.0 + d}, above{-n, 3.0 - d};  // |n·x| <= 3: the slab
    const Cylinder hole{Vec3(5 + d, 0, 0), n, 2.0 + d, 30};
    return CsgTree::subtract(
        {CsgTree::leaf(block, "block"),
         CsgTree::intersect({CsgTree::leaf(below, "below"), CsgTree::leaf(above, "above")}),
         CsgTree::leaf(hole, "hole")});
  };
  const PointCloud scan = sampled(part(0.0), 0.002);
  const TreeFitResult r = fitTreeParameters(scan, part(0.25));
  EXPECT_LT(r.rmsAfter, 0.5 * r.rmsBefore);
  EXPECT_EQ(r.sharedBlocks, 1u);  // the slab's and the hole's frame
  const HalfSpace below = *leafNamed(r.tree, "below").as<HalfSpace>();
  const HalfSpace above = *leafNamed(r.tree, "above").as<HalfSpace>();
  const Cylinder hole = *leafNamed(r.tree, "hole").as<Cylinder>();
  // Exactly parallel, not merely close: the same direction, bit for bit.
  EXPECT_EQ(below.normal, Vec3(-above.normal));
  EXPECT_EQ(hole.axis, below.normal);
  EXPECT_NEAR(below.offset, 3.0, 0.05);
  EXPECT_NEAR(above.offset, 3.0, 0.05);
  EXPECT_NEAR(hole.radius, 2.0, 0.05);
}

TEST(TreeFitting, RefusesBadInput) {
  const PointCloud scan = sampled(bracket(), 0.0);
  EXPECT_THROW(fitTreeParameters(scan, CsgTree()), std::invalid_argument);
  EXPECT_THROW(fitTreeParameters(PointCloud{}, bracket()), std::invalid_argument);
  // No point near the tree: nothing to fit, the input comes back.
  const CsgTree far = CsgTree::leaf(Sphere{Vec3(500, 0, 0), 1.0});
  const TreeFitResult r = fitTreeParameters(scan, far);
  EXPECT_EQ(r.points, 0u);
  EXPECT_TRUE(r.tree.structurallyEqual(far));
}

// The finish keeps a worse fit out: a tree whose fit the voxel labels
// disagree with is returned unchanged.
TEST(Finish, AcceptsOnlyWhatTheFitnessAndTheVoxelsAgreeWith) {
  const CsgTree truth = bracket();
  const PointCloud scan = sampled(truth, 0.0);
  const VoxelGrid grid =
      VoxelGrid::around(OrientedBox{Vec3(0, 0, 1), Mat3::Identity(), Vec3(21, 13, 6)});
  const VoxelTarget target{grid, solidVoxels(truth, grid)};
  const FinishResult good = finishTree(scan, bracket(0.3, 0.2), &target);
  EXPECT_TRUE(good.ran);
  EXPECT_TRUE(good.accepted);
  EXPECT_GT(good.after.total, good.before.total);
  EXPECT_GE(good.voxelIouAfter, good.voxelIouBefore);
  EXPECT_EQ(good.primitivesChanged, 4u);
  EXPECT_GT(volumetricIou(good.tree, truth, 150), 0.999);
  // Labels of the perturbed tree: the fit moves away from them, so the
  // voxel IoU drops and the input is kept.
  const VoxelTarget wrong{grid, solidVoxels(bracket(0.6, 0.5), grid)};
  const FinishResult kept = finishTree(scan, bracket(0.6, 0.5), &wrong);
  EXPECT_TRUE(kept.ran);
  EXPECT_FALSE(kept.accepted);
  EXPECT_LT(kept.voxelIouAfter, kept.voxelIouBefore);
  EXPECT_TRUE(kept.tree.structurallyEqual(bracket(0.6, 0.5)));
  EXPECT_EQ(kept.primitivesChanged, 0u);
}

// On bundled parts, clean and noisy: the hybrid with the finish is not
// further from the true part than without it, beyond 1e-3 of IoU (clean
// stepped_shaft loses 5.0e-4, 0.99900 -> 0.99850, while its Chamfer and
// residual improve: the fit follows the scan's points, and the truth differs
// from them there).
TEST(Finish, NeverLowersTheIouAgainstTheTruthOnBundledParts) {
  for (const std::string part : {"l_bracket", "plate_holes", "stepped_shaft"}) {
    const CsgTree truth = readTreeJson(test::dataDir() / part / "tree.json");
    for (const char* file : {"scan.ply", "scan_noisy.ply"}) {
      const Scan scan = readScan(test::dataDir() / part / file);
      ReconstructOptions with, without;
      with.finish.enabled = true;
      without.finish.enabled = false;
      const Reconstruction a = reconstruct(scan.cloud, with);
      const Reconstruction b = reconstruct(scan.cloud, without);
      ASSERT_TRUE(a.ok() && b.ok()) << part << "/" << file;
      ASSERT_TRUE(a.resultAs<HybridMethodResult>() && b.resultAs<HybridMethodResult>());
      EXPECT_TRUE(a.resultAs<HybridMethodResult>()->finish.ran) << part << "/" << file;
      EXPECT_FALSE(b.resultAs<HybridMethodResult>()->finish.ran);
      const double iouA = volumetricIou(a.tree, truth, 150);
      const double iouB = volumetricIou(b.tree, truth, 150);
      EXPECT_GE(iouA, iouB - 1e-3) << part << "/" << file;
      EXPECT_GE(a.voxelIou(), b.voxelIou()) << part << "/" << file;
      EXPECT_EQ(a.tree.primitiveCount(), b.tree.primitiveCount());
    }
  }
}

class FinishCli : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = test::freshTempDir("finish-cli"); }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(FinishCli, ReportsTheFinishAndNoFinishSkipsIt) {
  const std::string scan = (test::dataDir() / "plate_holes" / "scan.ply").string();
  const fs::path on = dir_ / "on", off = dir_ / "off";
  ASSERT_EQ(run("'" + scan + "' -o '" + on.string() + "' -q --no-preview --finish", dir_).code, 0);
  ASSERT_EQ(run("'" + scan + "' -o '" + off.string() + "' -q --no-preview --no-finish", dir_).code,
            0);
  const auto a = nlohmann::json::parse(slurp(on / "report.json"));
  const auto b = nlohmann::json::parse(slurp(off / "report.json"));
  ASSERT_TRUE(a.contains("finish"));
  EXPECT_TRUE(a["finish"]["ran"].get<bool>());
  for (const char* key : {"accepted", "residual_rms_before", "residual_rms_after", "fitness_before",
                          "fitness_after", "primitives_changed", "seconds"})
    EXPECT_TRUE(a["finish"].contains(key)) << key;
  EXPECT_TRUE(a["parameters"]["finish"].get<bool>());
  EXPECT_TRUE(a["timings_s"].contains("finish"));
  EXPECT_FALSE(b.contains("finish"));
  EXPECT_FALSE(b["parameters"]["finish"].get<bool>());
  EXPECT_FALSE(b["timings_s"].contains("finish"));
}

}  // namespace
}  // namespace csgvox
