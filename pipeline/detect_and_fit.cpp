#include "pipeline/detect_and_fit.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string>

#include "core/cpu_time.h"
#include "primitives/bounding_box.h"
#include "primitives/surface_fit.h"

namespace csgvox {
namespace {

// Points of the subset on which a scan is checked for scattered points.
constexpr std::size_t kScatterPoints = 2000;

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

}  // namespace

// The frame of the voxel grid. Voxels aligned with the part's faces see
// them without staircase aliasing, but the minimal oriented box of a noisy
// scan comes out tilted by a fraction of a degree (its volume is flat near
// the minimum), and an L-shaped part's can even turn diagonal. So the frame
// comes from the detected surfaces: the direction (plane normal or axis)
// with most inliers, then the heaviest direction orthogonal to it within
// two degrees. The minimal box is kept when no surface gives a direction or
// when the aligned box is more than a quarter larger.
OrientedBox gridBox(const PointCloud& scan, std::span<const Surface> surfaces, std::uint64_t seed) {
  const OrientedBox minimal = minimalOrientedBox(scan.points, {std::uint32_t(seed)});
  struct Direction {
    Vec3 dir;
    double weight;
  };
  std::vector<Direction> dirs;
  const double cosParallel = std::cos(2.0 * std::numbers::pi / 180.0);
  for (const Surface& s : surfaces) {
    const std::optional<Vec3> direction = surfaceDirection(s);
    if (!direction) continue;
    const Vec3 d = *direction;
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

double voxelStageBytes(std::size_t candidates, std::size_t voxels) {
  return 3.0 * double(std::max<std::size_t>(candidates, 1)) / 8.0 * double(voxels);
}

SurfacesAndCandidates detectAndFit(const PointCloud& scan, const DetectAndFitOptions& options,
                                   const StageCallback& onStage, const ProgressCallback& progress) {
  if (scan.empty()) throw std::invalid_argument("the scan has no points");
  if (!scan.hasNormals()) throw std::invalid_argument("the scan has no normals");
  SurfacesAndCandidates out;
  if (onStage) onStage("detect", false, {});
  Clock::time_point start = Clock::now();
  double cpu = processCpuSeconds();
  // Seconds and CPU seconds since the last call (or the start).
  const auto lap = [&](double& wall, double& cpuSeconds) {
    wall = secondsSince(start);
    const double now = processCpuSeconds();
    cpuSeconds = now - cpu;
    cpu = now;
    start = Clock::now();
  };
  DetectOptions dopt = options.detect;
  dopt.seed = options.seed;
  out.detection = detectSurfaces(scan, dopt, progress);
  if (!out.detection.ok()) return out;
  DetectionResult& det = out.detection;
  // The noise estimate is local: its neighbourhoods shrink as the points
  // get denser, and in a volume of dense scattered points a small
  // neighbourhood looks like a patch of noisy surface (30 000 random points
  // in a cube read 1.3 % of D). Scattered points are told by the spread
  // over wider neighbourhoods, those of 2000 of the points; noisy scans of
  // surfaces read about the same either way.
  double spread = det.noise;
  if (scan.size() > kScatterPoints) {
    PointCloud subset;
    const std::size_t step = (scan.size() + kScatterPoints - 1) / kScatterPoints;
    for (std::size_t i = 0; i < scan.size(); i += step) {
      subset.points.push_back(scan.points[i]);
      subset.normals.push_back(scan.normals[i]);
    }
    spread = std::max(spread, estimateNoise(subset));
  }
  lap(out.detectSeconds, out.detectCpuSeconds);
  if (spread > options.maxNoise * det.diagonal) {
    char buf[256];
    std::snprintf(buf, sizeof(buf),
                  "the points do not lie on surfaces: their estimated noise is %.3g %% of the "
                  "diagonal (at most %.3g %% is accepted); not the scan of a solid",
                  100.0 * spread / det.diagonal, 100.0 * options.maxNoise);
    det.status = DetectionResult::Status::NoSurfaces;
    det.message = buf;
    return out;
  }
  // After a search on a subsample, the surfaces were fitted, pruned and
  // split there, and all the points assigned (detectSurfaces): on all the
  // points they are fitted once.
  SurfaceFitOptions fit;
  if (det.searchedPoints < scan.size()) fit.removeRedundant = fit.splitSteps = fit.reassign = false;
  fitSurfaces(scan, out.detection, fit);
  // A raw scan: normals estimated from the points, or given by a scanner
  // (noisy, measured on the first surfaces), not a sample's exact ones.
  const bool raw = det.rawNormals;
  if (options.wallBores && raw) {
    WallBoreOptions wo = options.wallBoreOptions;
    wo.seed = options.seed;
    out.wallBores = addWallBores(scan, out.detection, wo);
    if (out.wallBores.bores > 0) {
      out.detection.message += "; " + std::to_string(out.wallBores.bores) + " bore" +
                               (out.wallBores.bores == 1 ? "" : "s") + " found from their walls";
    }
  }
  if (options.wallPlanes && raw) {
    out.wallPlanes = addWallPlanes(scan, out.detection, options.wallPlaneOptions);
    if (out.wallPlanes.planes > 0) {
      out.detection.message += "; " + std::to_string(out.wallPlanes.planes) + " face" +
                               (out.wallPlanes.planes == 1 ? "" : "s") +
                               " found from their points";
    }
  }
  if (options.sheetRounds && raw) {
    out.sheetRounds = replaceSheetRounds(scan, out.detection, options.sheetRoundOptions);
    const std::size_t edges =
        out.sheetRounds.tori + out.sheetRounds.cylinders + out.sheetRounds.corners;
    if (edges > 0) {
      out.detection.message += "; " + std::to_string(edges) + " round" + (edges == 1 ? "" : "s") +
                               " taken for a thin sheet's square edge";
    }
    if (out.sheetRounds.tilted > 0) {
      out.detection.message += "; " + std::to_string(out.sheetRounds.tilted) + " tilted plane" +
                               (out.sheetRounds.tilted == 1 ? "" : "s") +
                               " taken for a thin sheet's square edge";
    }
  }
  if (options.rimHoles && raw) {
    out.rimHoles = addRimHoles(scan, out.detection, options.rimHoleOptions);
    if (out.rimHoles.holes > 0) {
      out.detection.message += "; " + std::to_string(out.rimHoles.holes) + " hole" +
                               (out.rimHoles.holes == 1 ? "" : "s") + " found from their rims";
    }
    if (out.rimHoles.windows > 0) {
      out.detection.message += "; " + std::to_string(out.rimHoles.windows) + " window" +
                               (out.rimHoles.windows == 1 ? "" : "s") + " found from their rims";
    }
  }
  lap(out.fitSeconds, out.fitCpuSeconds);
  out.regularization = regularizeSurfaces(out.detection);
  // On a raw scan a surface seen in parts (a bore at its mouths) gives
  // several fits that regularisation makes one surface but for a tilt past
  // its tolerance: the fits that explain each other's points merge.
  if (raw) {
    out.regularization.duplicatesMerged += int(mergeDuplicateSurfaces(scan, out.detection, fit));
  }
  lap(out.regularizeSeconds, out.regularizeCpuSeconds);
  if (onStage) onStage("detect", true, out.detection.message);

  if (onStage) onStage("hypotheses", false, {});
  lap(out.hypothesisSeconds, out.hypothesisCpuSeconds);  // the stage callback's time is not counted
  const OrientedBox box = gridBox(scan, out.detection.surfaces, options.seed);
  const auto gridAt = [&](int resolution) {
    GridOptions go;
    go.resolution = resolution;
    return VoxelGrid::around(box, go);
  };
  const auto layGrid = [&](int resolution) {
    out.grid = gridAt(resolution);
    out.resolution = resolution;
    HypothesisOptions ho = options.hypotheses;
    ho.voxelSize = out.grid.voxelSize();
    ho.seed = std::uint32_t(options.seed);
    out.hypotheses = generateHypotheses(scan, out.detection.surfaces, ho);
  };
  // The resolution: the asked one, or finer when the part is thin (decided
  // on the asked grid's voxel size; hypotheses are built once, on the grid
  // chosen).
  int resolution = options.resolution;
  std::string finerNote;
  if (options.finerGrid && options.maxFinerGrid > 1.0) {
    const double h = gridAt(options.resolution).voxelSize();
    ThinFeatureOptions to;
    to.maxThickness = options.thinVoxels * h;
    to.reach = h;
    out.thin = findThinFeatures(scan, out.detection.surfaces, to);
    if (!out.thin.empty()) {
      // Voxels scale as 1 / resolution: the resolution that gives the
      // thinnest feature thinVoxels voxels, at most maxFinerGrid times the
      // asked one. Not laid when its voxels would be under noiseVoxels times
      // the residual of the feature's own surfaces: a part of two voxels
      // there is noise, not a wall. (The scan-wide noise estimate is no
      // guide here: its neighbourhoods straddle both faces of a thin wall.)
      const ThinFeature& t = out.thin.front();
      const double thinnest = std::max(t.thickness, 1e-12);
      double residual = out.detection.surfaces[std::size_t(t.first)].rms;
      if (t.second >= 0) {
        residual = std::max(residual, out.detection.surfaces[std::size_t(t.second)].rms);
      }
      const int finer = int(std::min(std::ceil(options.resolution * to.maxThickness / thinnest),
                                     std::floor(options.resolution * options.maxFinerGrid)));
      const double finerVoxel = h * double(options.resolution) / double(finer);
      if (finer > options.resolution && finerVoxel >= options.noiseVoxels * residual) {
        resolution = finer;
        char buf[128];
        std::snprintf(buf, sizeof(buf), ", resolution %d (a %s %.2g voxels thin)", finer,
                      std::string(thinKindName(t.kind)).c_str(), thinnest / h);
        finerNote = buf;
      }
    }
  }
  layGrid(resolution);
  if (resolution != options.resolution && options.memoryLimit > 0 &&
      voxelStageBytes(out.hypotheses.candidates.size(), out.grid.voxelCount()) >
          double(options.memoryLimit)) {
    layGrid(options.resolution);  // the finer grid does not fit: the asked one
    finerNote.clear();
  }
  lap(out.hypothesisSeconds, out.hypothesisCpuSeconds);
  if (onStage) {
    onStage("hypotheses", true,
            std::to_string(out.hypotheses.candidates.size()) + " candidates" + finerNote);
  }
  return out;
}

}  // namespace csgvox
