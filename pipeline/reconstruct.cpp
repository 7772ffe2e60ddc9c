#include "primitives/bounding_box.h"
#include "pipeline/reconstruct.h"

#include "core/nearest_neighbors.h"
#include "primitives/regularization.h"
#include "primitives/surface_refinement.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <stdexcept>

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
  StageClock(Reconstruction& out, const StageCallback& onStage)
      : out_(out), onStage_(onStage) {}
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

// The frame of the voxel grid. Voxels aligned with the part's faces see
// them without staircase aliasing, but the minimal oriented box of a noisy
// scan comes out tilted by a fraction of a degree (its volume is flat near
// the minimum), and an L-shaped part's can even turn diagonal. So the frame
// comes from the detected surfaces: the direction (plane normal or axis)
// with most inliers, then the heaviest direction orthogonal to it within
// two degrees. The minimal box is kept when no surface gives a direction or
// when the aligned box is more than a quarter larger.
OrientedBox gridBox(const PointCloud& scan, std::span<const Surface> surfaces) {
  const OrientedBox minimal = minimalOrientedBox(scan.points);
  struct Direction {
    Vec3 dir;
    double weight;
  };
  std::vector<Direction> dirs;
  const double cosParallel = std::cos(2.0 * std::numbers::pi / 180.0);
  for (const Surface& s : surfaces) {
    Vec3 d;
    if (const auto* p = s.as<PlaneSurface>()) {
      d = p->normal;
    } else if (const auto* c = s.as<CylinderSurface>()) {
      d = c->axisDir;
    } else if (const auto* c = s.as<ConeSurface>()) {
      d = c->axisDir;
    } else if (const auto* t = s.as<TorusSurface>()) {
      d = t->axisDir;
    } else {
      continue;
    }
    if (!(d.norm() > 0.0)) continue;
    d.normalize();
    const double w = double(s.inliers.size());
    auto same = std::find_if(dirs.begin(), dirs.end(), [&](const Direction& o) {
      return std::abs(o.dir.dot(d)) >= cosParallel;
    });
    if (same != dirs.end()) {
      same->weight += w;
    } else {
      dirs.push_back({d, w});
    }
  }
  if (dirs.empty()) return minimal;
  std::stable_sort(dirs.begin(), dirs.end(),
                   [](const Direction& a, const Direction& b) { return a.weight > b.weight; });
  const Vec3 a1 = dirs.front().dir;
  const double sinOrthogonal = std::sin(2.0 * std::numbers::pi / 180.0);
  Vec3 a2 = Vec3::Zero();
  for (const Direction& d : dirs) {
    if (std::abs(d.dir.dot(a1)) <= sinOrthogonal) {
      a2 = d.dir;
      break;
    }
  }
  if (a2 == Vec3::Zero()) {
    // Only one direction: the minimal box's axis most orthogonal to it.
    double best = 2.0;
    for (int k = 0; k < 3; ++k) {
      const double c = std::abs(minimal.axes.col(k).dot(a1));
      if (c < best) best = c, a2 = minimal.axes.col(k);
    }
  }
  a2 = (a2 - a2.dot(a1) * a1).normalized();
  Mat3 frame;
  frame.col(0) = a1;
  frame.col(1) = a2;
  frame.col(2) = a1.cross(a2);
  const OrientedBox aligned = boxAlong(scan.points, frame);
  const double volume = aligned.halfSize.prod(), minimalVolume = minimal.halfSize.prod();
  return volume <= 1.25 * minimalVolume ? aligned : minimal;
}

double Reconstruction::voxelIou() const {
  const std::size_t either = VoxelSet::countOr(construction.voxels, labels.inside);
  if (either == 0) return 1.0;
  return double(VoxelSet::countAnd(construction.voxels, labels.inside)) / double(either);
}

Reconstruction reconstruct(const PointCloud& scan, const ReconstructOptions& options,
                           const StageCallback& onStage, const ProgressCallback& progress) {
  if (scan.empty()) throw std::invalid_argument("the scan has no points");
  if (!scan.hasNormals()) throw std::invalid_argument("the scan has no normals");
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

  clock.start("detect");
  DetectOptions dopt = options.detect;
  dopt.seed = options.seed;
  // Detection stops at the deadline; the optimisation handles the deadline
  // inside its solvers and keeps going with local search only.
  const auto report = [&](double fraction, std::string_view step) {
    if (progress) progress(fraction, step);
    return true;
  };
  out.detection = detectSurfaces(scan, dopt, [&](double fraction, std::string_view step) {
    report(fraction, step);
    return !pastDeadline();
  });
  if (out.detection.status == DetectionResult::Status::Cancelled) return timedOut("detection");
  if (!out.detection.ok()) {
    out.status = Reconstruction::Status::NoSurfaces;
    out.message = out.detection.message;
    return out;
  }
  refineSurfaces(scan, out.detection);
  regularizeSurfaces(out.detection);
  clock.finish(out.detection.message);
  if (pastDeadline()) return timedOut("detection");

  clock.start("hypotheses");
  GridOptions go;
  go.resolution = options.resolution;
  out.grid = VoxelGrid::around(gridBox(scan, out.detection.surfaces), go);
  HypothesisOptions ho;
  ho.voxelSize = out.grid.voxelSize();
  ho.seed = std::uint32_t(options.seed);
  out.hypotheses = generateHypotheses(scan, out.detection.surfaces, ho);
  clock.finish(std::to_string(out.hypotheses.candidates.size()) + " candidates");
  if (pastDeadline()) return timedOut("hypotheses");
  if (options.memoryLimit > 0) {
    const double perVoxel = 3.0 * double(std::max<std::size_t>(out.hypotheses.candidates.size(), 1)) / 8.0;
    const double need = perVoxel * double(out.grid.voxelCount());
    if (need > double(options.memoryLimit)) {
      // Voxel count grows with the cube of the resolution.
      const double fit = double(options.resolution) *
                         std::cbrt(double(options.memoryLimit) / need);
      out.status = Reconstruction::Status::TooLarge;
      char buf[256];
      std::snprintf(buf, sizeof(buf),
                    "resolution %d needs about %.1f GiB for %zu candidates on %zu voxels, more "
                    "than the %.1f GiB allowed; use a resolution of at most %d",
                    options.resolution, need / double(1u << 30),
                    out.hypotheses.candidates.size(), out.grid.voxelCount(),
                    double(options.memoryLimit) / double(1u << 30), int(fit));
      out.message = buf;
      return out;
    }
  }

  clock.start("labels");
  out.labels = labelVoxels(out.grid, scan, options.labels);
  clock.finish("voxels " + dimsText(out.grid) + ", " + std::to_string(out.labels.inside.count()) +
               " inside (" + std::string(labelMethodName(options.labels.method)) + ")");
  if (pastDeadline()) return timedOut("labelling");

  clock.start("description_sets");
  std::vector<CsgTree> candidates;
  candidates.reserve(out.hypotheses.candidates.size());
  for (const Candidate& c : out.hypotheses.candidates) candidates.push_back(c.tree);
  const std::vector<DescriptionSet> descriptions = describeAll(candidates, out.grid, out.labels);
  clock.finish(std::to_string(descriptions.size()) + " sets");
  if (pastDeadline()) return timedOut("description sets");

  clock.start("optimisation");
  ConstructOptions co = options.construct;
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
  out.timeLimitHit = pastDeadline();
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
