#pragma once
/// The first half of the main job, shared by every caller (the main job,
/// `csgvox detect`, the benchmarks and the tests): surfaces detected,
/// refined and regularised, the voxel grid's frame, and the bounded
/// primitive hypotheses fitted to that grid's voxel size.

#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <string_view>

#include "core/point_cloud.h"
#include "core/progress.h"
#include "primitives/hypotheses.h"
#include "primitives/regularization.h"
#include "primitives/rim_holes.h"
#include "primitives/sheet_rounds.h"
#include "primitives/surface_detection.h"
#include "primitives/thin_features.h"
#include "primitives/wall_bores.h"
#include "voxel/voxel_grid.h"

namespace csgvox {

/// Called when a stage starts and when it ends (`done`), with a one-line
/// summary of what it produced at the end.
using StageCallback =
    std::function<void(std::string_view stage, bool done, const std::string& summary)>;

/// Options of detectAndFit().
struct DetectAndFitOptions {
  int resolution = 64;     ///< voxels along the longest side of the grid box (8..1024)
  std::uint64_t seed = 1;  ///< seeds detection and the hypotheses' box search
  DetectOptions detect;    ///< surface detection (its seed is replaced by `seed`)
  HypothesisOptions
      hypotheses;  ///< hypotheses (voxelSize and seed are set from the grid and `seed`)
  /// A scan whose estimated position noise is larger, on the whole scan or
  /// on 2000 of its points (wider neighbourhoods), is refused as not the
  /// scan of a solid's surfaces (scattered points), fraction of D. The
  /// bundled noisy scans have 0.005; uniform random points in a cube about
  /// 0.037.
  double maxNoise = 0.02;
  /// Finer voxels for thin parts: when the surfaces show a feature thinner
  /// than `thinVoxels` voxels at `resolution` (a wall or a slot between
  /// opposite planes that face each other, a rod or a hole), the grid is laid
  /// at the resolution that gives the thinnest one `thinVoxels` voxels, at
  /// most `maxFinerGrid` × `resolution`.
  /// No finer grid is laid when its voxels would be smaller than
  /// `noiseVoxels` × the RMS residual of the thin feature's own surfaces:
  /// the labels would follow the noise, not the walls.
  bool finerGrid = true;
  double thinVoxels = 2.0;
  double maxFinerGrid = 2.0;
  double noiseVoxels = 2.0;
  /// Bytes the voxel stage may use (0: no limit): a finer grid that would
  /// need more (voxelStageBytes) falls back to `resolution`.
  std::size_t memoryLimit = 0;
  /// The raw-scan stages below run when detection found the normals a raw
  /// scan's (DetectionResult::rawNormals): estimated from raw points
  /// (detect.estimatedNormals) or a scanner's, whose noise on the first
  /// surfaces found exceeds detect.scannerNormalNoise.
  /// On a raw scan, a
  /// round gap in a plane's points that no curved surface explains becomes a
  /// hole cylinder (addRimHoles): a scanner sees little of a small bore's
  /// wall, and the face around it shows the hole.
  bool rimHoles = true;
  RimHoleOptions rimHoleOptions;  ///< their parameters
  /// On a raw scan, the points no surface took are
  /// searched for the walls of bores and bosses along the part's directions
  /// (addWallBores; before the rims): RANSAC overlooks many small ones.
  bool wallBores = true;
  WallBoreOptions wallBoreOptions;  ///< their parameters (the seed is the job's)
  /// On a raw scan, after the bores, the points no surface took are searched
  /// for narrow faces across the part's directions (addWallPlanes): a
  /// groove's wall a voxel or two wide, whose normals the neighbourhoods
  /// blend with the faces beside it.
  bool wallPlanes = true;
  WallPlaneOptions wallPlaneOptions;  ///< their parameters
  /// On a raw scan, the rounds that are a thin
  /// sheet's square edges blended by the normals (replaceSheetRounds; before
  /// the rims, whose holes a torus along the rim would hide) are dropped or
  /// made end faces.
  bool sheetRounds = true;
  SheetRoundOptions sheetRoundOptions;  ///< their parameters
};

/// Bytes the voxel stage needs for `candidates` on `voxels` (the
/// description sets, and up to twice that again for the optimisation).
double voxelStageBytes(std::size_t candidates, std::size_t voxels);

/// Surfaces and candidates of a scan, as the main job computes them.
struct SurfacesAndCandidates {
  DetectionResult detection;            ///< fitted and regularised surfaces (or why none)
  RegularizationReport regularization;  ///< what the regularisation changed
  VoxelGrid grid;                       ///< the main job's voxel grid (its size: the fit tolerance)
  HypothesisSet hypotheses;             ///< bounded candidates (empty unless detection.ok())
  int resolution = 0;                   ///< the grid's resolution (finer than asked when thin)
  std::vector<ThinFeature> thin;        ///< features thinner than thinVoxels at the asked one
  RimHoleStats rimHoles;                ///< holes found from their rims (rimHoles)
  WallBoreStats wallBores;              ///< bores found from their walls (wallBores)
  WallPlaneStats wallPlanes;            ///< faces found from their points (wallPlanes)
  SheetRoundStats sheetRounds;          ///< a thin sheet's edges read as rounds (sheetRounds)
  double detectSeconds = 0.0;           ///< RANSAC
  double fitSeconds = 0.0;              ///< the surface fit (Ceres)
  double regularizeSeconds = 0.0;       ///< regularisation
  double hypothesisSeconds = 0.0;       ///< grid frame and hypotheses
  double detectCpuSeconds = 0.0;        ///< CPU seconds (all threads) of each of the four
  double fitCpuSeconds = 0.0;           ///< ... the surface fit
  double regularizeCpuSeconds = 0.0;    ///< ... regularisation
  double hypothesisCpuSeconds = 0.0;    ///< ... grid frame and hypotheses

  bool ok() const { return detection.ok(); }
};

/// The box the voxel grid is laid over: aligned with the heaviest surface
/// direction (plane normal or axis) and the heaviest one orthogonal to it,
/// or the scan's minimal oriented box when the surfaces give no direction or
/// the aligned box is over a quarter larger. `seed` seeds the minimal box's
/// randomised search.
OrientedBox gridBox(const PointCloud& scan, std::span<const Surface> surfaces,
                    std::uint64_t seed = 1);

/// Detects, refines and regularises the scan's surfaces, lays the voxel
/// grid over gridBox() (finer where the part is thin: finerGrid) and builds the bounded hypotheses
/// with the grid's voxel size as their fit tolerance. Stages "detect" and "hypotheses" are reported
/// to `onStage`. `progress` is passed to detection: returning false cancels it (detection.status is
/// then Cancelled and nothing after detection runs). When detection finds nothing usable, or the
/// points are too scattered for surfaces to explain them (estimated noise above maxNoise), the
/// result carries status NoSurfaces and a one-line message, and no grid or hypotheses.
/// @throw std::invalid_argument when the scan is empty or has no normals.
SurfacesAndCandidates detectAndFit(const PointCloud& scan, const DetectAndFitOptions& options = {},
                                   const StageCallback& onStage = {},
                                   const ProgressCallback& progress = {});

}  // namespace csgvox
