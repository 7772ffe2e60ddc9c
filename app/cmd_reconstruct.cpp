// The main job: csgvox SCAN [--res N] [-o OUTDIR] ...
// scan → surfaces → hypotheses → voxel labels → Wu's two optimisations →
// tree.json, tree.scad, tree.txt, mesh.ply, report.json.

#include "app/commands.h"
#include "app/console.h"
#include "app/report.h"
#include "io/errors.h"
#include "mesh/mesh_export.h"
#include "io/scad_export.h"
#include "io/scan_reader.h"
#include "io/text_export.h"
#include "io/tree_json.h"
#include "pipeline/reconstruct.h"
#include "io/mesh_files.h"
#include "mesh/fit_metrics.h"

#include <cstdio>
#include <filesystem>

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
      ->check(CLI::Range(8, 1024));
  app.add_option("--seed", opt->seed, "Random seed; the same seed gives the same tree");
  app.add_option("--label", opt->labelMethod,
                 "Voxel labelling: winding (generalised winding number) or vote (Wu's K-nearest "
                 "normal vote)")
      ->check(CLI::IsMember({"winding", "vote"}));
  app.add_option("--label-boundary", opt->boundary,
                 "Voxels holding scan points: centre (labelled at their centre like every other "
                 "voxel; default) or inside (always inside, Wu's rule)")
      ->check(CLI::IsMember({"centre", "inside"}));
  app.add_option("-K,--neighbors", opt->pipeline.labels.neighbors, "vote: nearest points per voxel")
      ->check(CLI::Range(1, 1000));
  app.add_option("--vote-epsilon", opt->pipeline.labels.epsilon,
                 "vote: outside when more than this fraction of neighbours face the voxel")
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--alpha", opt->pipeline.construct.subtree.alpha, "Weight of the fit term of Wu Eq. 4")
      ->check(CLI::Range(0.0, 100.0));
  app.add_option("--beta", opt->pipeline.construct.unionChoice.beta, "Weight of the fit term of Wu Eq. 6")
      ->check(CLI::Range(0.0, 100.0));
  app.add_option("--time-limit", opt->pipeline.timeLimit,
                 "Seconds for the reconstruction (0: none). Detection past it fails; the "
                 "optimisations past it keep the best tree found so far")
      ->check(CLI::Range(0.0, 1e6));
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

    ReconstructOptions ro2 = opt->pipeline;
    ro2.seed = opt->seed;
    ro2.resolution = opt->resolution;
    ro2.labels.method = labelMethodFromName(opt->labelMethod);
    ro2.labels.boundary = opt->boundary == "inside" ? BoundaryRule::Inside : BoundaryRule::Centre;
    const Reconstruction rec =
        reconstruct(
            scan.cloud, ro2,
            [&](std::string_view stage, bool done, const std::string& summary) {
              if (done) console.info(std::string(stage) + ": " + summary);
            },
            [&, last = console.elapsed()](double fraction, std::string_view step) mutable {
              // A line every few seconds while a stage runs long.
              if (console.elapsed() - last >= 3.0) {
                last = console.elapsed();
                console.info("  " + std::string(step) + " " +
                             std::to_string(int(100.0 * fraction)) + " %");
              }
              return true;
            });
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

    Report report;
    report.json["status"] = "ok";
    report.json["input"] = scanJson(scanPath, scan);
    report.json["parameters"] = {{"res", opt->resolution},
                                 {"seed", opt->seed},
                                 {"label", opt->labelMethod},
                                 {"label_boundary", opt->boundary},
                                 {"alpha", opt->pipeline.construct.subtree.alpha},
                                 {"beta", opt->pipeline.construct.unionChoice.beta},
                                 {"time_limit_s", opt->pipeline.timeLimit}};
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
                             {"proved_optimal", st.provedOptimal},
                             {"time_limit_hit", rec.timeLimitHit}};
    report.json["tree"] = {{"primitives", tree.primitiveCount()},
                           {"operations", tree.operationCount()},
                           {"depth", tree.depth()}};
    report.json["metrics"] = {{"voxel_iou", rec.voxelIou()},
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
