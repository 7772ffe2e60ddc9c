#include "job/job.h"

#include <cstdio>

#include "cad/step_export.h"
#include "io/csg_writer.h"
#include "io/mesh_files.h"
#include "io/png_file.h"
#include "io/report.h"
#include "io/scad_export.h"
#include "io/text_export.h"
#include "io/tree_json.h"
#include "mesh/mesh_export.h"
#include "render/preview.h"

namespace csgvox {

const std::vector<std::string>& jobFiles() {
  static const std::vector<std::string> files = {"tree.json", "tree.scad",  "tree.txt",
                                                 "tree.csg",  "tree.step",  "preview.png",
                                                 "mesh.ply",  "report.json"};
  return files;
}

namespace {

std::string fmt(const char* format, double a, double b = 0.0) {
  char buf[256];
  std::snprintf(buf, sizeof(buf), format, a, b);
  return buf;
}

// Eq. 7 of the tree on every scan point with the gp settings' tolerances and
// min/max, whatever built the tree: the figure `compare` ranks methods by.
Fitness pointFitness(const CsgTree& tree, const Scan& scan, const JobOptions& options) {
  FitnessOptions fo = options.reconstruct.gp.fitness;
  fo.operations = SetOperationKind::MinMax;
  fo.voxelWeight = 0.0;
  const FitnessModel model(scan.cloud.points, scan.cloud.normals, scan.cloud.diagonal(),
                           PrimitiveLibrary::ofTree(tree), fo);
  return model.evaluate(tree);
}

// tree.step and preview.png. The tree is the result: a solid OpenCASCADE
// cannot build costs tree.step only (one error line naming the node, a
// warning in the report), not the job.
void writeCadOutputs(OutputSet& output, const Scan& scan, const CsgTree& tree,
                     const TriangleMesh& mesh, const JobOptions& options,
                     nlohmann::ordered_json& timings, nlohmann::ordered_json& warnings,
                     const RunControl& control) {
  Stopwatch watch;
  if (!stepExportAvailable()) {
    output.skip("tree.step");
    warnings.push_back("tree.step: not written: this build has no OpenCASCADE");
  } else {
    try {
      StepOptions so;
      so.control = control;
      writeStep(output.path("tree.step"), tree, so);
    } catch (const CadError& e) {
      output.skip("tree.step");
      std::fprintf(stderr, "csgvox: error: tree.step not written: %s\n", e.what());
      warnings.push_back(std::string("tree.step: not written: ") + e.what());
    }
  }
  timings["step"] = watch.seconds();
  if (!options.preview) {
    output.skip("preview.png");
    return;
  }
  watch = Stopwatch();
  writePng(output.path("preview.png"), renderPreview(tree, mesh, &scan.cloud).image);
  timings["preview"] = watch.seconds();
}

// Every file of the job but report.json; `ctx` gains the export, step and
// preview timings and any warning.
void writeTreeFiles(OutputSet& output, const Scan& scan, const CsgTree& tree,
                    const JobOptions& options, ReportContext& ctx, const RunControl& control) {
  Stopwatch watch;
  writeTreeJson(output.path("tree.json"), tree);
  writeScad(output.path("tree.scad"), tree);
  writeTreeText(output.path("tree.txt"), tree);
  writeCsg(output.path("tree.csg"), tree);
  MeshOptions mo;
  mo.resolution = options.meshResolution;
  const TriangleMesh mesh = meshTree(tree, mo, control);
  writeMesh(output.path("mesh.ply"), mesh);
  ctx.timings["export"] = watch.seconds();
  writeCadOutputs(output, scan, tree, mesh, options, ctx.timings, ctx.warnings, control);
}

// The files written so far, in the order of jobFiles(), report.json included.
std::vector<std::string> writtenFiles(const OutputSet& output) {
  std::vector<std::string> names;
  for (const std::string& name : jobFiles()) {
    if (name == "report.json" || std::filesystem::exists(output.path(name))) {
      names.push_back(name);
    }
  }
  return names;
}

ReportContext contextOf(const std::filesystem::path& scanPath, const Scan& scan,
                        const JobOptions& options, nlohmann::ordered_json timings) {
  ReportContext ctx;
  ctx.scanPath = scanPath;
  ctx.scan = &scan;
  ctx.timeLimit = options.timeLimit;
  ctx.timings = std::move(timings);
  return ctx;
}

// Measures the tree into ctx (with the metrics' seconds) and prints the fit line.
void measureInto(ReportContext& ctx, const CsgTree& tree, double voxelIou,
                 const JobOptions& options, const Console& console) {
  Stopwatch watch;
  ctx.metrics = measureTree(tree, *ctx.scan, voxelIou, options, ctx.warnings, console);
  ctx.timings["metrics"] = watch.seconds();
  if (const auto& fit = ctx.metrics.fit) {
    console.info(fmt("fit: Chamfer %.3g %% of D, RMSE %.3g %% of D",
                     100 * fit->chamfer / fit->diagonal, 100 * fit->rmse / fit->diagonal));
  }
}

// Every file of the job, the tree measured, then report.json as `build`
// shapes it from the context; returns the report.
template <class BuildReport>
nlohmann::ordered_json writeFilesAndReport(OutputSet& output, ReportContext ctx,
                                           const CsgTree& tree, double voxelIou,
                                           const JobOptions& options, const Console& console,
                                           const RunControl& control, const BuildReport& build) {
  writeTreeFiles(output, *ctx.scan, tree, options, ctx, control);
  measureInto(ctx, tree, voxelIou, options, console);
  ctx.outputs = writtenFiles(output);
  const nlohmann::ordered_json report = build(ctx);
  writeJsonFile(output.path("report.json"), report);
  return report;
}

}  // namespace

TreeMetrics measureTree(const CsgTree& tree, const Scan& scan, double voxelIou,
                        const JobOptions& options, nlohmann::ordered_json& warnings,
                        const Console& console) {
  TreeMetrics m;
  m.voxelIou = voxelIou;
  // The tree is the result: a metric that cannot be computed is a warning
  // in the report, not a failed job.
  try {
    FitOptions fo;
    fo.surfaceSamples = 100000;
    fo.seed = options.reconstruct.seed;
    m.fit = evaluateFit(tree, scan.cloud, fo);
  } catch (const std::exception& e) {
    warnings.push_back(std::string("fit metrics: ") + e.what());
    console.info("warning: fit metrics not computed: " + std::string(e.what()));
  }
  m.fitness = pointFitness(tree, scan, options);
  return m;
}

nlohmann::ordered_json writeJob(OutputSet& output, const std::filesystem::path& scanPath,
                                const Scan& scan, const Reconstruction& rec,
                                const JobOptions& options, nlohmann::ordered_json timings,
                                const Console& console, const RunControl& control) {
  return writeFilesAndReport(output, contextOf(scanPath, scan, options, std::move(timings)),
                             rec.tree, rec.voxelIou(), options, console, control,
                             [&](const ReportContext& ctx) {
                               return reconstructionReport(rec, options.reconstruct, ctx);
                             });
}

nlohmann::ordered_json writeImportedJob(OutputSet& output, const std::filesystem::path& scanPath,
                                        const Scan& scan, const ImportedTree& imported,
                                        double voxelIou, const JobOptions& options,
                                        const Console& console, const RunControl& control) {
  return writeFilesAndReport(
      output, contextOf(scanPath, scan, options, nlohmann::ordered_json::object()), *imported.tree,
      voxelIou, options, console, control, [&](const ReportContext& ctx) {
        return importedTreeReport(imported, options.reconstruct, ctx);
      });
}

nlohmann::ordered_json reportWithoutFiles(const std::filesystem::path& scanPath, const Scan& scan,
                                          const Reconstruction& rec, const JobOptions& options,
                                          nlohmann::ordered_json timings, const Console& console) {
  ReportContext ctx = contextOf(scanPath, scan, options, std::move(timings));
  measureInto(ctx, rec.tree, rec.voxelIou(), options, console);
  return reconstructionReport(rec, options.reconstruct, ctx);
}

}  // namespace csgvox
