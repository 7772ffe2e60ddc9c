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
  const std::size_t either = VoxelSet::countOr(construction.voxels, labels.inside);
  if (either == 0) return 1.0;
  return double(VoxelSet::countAnd(construction.voxels, labels.inside)) / double(either);
}

Reconstruction reconstruct(const PointCloud& scan, const ReconstructOptions& options,
                           const StageCallback& onStage, const ProgressCallback& progress) {
  Reconstruction out;
  StageClock clock(out, onStage);
  const bool limited = options.timeLimit > 0.0;
  const Clock::time_point deadline =
      limited ? Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                   std::chrono::duration<double>(options.timeLimit))
              : Clock::time_point::max();
  const auto pastDeadline = [&] { return limited && Clock::now() > deadline; };
  const auto timedOut = [&](std::string_view stage) {
    out.status = Reconstruction::Status::TimedOut;
    out.message = "time limit reached during " + std::string(stage);
    out.timeLimitHit = true;
    return out;
  };

  // Detection stops at the deadline. After it, a limit never costs the
  // tree: labels and description sets run to the end, and the optimisation
  // stops searching at the deadline and keeps the best tree it has.
  DetectAndFitOptions fo;
  fo.resolution = options.resolution;
  fo.seed = options.seed;
  fo.detect = options.detect;
  const auto report = [&](double fraction, std::string_view step) {
    if (progress) progress(fraction, step);
    return true;
  };
  SurfacesAndCandidates found =
      detectAndFit(scan, fo, onStage, [&](double fraction, std::string_view step) {
        report(fraction, step);
        return !pastDeadline();
      });
  out.detection = std::move(found.detection);
  if (out.detection.status == DetectionResult::Status::Cancelled) return timedOut("detection");
  if (!out.detection.ok()) {
    out.status = Reconstruction::Status::NoSurfaces;
    out.message = out.detection.message;
    return out;
  }
  out.timings.push_back(
      {"detect", found.detectSeconds + found.refineSeconds + found.regularizeSeconds});
  out.timings.push_back({"hypotheses", found.hypothesisSeconds});
  out.grid = std::move(found.grid);
  out.hypotheses = std::move(found.hypotheses);
  out.timeLimitHit = pastDeadline();
  if (options.memoryLimit > 0) {
    const double perVoxel =
        3.0 * double(std::max<std::size_t>(out.hypotheses.candidates.size(), 1)) / 8.0;
    const double need = perVoxel * double(out.grid.voxelCount());
    if (need > double(options.memoryLimit)) {
      // Voxel count grows with the cube of the resolution.
      const double fit = double(options.resolution) * std::cbrt(double(options.memoryLimit) / need);
      out.status = Reconstruction::Status::TooLarge;
      char buf[256];
      std::snprintf(buf, sizeof(buf),
                    "resolution %d needs about %.1f GiB for %zu candidates on %zu voxels, more "
                    "than the %.1f GiB allowed; use a resolution of at most %d",
                    options.resolution, need / double(1u << 30), out.hypotheses.candidates.size(),
                    out.grid.voxelCount(), double(options.memoryLimit) / double(1u << 30),
                    int(fit));
      out.message = buf;
      return out;
    }
  }

  clock.start("labels");
  out.labels = labelVoxels(out.grid, scan, options.labels);
  clock.finish("voxels " + dimsText(out.grid) + ", " + std::to_string(out.labels.inside.count()) +
               " inside (" + std::string(labelMethodName(options.labels.method)) + ")");

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
  out.timeLimitHit = out.timeLimitHit || pastDeadline();
  const ConstructStats& st = out.construction.stats;
  clock.finish(std::to_string(st.chosen) + " of " + std::to_string(st.unionCandidates) +
               " union candidates" + (st.provedOptimal ? ", proved optimal" : ""));
  if (out.construction.tree.empty()) {
    out.status = Reconstruction::Status::NoCombination;
    out.message = "no combination of the detected primitives explains the scan";
    return out;
  }
  out.tree = out.construction.tree;
  out.status = Reconstruction::Status::Ok;
  out.message = std::to_string(out.tree.primitiveCount()) + " primitives, " +
                std::to_string(out.tree.operationCount()) + " operations, depth " +
                std::to_string(out.tree.depth());
  return out;
}

}  // namespace csgvox
