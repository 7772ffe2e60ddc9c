// csgvox eval TREE.json SCAN [--json] [--reference TRUE.json]

#include <cstdio>
#include <iostream>

#include "app/commands.h"
#include "app/options.h"
#include "core/solid_sampling.h"
#include "io/report.h"
#include "io/scan_reader.h"
#include "io/tree_json.h"
#include "job/console.h"
#include "mesh/fit_metrics.h"

namespace csgvox::app {

namespace {

struct EvalOptions {
  std::string tree;
  std::string scan;
  bool json = false;
  std::string reference;
  int iouResolution = 200;
  FitOptions fit;
};

}  // namespace

Command setupEval(CLI::App& app, CommonOptions& common) {
  auto opt = std::make_shared<EvalOptions>();
  app.add_option("TREE", opt->tree, "CSG tree (tree.json)")->required();
  app.add_option("SCAN", opt->scan, "Scan to compare with (any format csgvox reads)")->required();
  app.add_flag("--json", opt->json, "Print the metrics as JSON on stdout");
  app.add_option("--surface-samples", opt->fit.surfaceSamples,
                 "Points sampled on the tree's boundary for distances")
      ->check(inRange(1000, 50'000'000));
  app.add_option("--reference", opt->reference,
                 "A reference tree (tree.json, e.g. the part's true tree): adds the volumetric "
                 "IoU of the two solids");
  app.add_option("--iou-res", opt->iouResolution,
                 "Cells along the longest side of the stratified grid of the volumetric IoU")
      ->check(inRange(2, 2000));
  app.add_option("--seed", opt->fit.seed, "Random seed of the boundary sampling")
      ->check(nonNegativeInteger());
  return [opt, &common]() -> int {
    Console console(common.quiet);
    common.subject = opt->tree;
    const CsgTree tree = readTreeJson(std::filesystem::path(opt->tree));
    const Scan scan = readScan(std::filesystem::path(opt->scan));
    console.info("read " + opt->scan + ": " + describeScan(scan));
    Stopwatch watch;
    const FitMetrics m = evaluateFit(tree, scan.cloud, opt->fit);
    console.info("evaluated in " + std::to_string(watch.seconds()) + " s");
    const double d = m.diagonal;
    nlohmann::ordered_json j;
    j["tree"] = opt->tree;
    j["scan"] = opt->scan;
    j["points"] = m.points;
    j["diagonal"] = d;
    j["primitives"] = tree.primitiveCount();
    j["operations"] = tree.operationCount();
    j["depth"] = tree.depth();
    j["rmse"] = m.rmse;
    j["rmse_relative"] = m.rmse / d;
    j["surface_rmse"] = m.surfaceRmse;
    j["surface_rmse_relative"] = m.surfaceRmse / d;
    j["chamfer"] = m.chamfer;
    j["chamfer_relative"] = m.chamfer / d;
    j["max_distance"] = m.maxDistance;
    j["max_distance_relative"] = m.maxDistance / d;
    j["within_1pct"] = m.withinFraction;
    if (m.hasNormals) {
      j["normal_agreement"] = m.normalAgreement;
      j["normals_within_10deg"] = m.normalsWithin10Deg;
    }
    if (!opt->reference.empty()) {
      common.subject = opt->reference;
      const CsgTree reference = readTreeJson(std::filesystem::path(opt->reference));
      j["reference"] = opt->reference;
      j["iou_reference"] = volumetricIou(tree, reference, opt->iouResolution);
    }
    if (opt->json) {
      std::cout << j.dump(2) << "\n";
      return 0;
    }
    std::printf("tree                 %s (%zu primitives, %zu operations, depth %zu)\n",
                opt->tree.c_str(), tree.primitiveCount(), tree.operationCount(), tree.depth());
    std::printf("scan                 %s (%zu points, diagonal D = %.6g)\n", opt->scan.c_str(),
                m.points, d);
    std::printf("RMSE (Wu Eq. 9)      %.6g  (%.4f %% of D)\n", m.rmse, 100 * m.rmse / d);
    std::printf("surface RMSE         %.6g  (%.4f %% of D)\n", m.surfaceRmse,
                100 * m.surfaceRmse / d);
    std::printf("Chamfer distance     %.6g  (%.4f %% of D)\n", m.chamfer, 100 * m.chamfer / d);
    std::printf("max distance         %.6g  (%.4f %% of D)\n", m.maxDistance,
                100 * m.maxDistance / d);
    std::printf("within 1 %% of D      %.2f %% of points\n", 100 * m.withinFraction);
    if (j.contains("iou_reference")) {
      std::printf("IoU with reference   %.4f  (%s)\n", j["iou_reference"].get<double>(),
                  opt->reference.c_str());
    }
    if (m.hasNormals) {
      std::printf("normal agreement     %.4f mean cosine, %.2f %% within 10 degrees\n",
                  m.normalAgreement, 100 * m.normalsWithin10Deg);
    }
    return 0;
  };
}

}  // namespace csgvox::app
