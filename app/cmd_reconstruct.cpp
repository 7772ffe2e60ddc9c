// The main job: csgvox SCAN [MORE_SCANS...] [--res N] [-o OUTDIR] ...
// scan → surfaces → hypotheses → voxel labels → Wu's two optimisations →
// tree.json, tree.scad, tree.txt, mesh.ply, report.json.

#include <cstdio>
#include <filesystem>
#include <optional>

#include "app/commands.h"
#include "app/job_options.h"
#include "app/options.h"
#include "io/errors.h"
#include "io/mesh_files.h"
#include "io/output_set.h"
#include "io/report.h"
#include "io/scad_export.h"
#include "io/scan_reader.h"
#include "io/text_export.h"
#include "io/tree_json.h"
#include "job/console.h"
#include "mesh/fit_metrics.h"
#include "mesh/mesh_export.h"
#include "pipeline/reconstruct.h"

namespace csgvox::app {

namespace fs = std::filesystem;

Command setupReconstruct(CLI::App& app, CommonOptions& common) {
  auto opt = std::make_shared<ScanJobOptions>();
  // Show every default in --help.
  app.option_defaults()->always_capture_default();
  app.add_option("SCAN", opt->scan,
                 "Scan to reconstruct: PLY, XYZ, XYZN point cloud, or OFF/OBJ/STL/PLY mesh")
      ->required();
  app.add_option("MORE_SCANS", opt->moreScans,
                 "Further point clouds of the same part in the same frame (a scanner's exports "
                 "of its views or setups), read together with SCAN as one scan");
  app.add_option("-o,--output", opt->outDir,
                 "Output directory (default: <scan folder>/<scan name>-csgvox/)");
  addJobOptions(app, opt->job);
  return [opt, &common]() -> int {
    Console console(common.quiet);
    common.subject = opt->scan;
    const fs::path scanPath(opt->scan);
    StepTimes timings;
    Stopwatch watch;
    ReadOptions ro;
    ro.seed = opt->job.reconstruct.seed;
    std::vector<fs::path> inputs = {scanPath};
    for (const std::string& more : opt->moreScans) inputs.emplace_back(more);
    const Scan scan = readScans(inputs, ro);
    timings.add("read", watch.seconds(), watch.cpuSeconds());
    console.info("read " + scanPath.string() +
                 (inputs.size() > 1 ? " and " + std::to_string(inputs.size() - 1) + " more" : "") +
                 ": " + describeScan(scan));
    // Outputs are checked against the input before the reconstruction, and
    // appear together at the end or not at all.
    OutputSet output(opt->outDir.empty()
                         ? scanPath.parent_path() / (scanPath.stem().string() + "-csgvox")
                         : fs::path(opt->outDir),
                     jobFiles(), inputs);

    opt->job.reconstruct.detect.estimatedNormals = scan.info.normalsEstimated;
    const RunControl control(opt->job.timeLimit, console.progress());
    const Reconstruction rec = reconstruct(
        scan.cloud, opt->job.reconstruct,
        [&](std::string_view stage, bool done, const std::string& summary) {
          if (done) console.info(std::string(stage) + ": " + summary);
        },
        control);
    for (const StageTime& t : rec.timings) timings.add(t.stage, t.seconds, t.cpuSeconds);
    if (!rec.ok()) throw ParseError(scanPath.string() + ": " + rec.message);
    if (rec.timeLimitHit) {
      console.info(rec.method == Method::Gp
                       ? "time limit reached: the search kept its best tree so far"
                       : "time limit reached: the optimisation kept its best solution so far");
    }
    const CsgTree& tree = rec.tree;
    console.info("tree: " + std::to_string(tree.primitiveCount()) + " primitives, " +
                 std::to_string(tree.operationCount()) + " operations, depth " +
                 std::to_string(tree.depth()));
    const nlohmann::ordered_json report =
        writeJob(output, scanPath, scan, rec, opt->job, timings, console, control);
    output.commit();
    std::string written;
    for (const auto& name : report["outputs"])
      written += (written.empty() ? "" : ", ") + name.get<std::string>();
    console.info("wrote " + written + " in " + output.folder().string());
    return 0;
  };
}

}  // namespace csgvox::app
