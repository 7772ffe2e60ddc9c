// Detection → refinement → regularisation → hypotheses on the bundled scans
// (clean and noisy, 10 000 points): every observable ground-truth primitive of
// each part must have a matching candidate (candidate_matching.h defines the
// match: same type, axes within 2 degrees, visible geometry within 1 % of D).

#include <gtest/gtest.h>

#include <cstdio>

#include "candidate_matching.h"
#include "io/scan_reader.h"
#include "io/tree_json.h"
#include "part_list.h"
#include "pipeline/detect_and_fit.h"

namespace csgvox {
namespace {

// Primitives that the pipeline misses today, with the measured reason. They
// are checked to be still missed, so that fixing one forces updating this
// list, and nothing else may be missed.
struct KnownMiss {
  const char* part;
  const char* scan;
  const char* leaf;
  const char* reason;
};
// Empty: every observable primitive of every bundled scan has a candidate.
// A regression that cannot be fixed at once is listed here with its numbers.
const std::vector<KnownMiss> kKnownMisses = {};

const KnownMiss* knownMiss(const std::string& part, const std::string& scan,
                           const std::string& leaf) {
  for (const KnownMiss& k : kKnownMisses) {
    if (part == k.part && scan == k.scan && leaf == k.leaf) return &k;
  }
  return nullptr;
}

struct PipelineCase {
  std::string part;
  std::string scan;  // file name in data/<part>/
};

void PrintTo(const PipelineCase& c, std::ostream* os) { *os << c.part << "/" << c.scan; }

class DetectionPipeline : public ::testing::TestWithParam<PipelineCase> {};

TEST_P(DetectionPipeline, EveryObservablePrimitiveHasACandidate) {
  const auto& [part, scanName] = GetParam();
  const CsgTree tree = readTreeJson(test::dataDir() / part / "tree.json");
  const Scan scan = readScan(test::dataDir() / part / scanName);
  // The main job's own configuration (res 64, seed 1).
  const SurfacesAndCandidates found = detectAndFit(scan.cloud);
  const DetectionResult& det = found.detection;
  ASSERT_EQ(det.status, DetectionResult::Status::Ok) << det.message;
  const HypothesisSet& hyp = found.hypotheses;
  EXPECT_LE(hyp.candidates.size(), 600u);

  const test::GroundTruth gt = test::makeGroundTruth(tree);
  std::size_t observable = 0, matched = 0;
  for (std::size_t leaf = 0; leaf < gt.leaves.size(); ++leaf) {
    const test::LeafMatch m = test::matchLeaf(gt, leaf, hyp.candidates);
    if (!m.observable) continue;
    ++observable;
    matched += m.matched;
    if (const KnownMiss* k = knownMiss(part, scanName, gt.leaves[leaf]->name)) {
      EXPECT_FALSE(m.matched) << part << "/" << scanName << ": '" << k->leaf
                              << "' is matched now: remove it from kKnownMisses";
      std::printf("known gap: %s/%s '%s': %s\n", part.c_str(), scanName.c_str(), k->leaf,
                  k->reason);
      continue;
    }
    EXPECT_TRUE(m.matched) << part << "/" << scanName << ": leaf '" << gt.leaves[leaf]->name
                           << "' (" << primitiveTypeName(gt.leaves[leaf]->primitive.type())
                           << ") has no matching candidate: " << m.detail;
  }
  std::printf("%-18s %-15s %2zu surfaces, %3zu candidates, %zu/%zu primitives matched\n",
              part.c_str(), scanName.c_str(), det.surfaces.size(), hyp.candidates.size(), matched,
              observable);
}

std::vector<PipelineCase> cases() {
  std::vector<PipelineCase> out;
  for (const std::string& p : test::partNames()) {
    out.push_back({p, "scan.ply"});
    out.push_back({p, "scan_noisy.ply"});
  }
  return out;
}

INSTANTIATE_TEST_SUITE_P(BundledScans, DetectionPipeline, ::testing::ValuesIn(cases()),
                         [](const auto& info) {
                           std::string s = info.param.part + "_" + info.param.scan;
                           for (char& c : s) {
                             if (c == '.') c = '_';
                           }
                           return s;
                         });

}  // namespace
}  // namespace csgvox
