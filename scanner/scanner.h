#pragma once
/// The acquisition model of a structured-light turntable scanner: what a
/// part really looks like once scanned. A perspective range camera looks at
/// the part from `views` turntable positions at each of `elevations` per
/// setup. In setup 1 the part stands on its lowest face (that face is
/// unseen); setup 2 scans it turned over (180° about a horizontal axis) and
/// registers the points back into setup 1's frame with a small rigid error.
/// Each pixel's depth is the first hit of its ray on the part (RayCaster),
/// with noise along the ray growing with range² and 1/cos(incidence); hits
/// seen too obliquely are dropped; pixels at depth edges may give a point
/// between the two depths (mixed pixels); a few sparse outliers lie along
/// random pixels' rays near the part. Density stays as the views give it.
/// Exact N points: the image resolution is raised until the views give at
/// least N points, then a random N of them are kept.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/point_cloud.h"
#include "scanner/ray_caster.h"

namespace csgvox {

/// What a scan's normals are.
enum class ScannerNormals {
  None,     ///< raw xyz, no normals (what most scanners export)
  Scanner,  ///< from the range image (neighbouring pixels' points), noisy, facing the sensor
};

/// Options of scanPart. D is the diagonal of the part's bounds.
struct ScannerOptions {
  int views = 8;                                  ///< turntable positions per turn, >= 1
  std::vector<double> elevations = {20.0, 55.0};  ///< camera elevations above the table, degrees, each in (0, 90)
  int setups = 2;                                 ///< 1: part on its lowest face; 2: also turned over
  double registrationTranslation = 0.0005;        ///< setup 2's registration error: shift, fraction of D
  double registrationRotation = 0.0005;           ///< setup 2's registration error: turn about the part's centre, radians
  double depthNoise = 0.0005;                     ///< σ0: depth noise sigma at the reference range and normal incidence, fraction of D
  double noiseIncidenceCap = 10.0;                ///< the noise's 1/cos(incidence) factor is at most this, >= 1
  double maxIncidence = 75.0;                     ///< hits seen at a larger angle to the surface normal are dropped, degrees in (0, 90]
  double mixedPixels = 0.3;                       ///< probability that a pixel at a depth edge gives a point between the two depths, [0, 1]
  double depthEdge = 8.0;                         ///< neighbouring pixels' depths differing by more than this many pixel footprints are an edge, > 0
  double outliers = 0.002;                        ///< sparse outliers, fraction of each view's points, [0, 1]
  double outlierMargin = 0.1;                     ///< outliers lie in the part's box grown by this, fraction of D, >= 0
  double fieldOfView = 30.0;                      ///< full angle of the camera's square image, degrees in (0, 120)
  double standoff = 1.1;                          ///< camera distance over the one where the part's bounding sphere just fills the image, >= 1
  double densityVariation = 1.0;                  ///< density at the dense end of the part over the sparse end's, >= 1: a smooth ramp along the part's longest side
  ScannerNormals normals = ScannerNormals::None;  ///< raw xyz or the scanner's normals
  std::size_t points = 20000;                     ///< points returned (a random subset of the views' points); 0: every point
  int resolution = 0;                             ///< image side in pixels; 0: the smallest that gives `points` (256 when points is 0)
  std::uint64_t seed = 1;                         ///< random seed; the same seed gives the same scan on any number of threads

  /// Checks every option.
  /// @throw std::invalid_argument naming the first bad option and its range.
  void validate() const;
};

/// What a scan point is.
enum class ScanPointKind : std::uint8_t {
  Surface,  ///< a pixel's hit on the surface (with noise)
  Mixed,    ///< a pixel at a depth edge, between the two depths
  Outlier,  ///< a sparse outlier along a pixel's ray
};

/// Counts of a scan, over every view at the final resolution.
struct ScannerCounts {
  std::size_t rays = 0;              ///< pixels cast
  std::size_t hits = 0;              ///< rays that met the part
  std::size_t droppedIncidence = 0;  ///< hits dropped for their incidence
  std::size_t edgePixels = 0;        ///< kept hits at a depth edge
  std::size_t mixed = 0;             ///< edge pixels that gave a mixed point
  std::size_t outliers = 0;          ///< sparse outliers added
  std::size_t points = 0;            ///< points of every view: hits - dropped + outliers
  std::size_t kept = 0;              ///< points returned
};

/// A simulated scan in the part's own frame (setup 1's).
struct ScannerScan {
  PointCloud cloud;  ///< the points; normals only with ScannerNormals::Scanner
  /// Per point: what it is.
  std::vector<ScanPointKind> kinds;
  /// Per point: the index in `sensors` of the camera position that saw it.
  std::vector<std::uint32_t> sensorOf;
  /// Camera positions in the output frame, setup by setup, then elevation by
  /// elevation, then view by view (setups × elevations × views).
  std::vector<Vec3> sensors;
  /// Per setup: the registration error applied to its points (identity for
  /// setup 1): output point = registration[s] * (exact point in the part's frame).
  std::vector<Eigen::Isometry3d> registration;
  ScannerCounts counts;
  int resolution = 0;     ///< image side in pixels used
  double diagonal = 0.0;  ///< D of the part's bounds
  /// The setup (0-based) of sensor `sensor`.
  int setupOf(std::uint32_t sensor) const;
};

/// Scans the part behind `caster` (a solid in its own frame, z up: it stands
/// on the table at its lowest z). Deterministic for options.seed, whatever the
/// number of threads (each view has its own generator from seed, setup and
/// view).
/// @throw std::invalid_argument for bad options (ScannerOptions::validate),
///        or when a fixed resolution gives fewer than `points` points.
ScannerScan scanPart(const RayCaster& caster, const ScannerOptions& options = {});

}  // namespace csgvox
