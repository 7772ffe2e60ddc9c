#include "pipeline/reconstruct.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <stdexcept>

#include "core/nearest_neighbors.h"

namespace csgvox {
namespace {

using Clock = std::chrono::steady_clock;

std::string dimsText(const VoxelGrid& grid) {
  const auto& d = grid.dims();
  return std::to_string(d[0]) + " x " + std::to_string(d[1]) + " x " + std::to_string(d[2]);
}

// Times one stage, reports its start and end, and records its duration.
class StageClock {
 public:
  StageClock(Reconstruction& out, const StageCallback& onStage) : out_(out), onStage_(onStage) {}
  void start(std::string_view stage) {
    stage_ = stage;
    start_ = Clock::now();
    if (onStage_) onStage_(stage_, false, {});
  }
  void finish(const std::string& summary) {
    const double s = std::chrono::duration<double>(Clock::now() - start_).count();
    out_.timings.push_back({std::string(stage_), s});
    if (onStage_) onStage_(stage_, true, summary);
  }

 private:
  Reconstruction& out_;
  const StageCallback& onStage_;
  std::string_view stage_;
  Clock::time_point start_;
};

}  // namespace

double Reconstruction::voxelIou() const {
  const std::size_t either = VoxelSet::countOr(voxels, labels.inside);
  if (either == 0) return 1.0;
  return double(VoxelSet::countAnd(voxels, labels.inside)) / double(either);
}

std::string_view methodName(Method method) {
  switch (method) {
    case Method::Gp:
      return "gp";
    case Method::Imported:
      return "import-gp";
    case Method::Hybrid:
      return "hybrid";
    case Method::Voxel:
      break;
  }
  return "voxel";
}

Method methodFromName(std::string_view name) {
  if (name == "voxel") return Method::Voxel;
  if (name == "gp") return Method::Gp;
  if (name == "hybrid") return Method::Hybrid;
  throw std::invalid_argument("unknown method '" + std::string(name) + "' (hybrid, voxel or gp)");
}

namespace {

// The optimisations of Wu et al. on the labelled voxels.
void voxelMethod(Reconstruction& out, const PointCloud& scan, const ReconstructOptions& options,
                 StageClock& clock, Clock::time_point deadline,
                 const std::function<bool(double, std::string_view)>& report) {
  clock.start("description_sets");
  std::vector<CsgTree> candidates;
  candidates.reserve(out.hypotheses.candidates.size());
  for (const Candidate& c : out.hypotheses.candidates) candidates.push_back(c.tree);
  const std::vector<DescriptionSet> descriptions = describeAll(candidates, out.grid, out.labels);
  clock.finish(std::to_string(descriptions.size()) + " sets");

  clock.start("optimisation");
  ConstructOptions co = options.construct;
  co.seed = options.seed;
  if (co.snapDistance == 0.0) co.snapDistance = out.grid.voxelSize();
  // Scan points decide whether a sub-voxel skin is a real wall.
  const NearestNeighbors scanIndex(scan.points);
  const double nearScan = std::max(0.5 * out.grid.voxelSize(), 3.0 * out.detection.noise);
  if (!co.scannedAt) {
    co.scannedAt = [&](const Vec3& p) {
      double d2 = 0.0;
      scanIndex.nearest(p, &d2);
      return d2 <= nearScan * nearScan;
    };
  }
  co.subtree.deadline = std::min(co.subtree.deadline, deadline);
  co.unionChoice.deadline = std::min(co.unionChoice.deadline, deadline);
  out.construction = constructCsg(candidates, descriptions, out.labels.inside, co, report);
  out.timeLimitHit = out.timeLimitHit || Clock::now() > deadline;
  const ConstructStats& st = out.construction.stats;
  clock.finish(std::to_string(st.chosen) +
               (st.chosen == 1 ? " union member (" : " union members (") +
               std::to_string(st.selected) + " of " + std::to_string(st.unionCandidates) +
               " candidates selected" + (st.chosen != st.selected ? ", then refined" : "") +
               (st.provedOptimal ? ", proved optimal)" : ")"));
  out.tree = out.construction.tree;
  out.voxels = out.construction.voxels;
}

// The genetic-programming baseline on the points.
void gpMethod(Reconstruction& out, const PointCloud& scan, const ReconstructOptions& options,
              StageClock& clock, Clock::time_point deadline, const ProgressCallback& progress) {
  clock.start("evolve");
  GpOptions go = options.gp;
  go.evolve.seed = options.seed;
  if (deadline != Clock::time_point::max()) {
    const double left = std::chrono::duration<double>(deadline - Clock::now()).count();
    go.evolve.timeLimit = std::max(left, 1e-3);
  }
  VoxelTarget target;
  if (go.fitness.voxelWeight > 0.0) target = {out.grid, out.labels.inside};
  const std::size_t most = go.evolve.maxGenerations;
  out.gp = runGp(
      scan, out.detection.surfaces, go,
      [&](const GenerationReport& g) {
        if (progress) {
          char step[160];
          std::snprintf(step, sizeof(step), "generation %zu, best %.6g, %zu nodes, %.0f gen/s%s",
                        g.generation, g.bestFitness, g.bestNodes,
                        g.seconds > 0 ? double(g.generation) / g.seconds : 0.0,
                        g.rough ? " (rough)" : "");
          progress(most > 0 ? double(g.generation) / double(most) : 1.0, step);
        }
        return true;
      },
      go.fitness.voxelWeight > 0.0 ? &target : nullptr);
  out.timeLimitHit = out.timeLimitHit || out.gp.search.stop == EvolveStop::TimeLimit;
  const EvolveResult& s = out.gp.search;
  char summary[200];
  std::snprintf(summary, sizeof(summary),
                "%zu generations (%s), %zu trees evaluated, fitness %.6g, %zu primitives in the "
                "library (%zu separators)",
                s.generations, std::string(evolveStopName(s.stop)).c_str(), s.evaluations,
                s.fitness.total, out.gp.primitives.library.size(), out.gp.primitives.separators);
  std::string note = summary;
  if (out.gp.partitioned) {
    const PartitionedResult& p = *out.gp.partitioned;
    std::snprintf(summary, sizeof(summary),
                  "; %zu partitions searched in %.2f s, merged to %zu nodes, final search %.2f s",
                  p.partitions.size(), p.searchSeconds, p.mergedNodes, p.finalSeconds);
    note += summary;
  }
  clock.finish(note);
  out.tree = out.gp.tree;
  out.voxels = solidVoxels(out.tree, out.grid);
}

// The hybrid method's refinement of the voxel tree on the points.
void hybridMethod(Reconstruction& out, const PointCloud& scan, const ReconstructOptions& options,
                  StageClock& clock, Clock::time_point deadline) {
  clock.start("refine");
  HybridOptions ho = options.hybrid;
  ho.evolve.seed = options.seed;
  ho.noise = out.detection.noise;
  double left = 0.0;
  if (deadline != Clock::time_point::max()) {
    left = std::max(std::chrono::duration<double>(deadline - Clock::now()).count(), 1e-3);
  }
  out.voxelTree = out.tree;
  out.hybrid =
      refineTree(scan, out.tree, out.hypotheses.candidates, out.grid, out.labels.inside, ho, left);
  const HybridResult& h = out.hybrid;
  char summary[200];
  std::snprintf(summary, sizeof(summary),
                "%zu badly explained points, %zu regions, %zu subtrees replaced, fitness %.6g -> "
                "%.6g, primitives %zu -> %zu",
                h.badPoints, h.regions.size(), h.replaced, h.before.total, h.after.total,
                h.primitivesBefore, h.primitivesAfter);
  clock.finish(summary);
  out.tree = h.tree;
  if (options.finish.enabled && Clock::now() < deadline) {
    clock.start("finish");
    FinishOptions fo = options.finish;
    fo.fitness = ho.fitness;
    const VoxelTarget target{out.grid, out.labels.inside};
    out.finish = finishTree(scan, out.tree, &target, fo);
    const FinishResult& f = out.finish;
    std::snprintf(summary, sizeof(summary), "residual RMS %.4g -> %.4g, fitness %.6g -> %.6g, %s",
                  f.fit.rmsBefore, f.fit.rmsAfter, f.before.total, f.after.total,
                  f.accepted ? "accepted" : "input kept");
    clock.finish(summary);
    out.tree = f.tree;
  }
  out.voxels = solidVoxels(out.tree, out.grid);
}

Clock::time_point deadlineOf(double timeLimit) {
  return timeLimit > 0.0 ? Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                              std::chrono::duration<double>(timeLimit))
                         : Clock::time_point::max();
}

// Everything after detection, into `out` (which may hold timings already);
// `found` is taken over.
Reconstruction afterDetection(Reconstruction out, SurfacesAndCandidates found,
                              const PointCloud& scan, const ReconstructOptions& options,
                              const StageCallback& onStage, const ProgressCallback& progress,
                              Clock::time_point deadline) {
  StageClock clock(out, onStage);
  out.method = options.method;
  out.detection = std::move(found.detection);
  out.grid = std::move(found.grid);
  out.hypotheses = std::move(found.hypotheses);
  out.resolution = found.resolution;
  out.thin = std::move(found.thin);
  out.timeLimitHit = Clock::now() > deadline;
  if (options.method != Method::Gp && options.memoryLimit > 0) {
    const double need = voxelStageBytes(out.hypotheses.candidates.size(), out.grid.voxelCount());
    if (need > double(options.memoryLimit)) {
      // Voxel count grows with the cube of the resolution.
      const double fit = double(out.resolution) * std::cbrt(double(options.memoryLimit) / need);
      out.status = Reconstruction::Status::TooLarge;
      char buf[256];
      std::snprintf(buf, sizeof(buf),
                    "resolution %d needs about %.1f GiB for %zu candidates on %zu voxels, more "
                    "than the %.1f GiB allowed; use a resolution of at most %d",
                    out.resolution, need / double(1u << 30), out.hypotheses.candidates.size(),
                    out.grid.voxelCount(), double(options.memoryLimit) / double(1u << 30),
                    int(fit));
      out.message = buf;
      return out;
    }
  }

  clock.start("labels");
  LabelOptions lo = options.labels;
  lo.noise = out.detection.noise;
  out.labels = labelVoxels(out.grid, scan, lo);
  clock.finish("voxels " + dimsText(out.grid) + ", " + std::to_string(out.labels.inside.count()) +
               " inside (" + std::string(labelMethodName(options.labels.method)) + ")");

  const auto report = [&](double fraction, std::string_view step) {
    if (progress) progress(fraction, step);
    return true;
  };
  if (options.method == Method::Gp) {
    gpMethod(out, scan, options, clock, deadline, progress);
  } else {
    voxelMethod(out, scan, options, clock, deadline, report);
    if (options.method == Method::Hybrid && !out.tree.empty()) {
      hybridMethod(out, scan, options, clock, deadline);
    }
  }
  if (out.tree.empty()) {
    out.status = Reconstruction::Status::NoCombination;
    out.message = "no combination of the detected primitives explains the scan";
    return out;
  }
  out.status = Reconstruction::Status::Ok;
  out.message = std::to_string(out.tree.primitiveCount()) + " primitives, " +
                std::to_string(out.tree.operationCount()) + " operations, depth " +
                std::to_string(out.tree.depth());
  return out;
}

}  // namespace

Reconstruction reconstruct(const PointCloud& scan, const ReconstructOptions& options,
                           const StageCallback& onStage, const ProgressCallback& progress) {
  Reconstruction out;
  const Clock::time_point deadline = deadlineOf(options.timeLimit);
  const auto pastDeadline = [&] { return Clock::now() > deadline; };

  // Detection stops at the deadline. After it, a limit never costs the
  // tree: labels and description sets run to the end, and the optimisation
  // (or the search) stops at the deadline and keeps the best tree it has.
  DetectAndFitOptions fo;
  fo.resolution = options.resolution;
  fo.seed = options.seed;
  fo.detect = options.detect;
  fo.refineThin = options.refineThin && options.method != Method::Gp;
  fo.memoryLimit = options.memoryLimit;
  SurfacesAndCandidates found =
      detectAndFit(scan, fo, onStage, [&](double fraction, std::string_view step) {
        if (progress) progress(fraction, step);
        return !pastDeadline();
      });
  if (found.detection.status == DetectionResult::Status::Cancelled) {
    out.detection = std::move(found.detection);
    out.status = Reconstruction::Status::TimedOut;
    out.message = "time limit reached during detection";
    out.timeLimitHit = true;
    return out;
  }
  if (!found.ok()) {
    out.detection = std::move(found.detection);
    out.status = Reconstruction::Status::NoSurfaces;
    out.message = out.detection.message;
    return out;
  }
  out.timings.push_back(
      {"detect", found.detectSeconds + found.refineSeconds + found.regularizeSeconds});
  out.timings.push_back({"hypotheses", found.hypothesisSeconds});
  return afterDetection(std::move(out), std::move(found), scan, options, onStage, progress,
                        deadline);
}

Reconstruction reconstructDetected(const PointCloud& scan, const SurfacesAndCandidates& found,
                                   const ReconstructOptions& options, const StageCallback& onStage,
                                   const ProgressCallback& progress) {
  if (!found.ok()) throw std::invalid_argument("reconstructDetected: the detection found nothing");
  if (!scan.hasNormals())
    throw std::invalid_argument("reconstructDetected: the scan has no normals");
  return afterDetection(Reconstruction{}, found, scan, options, onStage, progress,
                        deadlineOf(options.timeLimit));
}

}  // namespace csgvox
