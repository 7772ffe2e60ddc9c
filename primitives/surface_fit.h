#pragma once
/// The surface fit: nonlinear least squares of each detected surface on
/// its inliers (orthogonal distance, robust loss), re-assignment of points to
/// the surface that explains them best, and a final re-fit, so the surface
/// parameters are as exact as the scan allows.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>

#include "core/point_cloud.h"
#include "core/surface.h"
#include "primitives/surface_detection.h"

namespace csgvox {

/// Options of fitSurfaces and fitSurface.
struct SurfaceFitOptions {
  double lossScale = 1.0;  ///< Huber loss scale of the orthogonal distance, in units of the
                           ///< detection epsilon (ratio)
  bool useNormals = true;  ///< also fit the scan normals, weighted by their estimated noise
  int maxIterations = 50;  ///< Levenberg-Marquardt iterations per fit (count)
  std::size_t maxFitPoints =
      5000;  ///< larger inlier sets are fitted on an even subset of this many points (count)
  bool reassign = true;  ///< re-assign points to the nearest compatible surface, then re-fit
  bool connectedPatches = true;    ///< the re-assignment keeps a surface's points only on its
                                   ///< connected patches (see reassignPoints)
  bool normalNoiseTest = true;     ///< the re-assignment also holds a point's normal to the
                                   ///< normal noise, not only to the cosine threshold (see
                                   ///< reassignPoints)
  bool removeRedundant = true;     ///< drop surfaces whose points other surfaces explain as well
  double redundantFraction = 0.8;  ///< a surface is redundant when other surfaces explain at least
                                   ///< this share of its inliers (fraction)
  bool flattenToPlanes = true;     ///< a cylinder or sphere whose fitted radius exceeds the
                                   ///< diagonal D, or a cone within 2 degrees of flat or wider
                                   ///< than D where its inliers lie, becomes the plane of its
                                   ///< inliers; a cone within 2 degrees of a cylinder, their
                                   ///< cylinder (or plane, when wider than D)
  bool splitSteps = true;  ///< a cylinder (or a cone within 5 degrees of one) whose inliers lie at
                           ///< two distinct distances from its axis becomes two cylinders (a hole
                           ///< and its counterbore taken as one surface)
};

/// Residual scales of one fit: each point contributes its orthogonal distance
/// divided by `position` and, when `normal` > 0, the tangential part of its
/// scan normal divided by the normal noise (see fitResidual2).
struct FitScales {
  double position = 1.0;  ///< position noise sigma, scan units (> 0)
  double normal = 0.0;    ///< normal noise sigma, radians; 0 ignores the normals
  double loss = 1.0;      ///< Huber scale of the orthogonal distance, scan units (> 0)
};

/// How well one point with scan normal n fits a surface, in the terms of
/// fitSurface's model.
struct PointFit {
  double distance = 0.0;  ///< orthogonal distance to the surface, scan units
  /// Squared components of n along the surface's principal tangent
  /// directions, each divided by sqrt(normal^2 + (position x curvature)^2):
  /// about chi-square with 2 degrees of freedom for a point on the surface.
  double normal2 = 0.0;
  double cosine = 1.0;  ///< cosine between n and the surface's oriented normal at p
};

/// Largest PointFit::normal2 of a point that lies on its surface: the 99.9 %
/// quantile of chi-square with 2 degrees of freedom.
inline constexpr double kNormalChi2 = 13.8;

/// The residuals of point p with scan normal n on the surface.
PointFit pointFit(const Surface& surface, const Vec3& p, const Vec3& n, const FitScales& scales);

/// True when the point lies on the surface: within `epsilon` (scan units),
/// its normal within the cosine `threshold` of the surface's oriented normal
/// and, when scales.normal > 0, normal2 <= kNormalChi2.
bool pointOnSurface(const Surface& surface, const Vec3& p, const Vec3& n, const FitScales& scales,
                    double epsilon, double threshold);

/// The scales fitSurfaces uses for the surfaces of a detection result:
/// position from result.noise (at least 2 % of result.epsilon), normal from
/// result.normalNoise (at least 0.02 rad; 0 when options.useNormals is
/// false), loss options.lossScale x result.epsilon.
FitScales fitScales(const DetectionResult& result, const SurfaceFitOptions& options = {});

/// Fits made on one cloud, kept so that a fit asked for again is looked up
/// instead of solved: a fit is a function of its points, its start, its
/// scales and its options alone, so the answer is the same, bit for bit.
/// Detection settles its surfaces after every RANSAC stage, and a surface
/// whose inliers did not change is fitted again from where its last fit
/// ended (about a third of the fitting time of a 100k-point scan).
/// Thread-safe; belongs to one cloud (its points and normals unchanged
/// while it is used).
class FitMemo {
 public:
  explicit FitMemo(const PointCloud& cloud);
  ~FitMemo();
  FitMemo(const FitMemo&) = delete;
  FitMemo& operator=(const FitMemo&) = delete;

  const PointCloud& cloud() const { return cloud_; }
  /// Fits looked up, and fits solved and kept (counts).
  std::size_t hits() const;
  std::size_t solved() const;

 private:
  friend double fitSurface(const PointCloud&, std::span<const std::uint32_t>, Surface&,
                           const FitScales&, const SurfaceFitOptions&, FitMemo*);
  struct Store;
  const PointCloud& cloud_;
  std::unique_ptr<Store> store_;
};

/// Fits `surface` (type and start parameters as given) to the points
/// `indices` of the cloud: robust (Huber) least squares of their orthogonal
/// distances and, optionally, of their normals' deviation. Unit vectors stay
/// unit; the plane's orientation and the convexity flag are re-derived from
/// the points' normals. Returns the RMS orthogonal distance of the points to
/// the fitted surface, or a negative number (leaving `surface` unchanged)
/// when the fit degenerates (for example a torus whose tube radius exceeds its
/// ring radius). Does not change surface.inliers. With a `memo` (of this
/// cloud), a fit it holds is looked up and a new one kept.
/// @throw std::invalid_argument when scales.position or scales.loss is not
///        positive or scales.normal is negative, or the memo belongs to
///        another cloud.
double fitSurface(const PointCloud& cloud, std::span<const std::uint32_t> indices, Surface& surface,
                  const FitScales& scales, const SurfaceFitOptions& options = {},
                  FitMemo* memo = nullptr);

/// A closed-form start for a surface of the given type on the points
/// `indices` and their normals, to be polished with fitSurface: PCA plane;
/// algebraic sphere; for surfaces of revolution the axis from the normals
/// (perpendicular to a cylinder's, at a constant angle to a cone's, meeting a
/// torus' normal lines), then a line or circle fit in the (height, radius)
/// half-plane. Returns false when the points do not determine the surface.
bool initialSurface(const PointCloud& cloud, std::span<const std::uint32_t> indices,
                    SurfaceType type, Surface& surface);

/// Number of parameters of a surface type: plane 3, sphere 4, cylinder 5,
/// cone 6, torus 7 (the simpler the type, the fewer).
int parameterCount(SurfaceType type);

/// True when the surface is a plausible feature of a part of diagonal `diag`:
/// radii up to the diagonal, a torus' tube no wider than its ring, a cone
/// neither within 2 degrees of flat nor of a cylinder.
bool plausibleSurface(const Surface& s, double diag);

/// plausibleSurface, and a cone no wider than `diag` where the points
/// `indices` of the cloud lie (their mean distance from its axis): a cone
/// whose apex lies far beyond the part is a wide cylinder or a plane there.
bool plausibleSurface(const Surface& s, double diag, const PointCloud& cloud,
                      std::span<const std::uint32_t> indices);

/// The unit outward normal of the (unbounded) surface at p, oriented as its
/// inliers: the plane's normal; for curved surfaces away from the axis,
/// centre or tube centre when the surface is convex, towards it otherwise.
Vec3 surfaceNormal(const Surface& surface, const Vec3& p);

/// Assigns every point to the surface it fits best (smallest scaled squared
/// distance plus PointFit::normal2) among those it lies on (pointOnSurface
/// with fitScales(result), result.epsilon and result.normalThreshold), or to
/// none. Without `normalNoiseTest`, the points left over once the surfaces
/// that live are settled go to them by distance and the cosine threshold
/// alone (PointFit::normal2 still ranks the surfaces): a raw scan's normals
/// within a few neighbourhoods of an edge blend the two faces, far beyond
/// the noise measured inside the faces, and the strips of them RANSAC takes
/// for surfaces of their own still die by the noise test. With `connectedPatches`, as in detection,
/// a surface's points must form connected patches (cells of side result.clusterEpsilon that touch):
/// when a surface has a patch of at least `minPoints` points, its points in
/// smaller patches (noise of other surfaces reaching into its band away from
/// it) go to the best other surface whose patch they touch, or to none.
/// Updates inliers,
/// assignment, centroids and rms, and drops surfaces left with fewer than
/// `minPoints` inliers (their points go to the next best surface). Surfaces
/// keep their order.
void reassignPoints(const PointCloud& cloud, DetectionResult& result, std::size_t minPoints,
                    bool connectedPatches = true, bool normalNoiseTest = true);

/// Merges the curved surfaces that regularisation left as duplicates: a
/// cylinder, cone, sphere or torus at least options.redundantFraction of
/// whose inliers a surface of its type and convexity, with as many inliers
/// or more, explains about as well (removeRedundant's test in fitSurfaces,
/// against that one surface) gives its inliers to it, the smallest first.
/// Two fits of one bore seen at its mouth only, one tilted a few degrees
/// past the regularisation's tolerance, become one surface once their radii
/// are made equal. The surfaces are not fitted again (they keep their
/// regularised parameters); inliers, rms, centroids and the assignment
/// follow, sorted by inlier count. Returns the number of surfaces merged.
/// @throw std::invalid_argument when result.assignment does not match the
///        cloud, or the cloud has no normals.
std::size_t mergeDuplicateSurfaces(const PointCloud& cloud, DetectionResult& result,
                                   const SurfaceFitOptions& options = {});

/// Refines every surface of `result` on its inliers (fitSurface with
/// fitScales), removes redundant surfaces (those whose points other surfaces
/// explain as well: duplicates, or one surface spanning several true ones),
/// re-assigns the points (reassignPoints), re-fits once and sets each
/// surface's rms and centroid.
/// Surfaces stay sorted by inlier count. A result without surfaces is left
/// as it is. Its fits go through `memo` (of this cloud) when one is given,
/// else through one of its own.
/// @throw std::invalid_argument when result.assignment does not match the
///        cloud, or the cloud has no normals, or the memo belongs to another
///        cloud.
void fitSurfaces(const PointCloud& cloud, DetectionResult& result,
                 const SurfaceFitOptions& options = {}, FitMemo* memo = nullptr);

}  // namespace csgvox
