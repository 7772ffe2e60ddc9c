// csgvox compare SCAN [--methods voxel,hybrid,gp] [--import-gp FIT EXPR] [-o DIR]:
// several methods on one detection, side by side.

#include <cstdio>
#include <ctime>
#include <filesystem>
#include <sstream>

#include "app/commands.h"
#include "app/job_options.h"
#include "app/options.h"
#include "io/errors.h"
#include "io/gp_files.h"
#include "io/report.h"
#include "job/console.h"
#include "pipeline/detect_and_fit.h"
#include "voxel/labeling.h"

namespace csgvox::app {

namespace fs = std::filesystem;

namespace {

struct CommandOptions : ScanJobOptions {
  std::string methods = "voxel,hybrid,gp";
  std::vector<std::string> importGp;  // FIT EXPR
};

std::vector<std::string> splitMethods(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream in(text);
  for (std::string name; std::getline(in, name, ',');) {
    if (name.empty()) continue;
    methodFromName(name);  // throws for an unknown name
    out.push_back(name);
  }
  if (out.empty()) throw std::invalid_argument("--methods names no method");
  return out;
}

double cpuSeconds() { return double(std::clock()) / CLOCKS_PER_SEC; }

// One row of the comparison from a job's report.
nlohmann::ordered_json row(const std::string& name, double wall, double cpu,
                           const nlohmann::ordered_json& report) {
  const auto& m = report["metrics"];
  const auto& t = report["tree"];
  nlohmann::ordered_json r = {{"method", name},
                              {"wall_s", wall},
                              {"cpu_s", cpu},
                              {"primitives", t["primitives"]},
                              {"operations", t["operations"]},
                              {"depth", t["depth"]},
                              {"voxel_iou", m["voxel_iou"]},
                              {"fitness", m["fitness"]["total"]}};
  r["chamfer_relative"] = m.contains("chamfer_relative") ? m["chamfer_relative"] : nullptr;
  r["rmse_relative"] = m.contains("rmse_relative") ? m["rmse_relative"] : nullptr;
  return r;
}

std::string percent(const nlohmann::ordered_json& v) {
  if (v.is_null()) return "-";
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.3f", 100.0 * v.get<double>());
  return buf;
}

void printTable(const nlohmann::ordered_json& rows) {
  std::printf("%-10s %8s %8s %6s %5s %6s %10s %9s %9s %12s\n", "method", "wall s", "CPU s", "prims",
              "ops", "depth", "Chamfer%D", "RMSE%D", "voxelIoU", "fitness");
  for (const auto& r : rows) {
    std::printf("%-10s %8.2f %8.2f %6d %5d %6d %10s %9s %9.4f %12.1f\n",
                r["method"].get<std::string>().c_str(), r["wall_s"].get<double>(),
                r["cpu_s"].get<double>(), r["primitives"].get<int>(), r["operations"].get<int>(),
                r["depth"].get<int>(), percent(r["chamfer_relative"]).c_str(),
                percent(r["rmse_relative"]).c_str(), r["voxel_iou"].get<double>(),
                r["fitness"].get<double>());
  }
  std::fflush(stdout);
}

}  // namespace

Command setupCompare(CLI::App& app, CommonOptions& common) {
  auto opt = std::make_shared<CommandOptions>();
  app.option_defaults()->always_capture_default();
  app.add_option("SCAN", opt->scan, "Scan to reconstruct with each method")->required();
  app.add_option("-o,--output", opt->outDir,
                 "Output directory: compare.json and one folder of outputs per method (default: "
                 "<scan folder>/<scan name>-compare/)");
  app.add_option("--methods", opt->methods, "Methods to run, comma separated: voxel, hybrid, gp");
  app.add_option("--import-gp", opt->importGp,
                 "Add the published GP code's own result as a row: its .fit primitive file and "
                 "its expression file (see csgvox import-gp --help)")
      ->expected(2);
  addJobOptions(app, opt->job);
  app.footer(
      "Every method runs on the same detected surfaces (detection is timed once, apart). Each "
      "row: wall and CPU seconds of the method, tree size, Chamfer and RMSE against the scan "
      "in % of its diagonal, voxel IoU against the voxel labels, and Eq. 7's fitness on every "
      "point (min/max, the gp tolerances).");
  return [opt, &common]() -> int {
    Console console(common.quiet);
    common.subject = opt->scan;
    const std::vector<std::string> methods = splitMethods(opt->methods);
    const fs::path scanPath(opt->scan);
    ReadOptions ro;
    ro.seed = opt->job.reconstruct.seed;
    const Scan scan = readScan(scanPath, ro);
    console.info("read " + scanPath.string() + ": " + describeScan(scan));
    const fs::path folder = opt->outDir.empty()
                                ? scanPath.parent_path() / (scanPath.stem().string() + "-compare")
                                : fs::path(opt->outDir);
    const fs::path inputs[] = {scanPath};
    // The folder holds one output set per method and compare.json: each set
    // appears whole or not at all.
    std::error_code ec;
    if (!fs::is_directory(folder) && !fs::create_directories(folder, ec)) {
      throw IoError(folder.string() + ": cannot create the output folder" +
                    (ec ? ": " + ec.message() : ""));
    }
    OutputSet summary(folder, {"compare.json"}, inputs);

    const ReconstructOptions& base = opt->job.reconstruct;
    Stopwatch watch;
    DetectAndFitOptions fo;
    fo.resolution = base.resolution;
    fo.seed = base.seed;
    fo.detect = base.detect;
    fo.detect.estimatedNormals = scan.info.normalsEstimated;
    fo.finerGrid = base.finerGrid;
    fo.memoryLimit = base.memoryLimit;
    const SurfacesAndCandidates found = detectAndFit(scan.cloud, fo, {}, console.progress());
    if (!found.ok()) throw ParseError(scanPath.string() + ": " + found.detection.message);
    const double detectSeconds = watch.seconds();
    StepTimes detectTimes;
    detectTimes.add("detect", detectSeconds, watch.cpuSeconds());
    console.info("detection: " + std::to_string(found.detection.surfaces.size()) + " surfaces, " +
                 std::to_string(found.hypotheses.candidates.size()) + " candidates");

    nlohmann::ordered_json rows = nlohmann::ordered_json::array();
    VoxelLabels labels;
    for (const std::string& name : methods) {
      JobOptions settings = opt->job;
      settings.reconstruct.method = methodFromName(name);
      const ReconstructOptions& options = settings.reconstruct;
      console.info("method " + name);
      const Stopwatch wall;
      const double cpu0 = cpuSeconds();
      const Reconstruction rec = reconstructDetected(
          scan.cloud, found, options,
          [&](std::string_view stage, bool done, const std::string& text) {
            if (done) console.info("  " + std::string(stage) + ": " + text);
          },
          RunControl(settings.timeLimit, console.progress()));
      const double wallSeconds = wall.seconds(), cpu = cpuSeconds() - cpu0;
      if (!rec.ok()) throw ParseError(scanPath.string() + ": " + name + ": " + rec.message);
      labels = rec.labels;
      OutputSet output(folder / name, jobFiles(), inputs);
      const nlohmann::ordered_json report =
          writeJob(output, scanPath, scan, rec, settings, detectTimes, console,
                   RunControl(0.0, console.progress()));
      output.commit();
      rows.push_back(row(name, wallSeconds, cpu, report));
    }
    if (!opt->importGp.empty()) {
      GpImportOptions io;
      io.box = gpScanClipBox(scan.cloud.bounds());
      const CsgTree tree = importGp(opt->importGp[0], opt->importGp[1], io).tree;
      LabelOptions lo = base.labels;
      lo.noise = found.detection.noise;
      if (methods.empty()) labels = labelVoxels(found.grid, scan.cloud, lo);
      const VoxelSet voxels = solidVoxels(tree, found.grid);
      const double voxelIou = VoxelSet::iou(voxels, labels.inside);
      ImportedTree imported;
      imported.tree = &tree;
      imported.grid = &found.grid;
      imported.resolution = found.resolution;
      imported.surfaces = found.detection.surfaces.size();
      OutputSet output(folder / "import-gp", jobFiles(), inputs);
      const nlohmann::ordered_json report =
          writeImportedJob(output, scanPath, scan, imported, voxelIou, opt->job, console,
                           RunControl(0.0, console.progress()));
      output.commit();
      rows.push_back(row("import-gp", 0.0, 0.0, report));
    }
    nlohmann::ordered_json out;
    out["input"] = scanJson(scanPath, scan);
    out["detection"] = {{"surfaces", found.detection.surfaces.size()},
                        {"candidates", found.hypotheses.candidates.size()},
                        {"seconds", detectSeconds}};
    out["rows"] = rows;
    writeJsonFile(summary.path("compare.json"), out);
    summary.commit();
    printTable(rows);
    console.info("wrote compare.json and one folder per method in " + folder.string());
    return 0;
  };
}

}  // namespace csgvox::app
