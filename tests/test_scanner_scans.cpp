// The main job on every bundled part's scanner scan (data/<part>/scan_scanner.ply:
// the scanner model's defaults, two setups, raw x y z, 20 000 points), read
// as the main job reads it (outliers removed, normals estimated and
// oriented) and compared with the part's true tree: IoU >= 0.97 and at most
// two primitives more than the truth. The parts that do not reach that bar
// yet are listed with their measured figure and reason; each must not fall
// further, and the test fails when one starts to pass (take it off the list).

#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <vector>

#include "io/scan_reader.h"
#include "io/tree_json.h"
#include "part_list.h"
#include "pipeline/reconstruct.h"
#include "test_helpers.h"

namespace csgvox {
namespace {

struct KnownGap {
  const char* part;
  double floor;  // the IoU it must keep (measured less 0.05)
  const char* reason;
};

// None now: bearing_housing (14 primitives for 11, its bore cut twice, each
// to its own depth) left the list when one cut of a surface shared by two
// union members became one (withSharedCuts; 13 primitives, IoU 0.994).
const std::vector<KnownGap> kKnownGaps = {};

const KnownGap* knownGap(const std::string& part) {
  for (const KnownGap& g : kKnownGaps) {
    if (part == g.part) return &g;
  }
  return nullptr;
}

// Folder of each bundled part: data/<part> and data/thin/<part>.
std::vector<std::string> partFolders() {
  std::vector<std::string> folders = test::partNames();
  for (const auto& e : std::filesystem::directory_iterator(test::dataDir() / "thin")) {
    if (e.is_directory() && std::filesystem::exists(e.path() / "tree.json")) {
      folders.push_back("thin/" + e.path().filename().string());
    }
  }
  return folders;
}

class ScannerScan : public ::testing::TestWithParam<std::string> {};

TEST_P(ScannerScan, VolumeAndPrimitiveCount) {
  const std::string folder = GetParam();
  const std::string part = std::filesystem::path(folder).filename().string();
  const CsgTree truth = readTreeJson(test::dataDir() / folder / "tree.json");
  const Scan scan = readScan(test::dataDir() / folder / "scan_scanner.ply");
  ASSERT_TRUE(scan.info.normalsEstimated);
  ReconstructOptions options;
  options.detect.estimatedNormals = scan.info.normalsEstimated;
  const Reconstruction rec = reconstruct(scan.cloud, options);
  ASSERT_TRUE(rec.ok()) << rec.message;
  const double iou = test::treeIou(rec.tree, truth);
  const std::size_t prims = rec.tree.primitiveCount();
  const bool passes = iou >= 0.97 && prims <= truth.primitiveCount() + 2;
  std::printf("%s: IoU %.4f, %zu primitives (truth %zu), %zu outliers removed\n", folder.c_str(),
              iou, prims, truth.primitiveCount(), scan.info.outliersRemoved);
  RecordProperty("iou", std::to_string(iou));
  if (const KnownGap* g = knownGap(part)) {
    EXPECT_FALSE(passes) << folder << " reaches the bar now: take it off kKnownGaps";
    EXPECT_GE(iou, g->floor) << folder << " (" << g->reason << ")";
    std::printf("known gap: %s\n", g->reason);
    return;
  }
  EXPECT_GE(iou, 0.97) << folder;
  EXPECT_LE(prims, truth.primitiveCount() + 2) << folder;
}

INSTANTIATE_TEST_SUITE_P(BundledParts, ScannerScan, ::testing::ValuesIn(partFolders()),
                         [](const auto& info) {
                           std::string name = info.param;
                           for (char& ch : name) {
                             if (ch == '/') ch = '_';
                           }
                           return name;
                         });

}  // namespace
}  // namespace csgvox
