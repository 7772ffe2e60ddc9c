#pragma once
/// Surface detection: the planes, cylinders, cones, spheres and tori that
/// explain a scan, found by efficient RANSAC (Schnabel et al. 2007) with
/// parameters relative to the scan's bounding-box diagonal D and to its
/// estimated noise, so clean and noisy scans need no tuning.

#include <cstddef>
#include <cstdint>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "core/point_cloud.h"
#include "core/progress.h"
#include "core/surface.h"

namespace csgvox {

/// Options of detectSurfaces. Lengths are fractions of the scan's
/// bounding-box diagonal D.
struct DetectOptions {
  /// Kinds of surface looked for.
  std::set<SurfaceType> enabled = {SurfaceType::Plane, SurfaceType::Cylinder, SurfaceType::Cone,
                                   SurfaceType::Sphere, SurfaceType::Torus};
  double epsilon = 0.005;  ///< largest distance of an inlier from its surface, fraction of D
                           ///< (raised by noiseFactor)
  double noiseFactor =
      2.5;  ///< epsilon is at least this many times the estimated noise sigma (ratio)
  double maxEpsilon = 0.02;      ///< cap on the noise-raised epsilon, fraction of D
  double clusterEpsilon = 0.01;  ///< largest gap inside one connected patch, fraction of D (raised
                                 ///< to spacingFactor x point spacing)
  double spacingFactor =
      3.0;  ///< clusterEpsilon is at least this many times the median point spacing (ratio)
  double normalThreshold = 0.9;  ///< smallest cosine between an inlier's normal and the surface's
                                 ///< (RANSAC ignores the sign, the final assignment does not)
  /// The normals were estimated from raw points (ScanInfo::normalsEstimated):
  /// near sharp edges they blend the two faces and fail the normal test of
  /// both, so after each stage the points a surface found beside them
  /// explains by distance (within epsilon plus 3 x the local RMS of its
  /// inliers, for a scanner's noise that grows at grazing incidence) are
  /// not searched again (else small spurious surfaces explain those strips:
  /// a false rounded edge). Given normals are trusted as they are.
  bool estimatedNormals = false;
  /// Given normals whose noise on the first stage's surfaces
  /// (DetectionResult::normalNoise) exceeds this many radians are a
  /// scanner's, from its range image, and are treated from the next stage
  /// on as estimated ones; the raw-scan stages after detection
  /// (DetectAndFitOptions) follow the same test. A uniform sample's exact
  /// normals read at most 0.0005 (the bundled scans, noisy ones too), a
  /// scanner's 0.022-0.026 and estimated ones about 0.017 (the bundled
  /// parts' scanner scans).
  double scannerNormalNoise = 0.005;
  double minPoints = 0.002;  ///< fewest inliers of a surface, fraction of the number of points N
  std::size_t minPointsFloor =
      12;  ///< fewest inliers of a surface, count (applies when minPoints*N is smaller)
  double probability =
      0.005;           ///< RANSAC: accepted probability of overlooking the best candidate (0, 1)
  bool staged = true;  ///< search planes and cylinders first, then cones and spheres, then tori
  int passes =
      2;  ///< passes over all enabled types; each later pass searches the unassigned points again
  double laterPassMinPoints =
      0.5;  ///< min-points factor of each later pass relative to the previous one (ratio)
  std::uint64_t seed = 1;  ///< random seed; the same seed and input give the same result
  /// A scan of more points is searched on an even subsample of about this
  /// many (evenSubsample: cells at least 6 x the noise wide), and then every
  /// point goes to the surface that explains it: the search costs the same
  /// and its thresholds stay put whatever the density (count; 0: always all
  /// points).
  std::size_t ransacPoints = 50000;
};

/// Surfaces found in a scan, with the point-to-surface assignment.
struct DetectionResult {
  /// Outcome of detectSurfaces.
  enum class Status {
    Ok,               ///< at least one surface was found
    NoSurfaces,       ///< the scan is valid but no surface explains enough points
    DegenerateInput,  ///< too few points, or they are identical, collinear or coplanar
    Cancelled,        ///< the progress callback asked to stop
  };

  std::vector<Surface> surfaces;  ///< detected surfaces, largest first
  std::vector<int> assignment;    ///< per point: index into surfaces, or -1 when unassigned
  std::vector<Vec3> centroids;    ///< per surface: mean of its inliers (pivot for regularisation)
  Status status = Status::NoSurfaces;
  std::string message;    ///< one line: what was found, or why nothing was
  double diagonal = 0.0;  ///< D of the scan, scan units
  double noise = 0.0;     ///< estimated position noise sigma, scan units
  double normalNoise =
      0.0;  ///< estimated normal noise sigma, radians (measured on the first planes found)
  /// The normals are a raw scan's: estimated (DetectOptions::estimatedNormals)
  /// or, by their noise after the first stage, a scanner's
  /// (DetectOptions::scannerNormalNoise). The raw-scan stages follow it.
  bool rawNormals = false;
  double epsilon = 0.0;          ///< inlier distance used, scan units
  double clusterEpsilon = 0.0;   ///< connectivity distance used, scan units
  double normalThreshold = 0.9;  ///< normal agreement used (|cos|)
  std::size_t minPoints =
      0;  ///< fewest inliers a surface may keep (the last pass's minimum), count
  /// Points RANSAC searched: all of them, or the even subsample's count for
  /// a scan of more than DetectOptions::ransacPoints (then the surfaces are
  /// fitted, split and pruned there, see detectSurfaces).
  std::size_t searchedPoints = 0;
  /// The even subsample's point indices, ascending, when RANSAC searched one
  /// (empty when it searched all points). The stages after detection work on
  /// these points too (see reconstruct).
  std::vector<std::uint32_t> searched;

  /// True when status is Ok.
  bool ok() const { return status == Status::Ok; }
};

/// Name of a status for messages: "ok", "no surfaces", "degenerate input", "cancelled".
std::string_view detectionStatusName(DetectionResult::Status status);

/// The neighbourhood of estimateNoise, by default and in detection.
inline constexpr int kNoiseNeighbors = 12;

/// Robust estimate of the scan's noise sigma: over a deterministic subset of
/// the points, the median residual of a quadric height fit, along the local
/// normal, to each point's `neighbors` nearest in its tangent plane (among
/// its 6 x neighbors nearest that face the same way when the cloud has
/// normals), corrected for the fit's degrees of freedom. Scale-free, not
/// flattened by the noise from sparse to dense scans, 0 on clean faces flat
/// or curved; edges and thin walls bias it little because the median
/// ignores them. Scan units; 0 for fewer than neighbors+1 points.
double estimateNoise(const PointCloud& cloud, int neighbors = kNoiseNeighbors);

/// Robust estimate of the noise of the scan's normals: the median angle
/// between a point's normal and its nearest neighbour's, divided by sqrt(2),
/// over a deterministic subset of the points. Radians; curvature between
/// neighbours adds to it, so it errs on the large side.
double estimateNormalNoise(const PointCloud& cloud);

/// Median distance from a point to its nearest neighbour, over a
/// deterministic subset of the points; scan units.
double estimateSpacing(const PointCloud& cloud);

/// Finds the surfaces that explain the scan:
/// 1. estimates the position noise, normal noise and point spacing, and
///    raises epsilon and clusterEpsilon to what they require;
/// 2. runs CGAL's efficient RANSAC in stages (planes and cylinders, then cones
///    and spheres, then tori, then `passes`-1 passes over all types with
///    fewer points), each stage on the points not yet explained;
/// 3. after each stage, replaces each shape by the best of it refined and
///    every enabled type fitted to its inliers (robust cost plus a BIC
///    penalty: a narrow plane strip is a plane, not a large cylinder), then
///    settles all surfaces so far with fitSurfaces (redundant ones
///    dropped, points re-assigned, surfaces re-fitted).
/// A scan of more than options.ransacPoints points is searched on an even
/// subsample of that many (seeded by options.seed), with the noise, spacing
/// and minimum support measured there, and its surfaces are fitted there
/// (fitSurfaces: the redundant ones dropped, stepped cylinders split, both
/// of which depend on the density); then every point of the scan is
/// assigned to the surface it lies on (reassignPoints, in connected
/// patches), with the minimum support scaled to the whole scan. A surface
/// fit on the whole scan should then leave those decisions alone
/// (detectAndFit runs it without removeRedundant, splitSteps and reassign:
/// the surfaces fitted once on their points).
/// Surfaces are sorted by inlier count (largest first); each inlier belongs
/// to exactly one surface. Plane normals agree with the majority of their
/// inliers' normals; curved surfaces say whether they are convex.
/// surface.rms is the RMS distance of the inliers. The same input and seed
/// give the same result. Degenerate scans (fewer than 3 points, all points
/// identical, collinear or coplanar) and scans without a fittable surface
/// return a non-Ok status with a message; they do not throw.
/// @throw std::invalid_argument when a cloud of 3 or more points has no
///        normals or holds a non-finite coordinate or normal, or when options
///        are out of range.
DetectionResult detectSurfaces(const PointCloud& cloud, const DetectOptions& options = {},
                               const ProgressCallback& progress = {});

}  // namespace csgvox
