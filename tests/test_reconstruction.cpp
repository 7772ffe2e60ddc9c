// The main job against ground truth: on every bundled part, clean and noisy,
// the reconstructed tree must match the part's true tree in volume (IoU ≥
// 0.95, by sampling both trees) with at most the true primitive count + 2.
// Parts the voxel stage cannot reconstruct yet are named in kKnownGaps with
// the reason; the test fails when one of them starts to pass, so the list
// only shrinks.

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <chrono>
#include <cstdio>
#include <string>
#include <thread>

#include "io/scan_reader.h"
#include "io/tree_json.h"
#include "mesh/fit_metrics.h"
#include "mesh/surface_sampler.h"
#include "part_list.h"
#include "pipeline/reconstruct.h"
#include "test_helpers.h"

namespace csgvox {
namespace {

struct KnownGap {
  const char* part;
  const char* scan;
  const char* reason;
};

// Empty: every bundled scan reaches the bar. A part that cannot (a feature
// voxels cannot see) is listed here with the measured reason, and the test
// fails when it starts to pass.
const std::vector<KnownGap> kKnownGaps = {};

const KnownGap* knownGap(const std::string& part, const std::string& scan) {
  for (const KnownGap& g : kKnownGaps) {
    if (part == g.part && scan == g.scan) return &g;
  }
  return nullptr;
}

struct Case {
  std::string part;
  std::string scan;
};

void PrintTo(const Case& c, std::ostream* os) { *os << c.part << "/" << c.scan; }

std::vector<Case> allCases() {
  std::vector<Case> cases;
  for (const std::string& p : test::partNames()) {
    for (const char* s : {"scan.ply", "scan_noisy.ply"}) cases.push_back({p, s});
  }
  return cases;
}

class ReconstructionVsTruth : public ::testing::TestWithParam<Case> {};

TEST_P(ReconstructionVsTruth, VolumeAndPrimitiveCount) {
  const Case& c = GetParam();
  const CsgTree truth = readTreeJson(test::dataDir() / c.part / "tree.json");
  const Scan scan = readScan(test::dataDir() / c.part / c.scan);
  const Reconstruction rec = reconstruct(scan.cloud);
  const std::size_t truePrims = truth.primitiveCount();
  double iou = 0.0;
  std::size_t prims = 0;
  if (rec.ok()) {
    iou = test::treeIou(rec.tree, truth);
    prims = rec.tree.primitiveCount();
  }
  // Chamfer distance to the scan catches what volume hides: a sub-voxel lid
  // or skin has almost no volume but a whole face of surface far from the
  // scan. A perfect tree scores about 0.26 % of D on the noisy scans.
  double chamfer = 1.0;
  if (rec.ok()) {
    FitOptions fo;
    fo.surfaceSamples = 50000;
    const FitMetrics fit = evaluateFit(rec.tree, scan.cloud, fo);
    chamfer = fit.chamfer / fit.diagonal;
  }
  const double chamferBound = c.scan == "scan.ply" ? 0.003 : 0.005;
  const bool passes = rec.ok() && iou >= 0.95 && prims <= truePrims + 2 && chamfer <= chamferBound;
  std::printf("%s/%s: %s, IoU %.4f, %zu primitives (truth %zu), Chamfer %.3f %% of D\n",
              c.part.c_str(), c.scan.c_str(), rec.ok() ? "ok" : rec.message.c_str(), iou, prims,
              truePrims, 100.0 * chamfer);
  RecordProperty("iou", std::to_string(iou));
  RecordProperty("primitives", std::to_string(prims));
  if (const KnownGap* g = knownGap(c.part, c.scan)) {
    EXPECT_FALSE(passes) << c.part << "/" << c.scan
                         << " reaches the bar now: remove it from kKnownGaps";
    // A known gap must not get worse unnoticed.
    EXPECT_TRUE(rec.ok()) << rec.message;
    EXPECT_GE(iou, 0.85);
    std::printf("known gap: %s\n", g->reason);
    return;
  }
  ASSERT_TRUE(rec.ok()) << rec.message;
  EXPECT_GE(iou, 0.95) << c.part << "/" << c.scan;
  EXPECT_LE(prims, truePrims + 2) << c.part << "/" << c.scan;
  EXPECT_LE(chamfer, chamferBound) << c.part << "/" << c.scan;
}

INSTANTIATE_TEST_SUITE_P(BundledParts, ReconstructionVsTruth, ::testing::ValuesIn(allCases()),
                         [](const auto& info) {
                           std::string name = info.param.part + "_" + info.param.scan;
                           for (char& ch : name) {
                             if (ch == '.') ch = '_';
                           }
                           return name;
                         });

TEST(Reconstruction, SameSeedSameTree) {
  const Scan scan = readScan(test::dataDir() / "housing_complex" / "scan_noisy.ply");
  ReconstructOptions o;
  o.seed = 5;
  const Reconstruction a = reconstruct(scan.cloud, o);
  const Reconstruction b = reconstruct(scan.cloud, o);
  ASSERT_EQ(a.ok(), b.ok());
  if (a.ok()) {
    EXPECT_EQ(treeNodeJson(a.tree), treeNodeJson(b.tree));
  }
}

// The tree of a reconstruction run with at most `threads` worker threads.
std::string treeAtThreads(const PointCloud& cloud, const ReconstructOptions& o, int threads) {
  const tbb::global_control limit(tbb::global_control::max_allowed_parallelism,
                                  std::size_t(threads));
  const Reconstruction r = reconstruct(cloud, o);
  EXPECT_TRUE(r.ok()) << r.message;
  return treeNodeJson(r.tree);
}

TEST(Reconstruction, SameTreeAtOneAndTwoThreads) {
  const Scan scan = readScan(test::dataDir() / "housing_complex" / "scan_noisy.ply");
  ReconstructOptions o;
  EXPECT_EQ(treeAtThreads(scan.cloud, o, 1), treeAtThreads(scan.cloud, o, 2));
  EXPECT_EQ(treeAtThreads(scan.cloud, o, 1), treeAtThreads(scan.cloud, o, 3));
}

TEST(Reconstruction, SameTreeAtOneAndTwoThreadsWhenDetectionSearchesASubsample) {
  const Scan scan = readScan(test::dataDir() / "housing_complex" / "scan_noisy.ply");
  ReconstructOptions o;
  o.detect.ransacPoints = 4000;  // of the scan's 10 000 points
  EXPECT_EQ(treeAtThreads(scan.cloud, o, 1), treeAtThreads(scan.cloud, o, 2));
}

// A scan larger than the detection's search gives the tree of the even
// subsample detection searched: the stages after detection work on those
// points (in their time), with the surfaces fitted on every point.
TEST(Reconstruction, ABigScanGivesTheTreeOfItsSubsample) {
  const CsgTree truth = readTreeJson(test::dataDir() / "housing_complex" / "tree.json");
  SampleOptions so;
  so.points = 40000;
  so.seed = 3;
  const PointCloud big = sampleSurface(truth, so).cloud;
  ReconstructOptions o;
  o.detect.ransacPoints = 10000;
  const Reconstruction whole = reconstruct(big, o);
  ASSERT_TRUE(whole.ok()) << whole.message;
  ASSERT_FALSE(whole.detection.searched.empty());
  EXPECT_EQ(whole.pointsAfterDetection, whole.detection.searched.size());
  EXPECT_NEAR(double(whole.pointsAfterDetection), 10000.0, 1000.0);
  // The repair's fitness sums one term of at most 1 per point it worked on,
  // nearly 1 for points on the tree: on every point it would be about 4x.
  const auto* hybrid = whole.resultAs<HybridMethodResult>();
  ASSERT_NE(hybrid, nullptr);
  EXPECT_LE(hybrid->repair.before.distanceTerm, double(whole.pointsAfterDetection));
  EXPECT_GE(hybrid->repair.before.distanceTerm, 0.9 * double(whole.pointsAfterDetection));
  EXPECT_GE(test::treeIou(whole.tree, truth), 0.99);
  EXPECT_LE(whole.tree.primitiveCount(), truth.primitiveCount() + 2);
  // The subsample alone, searched whole.
  ReconstructOptions all = o;
  all.detect.ransacPoints = 0;
  const Reconstruction sub = reconstruct(big.subset(whole.detection.searched), all);
  ASSERT_TRUE(sub.ok()) << sub.message;
  EXPECT_TRUE(sub.detection.searched.empty());
  EXPECT_EQ(sub.pointsAfterDetection, whole.pointsAfterDetection);
  EXPECT_EQ(whole.tree.primitiveCount(), sub.tree.primitiveCount());
  EXPECT_GE(test::treeIou(whole.tree, sub.tree), 0.998);
}

// By default the search is on at most about 50 000 points, the size of the
// benchmark's scans: a scan of that size is searched whole, and a 100 000
// point scan on its subsample, with the true tree.
TEST(Reconstruction, TheDefaultSearchTakesAbout50000PointsOfABiggerScan) {
  const CsgTree truth = readTreeJson(test::dataDir() / "housing_complex" / "tree.json");
  SampleOptions so;
  so.seed = 4;
  so.points = 50000;
  const Reconstruction atSize = reconstruct(sampleSurface(truth, so).cloud, ReconstructOptions{});
  ASSERT_TRUE(atSize.ok()) << atSize.message;
  EXPECT_TRUE(atSize.detection.searched.empty());
  EXPECT_EQ(atSize.pointsAfterDetection, 50000u);
  so.points = 100000;
  const Reconstruction big = reconstruct(sampleSurface(truth, so).cloud, ReconstructOptions{});
  ASSERT_TRUE(big.ok()) << big.message;
  EXPECT_EQ(big.pointsAfterDetection, big.detection.searched.size());
  EXPECT_NEAR(double(big.pointsAfterDetection), 50000.0, 5000.0);
  EXPECT_EQ(big.tree.primitiveCount(), truth.primitiveCount());
  EXPECT_GE(test::treeIou(big.tree, truth), 0.999);
}

TEST(Reconstruction, ReportsEveryStageInOrder) {
  const Scan scan = readScan(test::dataDir() / "plate_holes" / "scan.ply");
  std::vector<std::string> started, finished;
  const Reconstruction r =
      reconstruct(scan.cloud, {}, [&](std::string_view stage, bool done, const std::string&) {
        (done ? finished : started).emplace_back(stage);
      });
  ASSERT_TRUE(r.ok()) << r.message;
  // The default (hybrid) method ends with the refinement on the points.
  const std::vector<std::string> stages{"detect",           "hypotheses",   "labels",
                                        "description_sets", "optimisation", "repair"};
  EXPECT_EQ(started, stages);
  EXPECT_EQ(finished, stages);
  ASSERT_EQ(r.timings.size(), stages.size());
  for (std::size_t i = 0; i < stages.size(); ++i) {
    EXPECT_EQ(r.timings[i].stage, stages[i]);
    EXPECT_GE(r.timings[i].seconds, 0.0);
  }
  EXPECT_GT(r.voxelIou(), 0.9);
}

TEST(Reconstruction, TinyTimeLimitStopsCleanly) {
  const Scan scan = readScan(test::dataDir() / "housing_complex" / "scan.ply");
  const Reconstruction r = reconstruct(scan.cloud, {}, {}, RunControl(1e-6));
  // The limit is spent before detection ends: no tree, and the reason.
  EXPECT_EQ(r.status, Reconstruction::Status::TimedOut);
  EXPECT_TRUE(r.tree.empty());
  EXPECT_TRUE(r.timeLimitHit);
  EXPECT_NE(r.message.find("time limit"), std::string::npos) << r.message;
}

TEST(Reconstruction, LimitPastDetectionStillGivesTheTree) {
  // The limit runs out while the labels are computed (the stage callback
  // holds the run there past the deadline): the job must still end with a
  // valid tree, as if the optimisation had been stopped (it failed "during
  // labelling" before). Detection of this scan takes about 0.1 s (1-3 s in
  // a sanitised build, hence the slowdown factor).
  const Scan scan = readScan(test::dataDir() / "plate_holes" / "scan.ply");
  const double limit = 3.0 * CSGVOX_TEST_SLOWDOWN;
  const RunControl control(limit);
  const auto pastDeadline = control.deadline() + std::chrono::milliseconds(200);
  const Reconstruction r = reconstruct(
      scan.cloud, {},
      [&](std::string_view stage, bool done, const std::string&) {
        if (stage == "labels" && !done) std::this_thread::sleep_until(pastDeadline);
      },
      control);
  ASSERT_EQ(r.status, Reconstruction::Status::Ok) << r.message;
  EXPECT_TRUE(r.timeLimitHit);
  EXPECT_FALSE(r.tree.empty());
  EXPECT_GT(r.voxelIou(), 0.9);
}

// A cancel request stops the run in whatever stage it comes: status
// Cancelled, no tree, no later stage started, and the stage it came in
// ends within half a second of the request (made as the stage starts).
// Each method's own stages are cancelled on their method.
TEST(Reconstruction, CancelStopsEveryStage) {
  // Its repair search has a region to search (5 s uncancelled).
  const Scan scan = readScan(test::dataDir() / "bearing_housing" / "scan.ply");
  const std::vector<std::pair<Method, std::string>> cases = {
      {Method::Hybrid, "detect"},       {Method::Hybrid, "hypotheses"},
      {Method::Hybrid, "labels"},       {Method::Hybrid, "description_sets"},
      {Method::Hybrid, "optimisation"}, {Method::Hybrid, "repair"},
      {Method::Hybrid, "finish"},       {Method::Gp, "evolve"},
      {Method::Voxel, "optimisation"}};
  for (const auto& [method, at] : cases) {
    ReconstructOptions o;
    o.method = method;
    o.finish.enabled = at == "finish";
    const RunControl control;
    std::chrono::steady_clock::time_point asked;
    std::vector<std::string> started;
    const Reconstruction r = reconstruct(
        scan.cloud, o,
        [&](std::string_view stage, bool done, const std::string&) {
          if (done) return;
          started.emplace_back(stage);
          if (stage == at) {
            asked = std::chrono::steady_clock::now();
            control.cancel();
          }
        },
        control);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - asked).count();
    EXPECT_EQ(r.status, Reconstruction::Status::Cancelled) << at << ": " << r.message;
    EXPECT_TRUE(r.tree.empty()) << at;
    ASSERT_FALSE(started.empty());
    EXPECT_EQ(started.back(), at) << "a stage started after the request";
    EXPECT_LT(seconds, 0.5 * CSGVOX_TEST_SLOWDOWN) << at;
  }
}

// A progress callback that returns false is a cancel request.
TEST(Reconstruction, ProgressReturningFalseCancels) {
  const Scan scan = readScan(test::dataDir() / "plate_holes" / "scan.ply");
  int calls = 0;
  const Reconstruction r =
      reconstruct(scan.cloud, {}, {}, RunControl(0.0, [&](double, std::string_view) {
                    ++calls;
                    return false;
                  }));
  EXPECT_EQ(r.status, Reconstruction::Status::Cancelled) << r.message;
  EXPECT_GE(calls, 1);
  EXPECT_NE(r.message.find("cancelled during detection"), std::string::npos) << r.message;
}

TEST(Reconstruction, RejectsScansWithoutNormals) {
  PointCloud cloud;
  EXPECT_THROW(reconstruct(cloud), std::invalid_argument);
  cloud.points.assign(200, Vec3::Zero());
  EXPECT_THROW(reconstruct(cloud), std::invalid_argument);
}

}  // namespace
}  // namespace csgvox
