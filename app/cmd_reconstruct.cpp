// The main job: csgvox SCAN [--res N] [-o OUTDIR] ...
// scan → surfaces → hypotheses → voxel labels → Wu's two optimisations →
// tree.json, tree.scad, tree.txt, mesh.ply, report.json.

#include <cstdio>
#include <filesystem>
#include <optional>

#include "app/commands.h"
#include "app/console.h"
#include "app/options.h"
#include "io/errors.h"
#include "io/mesh_files.h"
#include "io/output_set.h"
#include "io/report.h"
#include "io/scad_export.h"
#include "io/scan_reader.h"
#include "io/text_export.h"
#include "io/tree_json.h"
#include "mesh/fit_metrics.h"
#include "mesh/mesh_export.h"
#include "pipeline/reconstruct.h"

namespace csgvox::app {

namespace fs = std::filesystem;

namespace {

struct CommandOptions {
  std::string scan;
  std::string outDir;
  int resolution = 64;
  std::uint64_t seed = 1;
  std::string labelMethod = "winding";
  std::string boundary = "centre";
  ReconstructOptions pipeline;
  int meshResolution = 160;
};

std::string fmt(const char* format, double a, double b = 0.0) {
  char buf[256];
  std::snprintf(buf, sizeof(buf), format, a, b);
  return buf;
}

}  // namespace

Command setupReconstruct(CLI::App& app, CommonOptions& common) {
  auto opt = std::make_shared<CommandOptions>();
  // Show every default in --help.
  app.option_defaults()->always_capture_default();
  app.add_option("SCAN", opt->scan,
                 "Scan to reconstruct: PLY, XYZ, XYZN point cloud, or OFF/OBJ/STL/PLY mesh")
      ->required();
  app.add_option("-o,--output", opt->outDir,
                 "Output directory (default: <scan folder>/<scan name>-csgvox/)");
  app.add_option("--res", opt->resolution, "Voxels along the longest side of the part")
      ->check(inRange(8, 1024));
  app.add_option("--seed", opt->seed, "Random seed; the same seed gives the same tree")
      ->check(nonNegativeInteger());
  app.add_option("--label", opt->labelMethod,
                 "Voxel labelling: winding (generalised winding number) or vote (Wu's K-nearest "
                 "normal vote)")
      ->check(CLI::IsMember({"winding", "vote"}));
  app.add_option("--label-boundary", opt->boundary,
                 "Voxels holding scan points: centre (labelled at their centre like every other "
                 "voxel; default) or inside (always inside, Wu's rule)")
      ->check(CLI::IsMember({"centre", "inside"}));
  app.add_option("-K,--neighbors", opt->pipeline.labels.neighbors, "vote: nearest points per voxel")
      ->check(inRange(1, 1000));
  app.add_option("--vote-epsilon", opt->pipeline.labels.epsilon,
                 "vote: outside when more than this fraction of neighbours face the voxel")
      ->check(inRange(0.0, 1.0));
  app.add_option("--alpha", opt->pipeline.construct.subtree.alpha,
                 "Weight of the fit term of Wu Eq. 4")
      ->check(inRange(0.0, 100.0));
  app.add_option("--beta", opt->pipeline.construct.unionChoice.beta,
                 "Weight of the fit term of Wu Eq. 6")
      ->check(inRange(0.0, 100.0));
  app.add_option("--time-limit", opt->pipeline.timeLimit,
                 "Seconds for the reconstruction (0: none). Detection past it fails; the "
                 "optimisations past it keep the best tree found so far")
      ->check(inRange(0.0, 1e6));
  app.add_option("--mesh-res", opt->meshResolution, "Resolution of mesh.ply")
      ->check(inRange(8, 2048));
  return [opt, &common]() -> int {
    Console console(common.quiet);
    common.subject = opt->scan;
    const fs::path scanPath(opt->scan);
    nlohmann::ordered_json timings;
    Stopwatch watch;
    ReadOptions ro;
    ro.seed = opt->seed;
    const Scan scan = readScan(scanPath, ro);
    timings["read"] = watch.seconds();
    console.info("read " + scanPath.string() + ": " + describeScan(scan));
    // Outputs are checked against the input before the reconstruction, and
    // appear together at the end or not at all.
    const fs::path inputs[] = {scanPath};
    OutputSet output(opt->outDir.empty()
                         ? scanPath.parent_path() / (scanPath.stem().string() + "-csgvox")
                         : fs::path(opt->outDir),
                     {"tree.json", "tree.scad", "tree.txt", "mesh.ply", "report.json"}, inputs);

    ReconstructOptions ro2 = opt->pipeline;
    ro2.seed = opt->seed;
    ro2.resolution = opt->resolution;
    ro2.labels.method = labelMethodFromName(opt->labelMethod);
    ro2.labels.boundary = opt->boundary == "inside" ? BoundaryRule::Inside : BoundaryRule::Centre;
    const Reconstruction rec = reconstruct(
        scan.cloud, ro2,
        [&](std::string_view stage, bool done, const std::string& summary) {
          if (done) console.info(std::string(stage) + ": " + summary);
        },
        console.progress());
    for (const StageTime& t : rec.timings) timings[t.stage] = t.seconds;
    if (!rec.ok()) throw ParseError(scanPath.string() + ": " + rec.message);
    if (rec.timeLimitHit) {
      console.info("time limit reached: the optimisation kept its best solution so far");
    }
    const DetectionResult& det = rec.detection;
    const HypothesisSet& hyp = rec.hypotheses;
    const VoxelGrid& grid = rec.grid;
    const auto& dims = grid.dims();
    const Construction& built = rec.construction;
    const CsgTree& tree = built.tree;
    console.info("tree: " + std::to_string(tree.primitiveCount()) + " primitives, " +
                 std::to_string(tree.operationCount()) + " operations, depth " +
                 std::to_string(tree.depth()));

    watch = Stopwatch();
    writeTreeJson(output.path("tree.json"), tree);
    writeScad(output.path("tree.scad"), tree);
    writeTreeText(output.path("tree.txt"), tree);
    MeshOptions mo;
    mo.resolution = opt->meshResolution;
    writeMesh(output.path("mesh.ply"), meshTree(tree, mo, console.progress()));
    timings["export"] = watch.seconds();

    // The tree is the result: a metric that cannot be computed is a warning
    // in the report, not a failed job.
    watch = Stopwatch();
    nlohmann::ordered_json warnings = nlohmann::ordered_json::array();
    std::optional<FitMetrics> fit;
    try {
      FitOptions fo;
      fo.surfaceSamples = 100000;
      fo.seed = opt->seed;
      fit = evaluateFit(tree, scan.cloud, fo);
    } catch (const std::exception& e) {
      warnings.push_back(std::string("fit metrics: ") + e.what());
      console.info("warning: fit metrics not computed: " + std::string(e.what()));
    }
    timings["metrics"] = watch.seconds();

    nlohmann::ordered_json report;
    report["status"] = "ok";
    report["input"] = scanJson(scanPath, scan);
    report["parameters"] = {{"res", opt->resolution},
                            {"seed", opt->seed},
                            {"label", opt->labelMethod},
                            {"label_boundary", opt->boundary},
                            {"alpha", opt->pipeline.construct.subtree.alpha},
                            {"beta", opt->pipeline.construct.unionChoice.beta},
                            {"time_limit_s", opt->pipeline.timeLimit}};
    report["grid"] = {{"dims", {dims[0], dims[1], dims[2]}}, {"voxel_size", grid.voxelSize()}};
    const ConstructStats& st = built.stats;
    report["counts"] = {{"surfaces", det.surfaces.size()},
                        {"hypotheses", hyp.candidates.size()},
                        {"usable_roots", st.usableRoots},
                        {"truncation_roots", st.truncationRoots},
                        {"subtrees", st.subtrees},
                        {"union_candidates", st.unionCandidates},
                        {"chosen", st.chosen},
                        {"proved_optimal", st.provedOptimal},
                        {"time_limit_hit", rec.timeLimitHit}};
    report["tree"] = {{"primitives", tree.primitiveCount()},
                      {"operations", tree.operationCount()},
                      {"depth", tree.depth()}};
    nlohmann::ordered_json metrics = {{"voxel_iou", rec.voxelIou()}};
    if (fit) {
      metrics["rmse"] = fit->rmse;
      metrics["rmse_relative"] = fit->rmse / fit->diagonal;
      metrics["chamfer"] = fit->chamfer;
      metrics["chamfer_relative"] = fit->chamfer / fit->diagonal;
      metrics["within_1pct"] = fit->withinFraction;
      metrics["normal_agreement"] = fit->normalAgreement;
    }
    report["metrics"] = std::move(metrics);
    report["warnings"] = std::move(warnings);
    report["timings_s"] = timings;
    writeJsonFile(output.path("report.json"), report);
    output.commit();
    if (fit) {
      console.info(fmt("fit: Chamfer %.3g %% of D, RMSE %.3g %% of D",
                       100 * fit->chamfer / fit->diagonal, 100 * fit->rmse / fit->diagonal));
    }
    console.info("wrote tree.json, tree.scad, tree.txt, mesh.ply, report.json in " +
                 output.folder().string());
    return 0;
  };
}

}  // namespace csgvox::app
