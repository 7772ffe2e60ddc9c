#include "job/job.h"

#include <pthread.h>
#include <tbb/task_arena.h>
#include <tbb/task_group.h>
#include <time.h>

#include <algorithm>
#include <cstdio>
#include <mutex>
#include <optional>

#include "cad/step_export.h"
#include "design/designed_tree.h"
#include "io/csg_writer.h"
#include "io/design_json.h"
#include "io/design_scad.h"
#include "io/freecad_macro.h"
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
  static const std::vector<std::string> files = {
      "tree.json", "tree.scad",   "tree.txt", "tree.csg",   "tree.step",
      "tree.FCMacro", "preview.png", "mesh.ply", "report.json"};
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
  return treeFitness(tree, scan.cloud.points, scan.cloud.normals, scan.cloud.diagonal(), fo);
}

// What writing tree.step came to: written or not, the warnings to report
// (and the error line to print when it was not written), its seconds.
struct StepOutcome {
  bool written = false;
  nlohmann::ordered_json warnings = nlohmann::ordered_json::array();
  std::string error;  ///< non-empty: tree.step is not written, for this reason
  double seconds = 0.0, cpuSeconds = 0.0;
};

// tree.step. The tree is the result: a solid OpenCASCADE cannot build is
// tried from the fitted tree when `tree` is the designed one, and then costs
// tree.step only (one error line naming the node, a warning in the report),
// not the job.
StepOutcome writeStepFile(const std::filesystem::path& path, const CsgTree& tree,
                          const CsgTree* fitted, const RunControl& control) {
  StepOutcome out;
  StepOptions so;
  so.control = control;
  try {
    writeStep(path, tree, so);
    out.written = true;
  } catch (const CadError& e) {
    // OpenCASCADE fails on some exact coincidences the designed values
    // make; the fitted tree (the same solid within its IoU) may pass.
    if (fitted && !fitted->empty()) {
      try {
        writeStep(path, *fitted, so);
        out.written = true;
        out.warnings.push_back(std::string("tree.step: written from the fitted values: the "
                                           "designed tree's solid failed: ") +
                               e.what());
      } catch (const CadError&) {
      }
    }
    if (!out.written) {
      out.error = e.what();
      out.warnings.push_back(std::string("tree.step: not written: ") + e.what());
    }
  }
  return out;
}

// The CPU seconds of one thread's work so far, read from any thread: the
// work's thread reads its clock while it runs; its total once done.
class ThreadWorkCpu {
 public:
  void begin() {
    const std::lock_guard<std::mutex> lock(mutex_);
    running_ = pthread_getcpuclockid(pthread_self(), &clock_) == 0;
    start_ = running_ ? read(clock_) : 0.0;
  }
  void end() {
    const std::lock_guard<std::mutex> lock(mutex_);
    if (running_) total_ = read(clock_) - start_;
    running_ = false;
  }
  double seconds() const {
    const std::lock_guard<std::mutex> lock(mutex_);
    return running_ ? read(clock_) - start_ : total_;
  }

 private:
  static double read(clockid_t clock) {
    timespec t{};
    clock_gettime(clock, &t);
    return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
  }
  mutable std::mutex mutex_;
  clockid_t clock_{};
  double start_ = 0.0, total_ = 0.0;
  bool running_ = false;
};

// tree.step built on a task of its own (OpenCASCADE works on one thread)
// while the calling thread writes the other files, meshes, draws the preview
// and measures the tree: with two threads or more its seconds leave the
// job's critical path; with one the task runs at wait(). The stages of the
// calling thread run isolated (stage()), so that thread never takes the task
// up inside one of them, and their CPU seconds leave out the task's
// (BesideStopwatch).
class StepTask {
 public:
  StepTask(std::filesystem::path path, const CsgTree& tree, const CsgTree* fitted,
           const RunControl& control) {
    group_.run([this, path = std::move(path), &tree, fitted, &control] {
      const Stopwatch watch;
      cpu_.begin();
      const struct End {
        ThreadWorkCpu& cpu;
        ~End() { cpu.end(); }  // also when writeStep throws
      } end{cpu_};
      outcome_ = writeStepFile(path, tree, fitted, control);
      outcome_.seconds = watch.seconds();
    });
  }
  StepTask(const StepTask&) = delete;
  StepTask& operator=(const StepTask&) = delete;
  // On the way out of a failed stage: the task still ends before its tree.
  ~StepTask() {
    try {
      group_.wait();
    } catch (...) {
    }
  }

  /// Runs `body` on the calling thread, isolated from the task.
  template <class Body>
  void stage(const Body& body) {
    tbb::this_task_arena::isolate(body);
  }
  /// The CPU seconds of the task so far.
  double taskCpu() const { return cpu_.seconds(); }

  /// The outcome, once the task has ended (its exception rethrown).
  StepOutcome wait() {
    group_.wait();
    StepOutcome out = outcome_;
    out.cpuSeconds = cpu_.seconds();
    return out;
  }

 private:
  tbb::task_group group_;
  ThreadWorkCpu cpu_;
  StepOutcome outcome_;
};

// Wall-clock and CPU seconds of a stage that runs beside a StepTask: the
// process's CPU seconds less the task's over the stage.
class BesideStopwatch {
 public:
  explicit BesideStopwatch(const StepTask* beside)
      : beside_(beside), besideStart_(beside ? beside->taskCpu() : 0.0) {}
  double seconds() const { return watch_.seconds(); }
  double cpuSeconds() const {
    const double own = watch_.cpuSeconds();
    return beside_ ? std::max(0.0, own - (beside_->taskCpu() - besideStart_)) : own;
  }

 private:
  const StepTask* beside_;
  double besideStart_;
  Stopwatch watch_;
};

// Every file of the job but tree.step and report.json; `ctx` gains the
// export and preview timings. With a design, tree.json, tree.scad and
// tree.txt are its parametric forms and `tree` is its world tree. tree.step
// is written beside it (`beside`; null when this build cannot write it).
void writeTreeFiles(OutputSet& output, const Scan& scan, const CsgTree& tree,
                    const DesignedTree* design, const JobOptions& options, ReportContext& ctx,
                    const RunControl& control, const StepTask* beside) {
  BesideStopwatch watch(beside);
  if (design) {
    writeDesignedTreeJson(output.path("tree.json"), *design);
    writeDesignedScad(output.path("tree.scad"), *design);
    writeTreeText(output.path("tree.txt"), *design);
    writeFreecadMacro(output.path("tree.FCMacro"), *design);
  } else {
    output.skip("tree.FCMacro");
    writeTreeJson(output.path("tree.json"), tree);
    writeScad(output.path("tree.scad"), tree);
    writeTreeText(output.path("tree.txt"), tree);
  }
  writeCsg(output.path("tree.csg"), tree);
  MeshOptions mo;
  mo.resolution = options.meshResolution;
  const TriangleMesh mesh = meshTree(tree, mo, control);
  writeMesh(output.path("mesh.ply"), mesh);
  ctx.timings.add("export", watch.seconds(), watch.cpuSeconds());
  ctx.timings.add("step", 0.0, 0.0);  // its place in the report; its seconds come with it
  if (!options.preview) {
    output.skip("preview.png");
    return;
  }
  const BesideStopwatch previewWatch(beside);
  writePng(output.path("preview.png"), renderPreview(tree, mesh, &scan.cloud).image);
  ctx.timings.add("preview", previewWatch.seconds(), previewWatch.cpuSeconds());
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
                        const JobOptions& options, StepTimes timings) {
  ReportContext ctx;
  ctx.scanPath = scanPath;
  ctx.scan = &scan;
  ctx.timeLimit = options.timeLimit;
  ctx.timings = std::move(timings);
  return ctx;
}

// Measures the tree into ctx (with the metrics' seconds) and prints the fit line.
void measureInto(ReportContext& ctx, const CsgTree& tree, double voxelIou,
                 const JobOptions& options, const Console& console,
                 const StepTask* beside = nullptr) {
  BesideStopwatch watch(beside);
  ctx.metrics = measureTree(tree, *ctx.scan, voxelIou, options, ctx.warnings, console);
  ctx.timings.add("metrics", watch.seconds(), watch.cpuSeconds());
  if (const auto& fit = ctx.metrics.fit) {
    console.info(fmt("fit: Chamfer %.3g %% of D, RMSE %.3g %% of D",
                     100 * fit->chamfer / fit->diagonal, 100 * fit->rmse / fit->diagonal));
  }
}

// The designed form of the fitted tree (none with raw values, or when it
// cannot be built: a warning then, and the fitted tree is written).
std::optional<DesignedTree> designFor(const CsgTree& fitted, const Scan& scan,
                                      const JobOptions& options, ReportContext& ctx,
                                      const Console& console) {
  if (options.rawValues) return std::nullopt;
  try {
    return designTree(fitted, scan.cloud.points);
  } catch (const std::exception& e) {
    ctx.warnings.push_back(std::string("design: not built, the fitted values are written: ") +
                           e.what());
    console.info(std::string("warning: designed values not computed: ") + e.what());
    return std::nullopt;
  }
}

// Every file of the job, the tree measured, then report.json as `build`
// shapes it from the context; returns the report. The files hold the
// designed tree unless options.rawValues.
template <class BuildReport>
nlohmann::ordered_json writeFilesAndReport(OutputSet& output, ReportContext ctx,
                                           const CsgTree& fitted, double voxelIou,
                                           const JobOptions& options, const Console& console,
                                           const RunControl& control, const BuildReport& build) {
  Stopwatch watch;
  const std::optional<DesignedTree> design = designFor(fitted, *ctx.scan, options, ctx, console);
  const double designSeconds = watch.seconds(), designCpuSeconds = watch.cpuSeconds();
  const CsgTree tree = design ? design->tree() : fitted;
  if (design) {
    ctx.timings.add("design", designSeconds, designCpuSeconds);
    console.info(fmt("design: %.0f parameters, %.0f snapped", double(design->parameters.size()),
                     double(design->snappedCount())));
  }
  std::optional<StepTask> step;
  if (stepExportAvailable()) {
    step.emplace(output.path("tree.step"), tree, design ? &design->fitted : nullptr, control);
  } else {
    output.skip("tree.step");
    ctx.warnings.push_back("tree.step: not written: this build has no OpenCASCADE");
  }
  const StepTask* beside = step ? &*step : nullptr;
  std::size_t stepWarningsAt = 0;
  const auto stages = [&] {
    writeTreeFiles(output, *ctx.scan, tree, design ? &*design : nullptr, options, ctx, control,
                   beside);
    stepWarningsAt = ctx.warnings.size();
    measureInto(ctx, tree, voxelIou, options, console, beside);
  };
  if (step) {
    step->stage(stages);
    const StepOutcome done = step->wait();
    ctx.timings.add("step", done.seconds, done.cpuSeconds);
    for (std::size_t k = 0; k < done.warnings.size(); ++k) {
      ctx.warnings.insert(ctx.warnings.begin() + std::ptrdiff_t(stepWarningsAt + k),
                          done.warnings[k]);
    }
    if (!done.written) {
      output.skip("tree.step");
      std::fprintf(stderr, "csgvox: error: tree.step not written: %s\n", done.error.c_str());
    }
  } else {
    stages();
  }
  ctx.outputs = writtenFiles(output);
  nlohmann::ordered_json report = build(ctx);
  if (design) report["design"] = designReportJson(*design, designSeconds);
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
                                const JobOptions& options, StepTimes timings,
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
      output, contextOf(scanPath, scan, options, StepTimes{}), *imported.tree,
      voxelIou, options, console, control, [&](const ReportContext& ctx) {
        return importedTreeReport(imported, options.reconstruct, ctx);
      });
}

nlohmann::ordered_json reportWithoutFiles(const std::filesystem::path& scanPath, const Scan& scan,
                                          const Reconstruction& rec, const JobOptions& options,
                                          StepTimes timings, const Console& console) {
  ReportContext ctx = contextOf(scanPath, scan, options, std::move(timings));
  measureInto(ctx, rec.tree, rec.voxelIou(), options, console);
  return reconstructionReport(rec, options.reconstruct, ctx);
}

}  // namespace csgvox
