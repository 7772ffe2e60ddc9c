// The finish: the Ceres fit of a tree's shared parameters on the points
// (primitives/tree_parameters.h, primitives/tree_fitting.h) and its
// acceptance in the hybrid method (pipeline/finish.h).

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <random>

#include "core/solid_sampling.h"
#include "io/scan_reader.h"
#include "io/tree_json.h"
#include "part_list.h"
#include "pipeline/finish.h"
#include "pipeline/reconstruct.h"
#include "primitives/tree_fitting.h"

namespace csgvox {
namespace {

// Exploration: hybrid without finish, then finish variants, IoU against the
// truth. Run with --gtest_also_run_disabled_tests; FINISH_PARTS limits parts.
TEST(FinishExplore, DISABLED_Variants) {
  const char* only = std::getenv("FINISH_PARTS");
  for (const std::string& part : test::partNames()) {
    if (only && std::string(only).find(part) == std::string::npos) continue;
    const CsgTree truth = readTreeJson(test::dataDir() / part / "tree.json");
    for (const char* file : {"scan.ply", "scan_noisy.ply"}) {
      const Scan scan = readScan(test::dataDir() / part / file);
      ReconstructOptions ro;
      ro.finish.enabled = false;
      const Reconstruction rec = reconstruct(scan.cloud, ro);
      if (!rec.ok()) continue;
      const VoxelTarget target{rec.grid, rec.labels.inside};
      const double iou0 = volumetricIou(rec.tree, truth, 150);
      std::printf("%s/%s: IoU %.4f\n", part.c_str(), file, iou0);
      struct Variant {
        const char* name;
        FinishOptions o;
      };
      std::vector<Variant> variants;
      variants.push_back({"sardf", {}});
      FinishOptions mm;
      mm.operations = SetOperationKind::MinMax;
      variants.push_back({"minmax", mm});
      for (const Variant& v : variants) {
        const FinishResult f = finishTree(scan.cloud, rec.tree, &target, v.o);
        const double iou1 = volumetricIou(f.fit.tree, truth, 150);
        std::printf(
            "  %-8s rms %.4g -> %.4g  fit %.1f -> %.1f  viou %.4f -> %.4f  IoU %.4f -> %.4f  "
            "%s  %d it  %zu par  %.2fs\n",
            v.name, f.fit.rmsBefore, f.fit.rmsAfter, f.before.total, f.after.total,
            f.voxelIouBefore, f.voxelIouAfter, iou0, iou1, f.accepted ? "ACC" : "rej",
            f.fit.iterations, f.fit.parameters, f.seconds);
      }
    }
  }
}

}  // namespace
}  // namespace csgvox
