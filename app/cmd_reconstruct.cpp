// The main job: csgvox SCAN [--res N] [-o OUTDIR] ...
// scan → surfaces → hypotheses → voxel labels → Wu's two optimisations →
// tree.json, tree.scad, tree.txt, mesh.ply, report.json.

#include "app/commands.h"
#include "app/console.h"
#include "app/report.h"
#include "io/errors.h"
#include "io/mesh_export.h"
#include "io/scad_export.h"
#include "io/scan_reader.h"
#include "io/text_export.h"
#include "io/tree_json.h"
#include "io/triangle_mesh.h"
#include "optimize/csg_construction.h"
#include "primitives/fit_metrics.h"
#include "primitives/hypotheses.h"
#include "primitives/regularization.h"
#include "primitives/surface_detection.h"
#include "primitives/surface_refinement.h"
#include "voxel/description_sets.h"
#include "voxel/labeling.h"

#include <cstdio>
#include <filesystem>

namespace csgvox::app {

namespace fs = std::filesystem;

namespace {

struct ReconstructOptions {
  std::string scan;
  std::string outDir;
  int resolution = 64;
  std::uint64_t seed = 1;
  std::string labelMethod = "winding";
  LabelOptions labels;
  ConstructOptions construct;
  int meshResolution = 160;
};

std::string fmt(const char* format, double a, double b = 0.0) {
  char buf[256];
  std::snprintf(buf, sizeof(buf), format, a, b);
  return buf;
}

}  // namespace

Command setupReconstruct(CLI::App& app, CommonOptions& common) {
  auto opt = std::make_shared<ReconstructOptions>();
  app.add_option("SCAN", opt->scan,
                 "Scan to reconstruct: PLY, XYZ, XYZN point cloud, or OFF/OBJ/STL/PLY mesh")
      ->required();
  app.add_option("-o,--output", opt->outDir,
                 "Output directory (default: <scan folder>/<scan name>-csgvox/)");
  app.add_option("--res", opt->resolution, "Voxels along the longest side of the part")
      ->check(CLI::Range(8, 1024));
  app.add_option("--seed", opt->seed, "Random seed; the same seed gives the same tree");
  app.add_option("--label", opt->labelMethod,
                 "Voxel labelling: winding (generalised winding number) or vote (Wu's K-nearest "
                 "normal vote)")
      ->check(CLI::IsMember({"winding", "vote"}));
  app.add_option("-K,--neighbors", opt->labels.neighbors, "vote: nearest points per voxel")
      ->check(CLI::Range(1, 1000));
  app.add_option("--vote-epsilon", opt->labels.epsilon,
                 "vote: outside when more than this fraction of neighbours face the voxel")
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--alpha", opt->construct.subtree.alpha, "Weight of the fit term of Wu Eq. 4")
      ->check(CLI::Range(0.0, 100.0));
  app.add_option("--beta", opt->construct.unionChoice.beta, "Weight of the fit term of Wu Eq. 6")
      ->check(CLI::Range(0.0, 100.0));
  app.add_option("--mesh-res", opt->meshResolution, "Resolution of mesh.ply")
      ->check(CLI::Range(8, 2048));
  return [opt, &common]() -> int {
    Console console(common.quiet);
    const fs::path scanPath(opt->scan);
    nlohmann::ordered_json timings;
    Stopwatch watch;
    ReadOptions ro;
    ro.seed = opt->seed;
    const Scan scan = readScan(scanPath, ro);
    timings["read"] = watch.seconds();
    console.info("read " + scanPath.string() + ": " + describeScan(scan));

    watch = Stopwatch();
    DetectOptions dopt;
    dopt.seed = opt->seed;
    DetectionResult det = detectSurfaces(scan.cloud, dopt);
    if (det.status != DetectionResult::Status::Ok) {
      throw ParseError(scanPath.string() + ": " + det.message);
    }
    refineSurfaces(scan.cloud, det);
    regularizeSurfaces(det);
    timings["detect"] = watch.seconds();
    console.info("surfaces: " + det.message);

    watch = Stopwatch();
    GridOptions go;
    go.resolution = opt->resolution;
    const VoxelGrid grid = VoxelGrid::around(minimalOrientedBox(scan.cloud.points), go);
    HypothesisOptions ho;
    ho.voxelSize = grid.voxelSize();
    ho.seed = std::uint32_t(opt->seed);
    const HypothesisSet hyp = generateHypotheses(scan.cloud, det.surfaces, ho);
    timings["hypotheses"] = watch.seconds();
    console.info("hypotheses: " + std::to_string(hyp.candidates.size()) + " candidates");

    watch = Stopwatch();
    opt->labels.method = labelMethodFromName(opt->labelMethod);
    const VoxelLabels labels = labelVoxels(grid, scan.cloud, opt->labels);
    timings["labels"] = watch.seconds();
    const auto& dims = grid.dims();
    console.info("voxels: " + std::to_string(dims[0]) + " x " + std::to_string(dims[1]) + " x " +
                 std::to_string(dims[2]) + ", " + std::to_string(labels.inside.count()) +
                 " inside (" + opt->labelMethod + ")");

    watch = Stopwatch();
    std::vector<CsgTree> candidates;
    for (const Candidate& c : hyp.candidates) candidates.push_back(c.tree);
    const std::vector<DescriptionSet> descriptions = describeAll(candidates, grid, labels);
    timings["description_sets"] = watch.seconds();
    watch = Stopwatch();
    opt->construct.snapDistance = grid.voxelSize();
    const Construction built = constructCsg(candidates, descriptions, labels.inside,
                                            opt->construct);
    timings["optimisation"] = watch.seconds();
    if (built.tree.empty()) {
      throw ParseError(scanPath.string() +
                       ": no combination of the detected primitives explains the scan");
    }
    const CsgTree& tree = built.tree;
    console.info("tree: " + std::to_string(tree.primitiveCount()) + " primitives, " +
                 std::to_string(tree.operationCount()) + " operations, depth " +
                 std::to_string(tree.depth()));

    fs::path out = opt->outDir.empty()
                       ? scanPath.parent_path() / (scanPath.stem().string() + "-csgvox")
                       : fs::path(opt->outDir);
    std::error_code ec;
    fs::create_directories(out, ec);
    if (ec || !fs::is_directory(out)) {
      throw IoError(out.string() + ": cannot create the output directory");
    }
    watch = Stopwatch();
    writeTreeJson(out / "tree.json", tree);
    writeScad(out / "tree.scad", tree);
    writeTreeText(out / "tree.txt", tree);
    MeshOptions mo;
    mo.resolution = opt->meshResolution;
    writeMesh(out / "mesh.ply", meshTree(tree, mo));
    timings["export"] = watch.seconds();

    watch = Stopwatch();
    FitOptions fo;
    fo.surfaceSamples = 100000;
    fo.seed = opt->seed;
    const FitMetrics fit = evaluateFit(tree, scan.cloud, fo);
    timings["metrics"] = watch.seconds();
    const std::size_t both = VoxelSet::countAnd(built.voxels, labels.inside);
    const std::size_t either = VoxelSet::countOr(built.voxels, labels.inside);

    Report report;
    report.json["status"] = "ok";
    report.json["input"] = scanJson(scanPath, scan);
    report.json["parameters"] = {{"res", opt->resolution},
                                 {"seed", opt->seed},
                                 {"label", opt->labelMethod},
                                 {"alpha", opt->construct.subtree.alpha},
                                 {"beta", opt->construct.unionChoice.beta}};
    report.json["grid"] = {{"dims", {dims[0], dims[1], dims[2]}},
                           {"voxel_size", grid.voxelSize()}};
    const ConstructStats& st = built.stats;
    report.json["counts"] = {{"surfaces", det.surfaces.size()},
                             {"hypotheses", hyp.candidates.size()},
                             {"usable_roots", st.usableRoots},
                             {"truncation_roots", st.truncationRoots},
                             {"subtrees", st.subtrees},
                             {"union_candidates", st.unionCandidates},
                             {"chosen", st.chosen},
                             {"proved_optimal", st.provedOptimal}};
    report.json["tree"] = {{"primitives", tree.primitiveCount()},
                           {"operations", tree.operationCount()},
                           {"depth", tree.depth()}};
    report.json["metrics"] = {{"voxel_iou", either ? double(both) / double(either) : 1.0},
                              {"rmse", fit.rmse},
                              {"rmse_relative", fit.rmse / fit.diagonal},
                              {"chamfer", fit.chamfer},
                              {"chamfer_relative", fit.chamfer / fit.diagonal},
                              {"within_1pct", fit.withinFraction},
                              {"normal_agreement", fit.normalAgreement}};
    report.json["timings_s"] = timings;
    report.write(out / "report.json");
    console.info(fmt("fit: Chamfer %.3g %% of D, RMSE %.3g %% of D", 100 * fit.chamfer / fit.diagonal,
                     100 * fit.rmse / fit.diagonal));
    console.info("wrote tree.json, tree.scad, tree.txt, mesh.ply, report.json in " + out.string());
    return 0;
  };
}

}  // namespace csgvox::app
