#include "scanner/scanner.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>
#include <random>
#include <stdexcept>
#include <string>

#include "core/seed.h"

namespace csgvox {
namespace {

constexpr double kDegree = std::numbers::pi / 180.0;
constexpr int kPilotResolution = 48;  // image side of the run that sizes the real one
constexpr int kMaxResolution = 8192;

std::string number(double x) {
  std::string s = std::to_string(x);
  s.erase(s.find_last_not_of('0') + 1);
  if (!s.empty() && s.back() == '.') s.pop_back();
  return s;
}

void require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument(what);
}

// One camera position of one setup.
struct Camera {
  int setup = 0;
  Vec3 position;  // in the table's frame
  Vec3 forward, right, up;
};

// A setup: the part's pose on the table (part frame -> table frame) and the
// registration that brings its points back (exact part frame -> output).
struct Setup {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d registration = Eigen::Isometry3d::Identity();
};

// What one camera position gives, in pixel order then outliers.
struct ViewScan {
  std::vector<Vec3> points, normals;
  std::vector<ScanPointKind> kinds;
  ScannerCounts counts;
};

// The scene every view shares.
struct Scene {
  const RayCaster& caster;
  const ScannerOptions& options;
  Aabb box;             // the part's bounds, in its own frame
  double diagonal = 0;  // D
  double range = 0;     // reference range: camera to the box centre
  std::vector<Setup> setups;
  std::vector<Camera> cameras;
};

std::vector<Setup> makeSetups(const ScannerOptions& o, const Aabb& box, double diagonal) {
  std::vector<Setup> setups(std::size_t(o.setups));
  const Vec3 c = box.center();
  if (o.setups > 1) {
    // Turned over: 180° about the x axis through the box centre; the box
    // maps onto itself, so the part again stands at the box's lowest z.
    Setup& s = setups[1];
    s.pose = Eigen::Translation3d(c) * Eigen::AngleAxisd(std::numbers::pi, Vec3::UnitX()) *
             Eigen::Translation3d(-c);
    std::mt19937_64 rng(mixSeed(o.seed, 1000 + 1));
    std::normal_distribution<double> gauss;
    Vec3 axis(gauss(rng), gauss(rng), gauss(rng));
    Vec3 shift(gauss(rng), gauss(rng), gauss(rng));
    axis.normalize();
    shift.normalize();
    s.registration = Eigen::Translation3d(o.registrationTranslation * diagonal * shift) *
                     Eigen::Translation3d(c) *
                     Eigen::AngleAxisd(o.registrationRotation, axis) * Eigen::Translation3d(-c);
  }
  return setups;
}

std::vector<Camera> makeCameras(const ScannerOptions& o, const Aabb& box, double range) {
  std::vector<Camera> cameras;
  const Vec3 aim = box.center();
  for (int s = 0; s < o.setups; ++s) {
    for (double elevation : o.elevations) {
      for (int v = 0; v < o.views; ++v) {
        const double az = 2.0 * std::numbers::pi * v / o.views;
        const double el = elevation * kDegree;
        Camera cam;
        cam.setup = s;
        cam.position =
            aim + range * Vec3(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az),
                               std::sin(el));
        cam.forward = (aim - cam.position).normalized();
        cam.right = cam.forward.cross(Vec3::UnitZ()).normalized();
        cam.up = cam.right.cross(cam.forward);
        cameras.push_back(cam);
      }
    }
  }
  return cameras;
}

// The per-pixel result of casting: depth along the unit ray (NaN: no point),
// the cosine of the incidence.
struct RangeImage {
  int side = 0;
  std::vector<Vec3> directions;  // per pixel, unit, in the part's frame
  std::vector<double> depth;     // NaN where the pixel has no point
  std::vector<double> cosine;    // incidence cosine of the hit
  std::size_t index(int i, int j) const { return std::size_t(j) * std::size_t(side) + i; }
};

// Casts every pixel of `cam` at the part in its pose for the camera's setup.
RangeImage castView(const Scene& scene, const Camera& cam, const Vec3& origin, int side,
                    ViewScan& out) {
  const Eigen::Isometry3d& pose = scene.setups[std::size_t(cam.setup)].pose;
  const Mat3 toPart = pose.linear().transpose();
  const double halfWidth = std::tan(0.5 * scene.options.fieldOfView * kDegree);
  const double cosLimit = std::cos(scene.options.maxIncidence * kDegree);
  const double maxDistance = 2.0 * scene.range + scene.diagonal;
  RangeImage image;
  image.side = side;
  const std::size_t n = std::size_t(side) * std::size_t(side);
  image.directions.resize(n);
  image.depth.assign(n, std::numeric_limits<double>::quiet_NaN());
  image.cosine.assign(n, 0.0);
  for (int j = 0; j < side; ++j) {
    for (int i = 0; i < side; ++i) {
      const double x = ((i + 0.5) / side * 2.0 - 1.0) * halfWidth;
      const double y = (1.0 - (j + 0.5) / side * 2.0) * halfWidth;
      const Vec3 d = toPart * (cam.forward + x * cam.right + y * cam.up).normalized();
      const std::size_t k = image.index(i, j);
      image.directions[k] = d;
      ++out.counts.rays;
      const auto hit = scene.caster.firstHit(origin, d, maxDistance);
      if (!hit) continue;
      ++out.counts.hits;
      const double c = -d.dot(hit->normal);
      if (c < cosLimit || c <= 0.0) {
        ++out.counts.droppedIncidence;
        continue;
      }
      image.depth[k] = hit->distance;
      image.cosine[k] = c;
    }
  }
  return image;
}

// Neighbours of pixel (i, j) inside the image: right, left, down, up.
constexpr int kDi[4] = {1, -1, 0, 0};
constexpr int kDj[4] = {0, 0, 1, -1};

// True when depths a and b of neighbouring pixels are not one surface.
bool isEdge(double a, double b, double footprintPerDepth, double edgeFactor) {
  return std::abs(a - b) > edgeFactor * footprintPerDepth * std::min(a, b);
}

// Scanner normal at pixel k from its neighbours' points (not across an edge):
// central differences where both sides are there, one-sided otherwise;
// facing the sensor; -direction when the neighbours give none.
Vec3 rangeImageNormal(const RangeImage& image, const std::vector<Vec3>& points, int i, int j,
                      double footprintPerDepth, double edgeFactor) {
  const std::size_t k = image.index(i, j);
  auto neighbour = [&](int a) -> std::ptrdiff_t {
    const int ni = i + kDi[a], nj = j + kDj[a];
    if (ni < 0 || nj < 0 || ni >= image.side || nj >= image.side) return -1;
    const std::size_t m = image.index(ni, nj);
    if (std::isnan(image.depth[m])) return -1;
    if (isEdge(image.depth[k], image.depth[m], footprintPerDepth, edgeFactor)) return -1;
    return std::ptrdiff_t(m);
  };
  auto tangent = [&](int plus, int minus, Vec3& t) {
    const std::ptrdiff_t p = neighbour(plus), m = neighbour(minus);
    if (p < 0 && m < 0) return false;
    const Vec3& a = p >= 0 ? points[std::size_t(p)] : points[k];
    const Vec3& b = m >= 0 ? points[std::size_t(m)] : points[k];
    t = a - b;
    return true;
  };
  const Vec3& d = image.directions[k];
  Vec3 tu, tv;
  if (!tangent(0, 1, tu) || !tangent(2, 3, tv)) return -d;
  Vec3 n = tu.cross(tv);
  const double length = n.norm();
  if (!(length > 0.0)) return -d;
  n /= length;
  return n.dot(d) > 0.0 ? Vec3(-n) : n;
}

// Scans one camera position at image side `side`.
ViewScan scanView(const Scene& scene, std::size_t cameraIndex, int side) {
  const ScannerOptions& o = scene.options;
  const Camera& cam = scene.cameras[cameraIndex];
  const Setup& setup = scene.setups[std::size_t(cam.setup)];
  const std::size_t perSetup = scene.cameras.size() / scene.setups.size();
  std::mt19937_64 rng(
      mixSeed(mixSeed(o.seed, std::uint64_t(cam.setup) + 1), cameraIndex % perSetup));
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::normal_distribution<double> gauss(0.0, 1.0);

  ViewScan out;
  const Vec3 origin = setup.pose.inverse() * cam.position;  // in the part's frame
  RangeImage image = castView(scene, cam, origin, side, out);
  const double footprintPerDepth = 2.0 * std::tan(0.5 * o.fieldOfView * kDegree) / side;

  // Mixed pixels: a pixel with a neighbour across a depth jump may give a
  // point between its depth and that neighbour's (the largest jump).
  std::vector<double> depth = image.depth;
  std::vector<bool> mixed(depth.size(), false);
  for (int j = 0; j < side; ++j) {
    for (int i = 0; i < side; ++i) {
      const std::size_t k = image.index(i, j);
      if (std::isnan(image.depth[k])) continue;
      double far = image.depth[k];
      for (int a = 0; a < 4; ++a) {
        const int ni = i + kDi[a], nj = j + kDj[a];
        if (ni < 0 || nj < 0 || ni >= side || nj >= side) continue;
        const double other = image.depth[image.index(ni, nj)];
        if (std::isnan(other) || !isEdge(image.depth[k], other, footprintPerDepth, o.depthEdge)) {
          continue;
        }
        if (std::abs(other - image.depth[k]) > std::abs(far - image.depth[k])) far = other;
      }
      if (far == image.depth[k]) continue;
      ++out.counts.edgePixels;
      if (uniform(rng) >= o.mixedPixels) continue;
      depth[k] = image.depth[k] + uniform(rng) * (far - image.depth[k]);
      mixed[k] = true;
      ++out.counts.mixed;
    }
  }

  // Depth noise along the ray.
  const double sigma0 = o.depthNoise * scene.diagonal;
  std::vector<Vec3> points(depth.size(), Vec3::Zero());
  for (std::size_t k = 0; k < depth.size(); ++k) {
    if (std::isnan(depth[k])) continue;
    const double ratio = depth[k] / scene.range;
    const double factor = std::min(1.0 / image.cosine[k], o.noiseIncidenceCap);
    const double t = depth[k] + sigma0 * ratio * ratio * factor * gauss(rng);
    points[k] = origin + t * image.directions[k];
  }

  const bool withNormals = o.normals == ScannerNormals::Scanner;
  for (int j = 0; j < side; ++j) {
    for (int i = 0; i < side; ++i) {
      const std::size_t k = image.index(i, j);
      if (std::isnan(depth[k])) continue;
      out.points.push_back(points[k]);
      out.kinds.push_back(mixed[k] ? ScanPointKind::Mixed : ScanPointKind::Surface);
      if (withNormals) {
        out.normals.push_back(
            rangeImageNormal(image, points, i, j, footprintPerDepth, o.depthEdge));
      }
    }
  }

  // Sparse outliers: a random depth along a random pixel's ray, within the
  // part's box grown by the margin.
  const std::size_t outliers = std::size_t(std::llround(o.outliers * double(out.points.size())));
  const Aabb box = scene.box.grown(o.outlierMargin * scene.diagonal);
  std::uniform_int_distribution<std::size_t> pixel(0, image.directions.size() - 1);
  for (std::size_t added = 0, tries = 0; added < outliers && tries < 1000 * (outliers + 1);
       ++tries) {
    const Vec3& d = image.directions[pixel(rng)];
    const auto span = rayBoxInterval(box, origin, d, 2.0 * scene.range + scene.diagonal);
    if (!span) continue;
    const double t = span->first + uniform(rng) * (span->second - span->first);
    out.points.push_back(origin + t * d);
    out.kinds.push_back(ScanPointKind::Outlier);
    if (withNormals) out.normals.push_back(-d);
    ++added;
    ++out.counts.outliers;
  }
  // Into the output frame.
  for (Vec3& p : out.points) p = setup.registration * p;
  for (Vec3& n : out.normals) n = setup.registration.linear() * n;
  out.counts.points = out.points.size();
  return out;
}

void addCounts(ScannerCounts& a, const ScannerCounts& b) {
  a.rays += b.rays;
  a.hits += b.hits;
  a.droppedIncidence += b.droppedIncidence;
  a.edgePixels += b.edgePixels;
  a.mixed += b.mixed;
  a.outliers += b.outliers;
  a.points += b.points;
}

// Every view at image side `side`, joined in camera order.
ScannerScan scanAll(const Scene& scene, int side) {
  std::vector<ViewScan> views(scene.cameras.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, views.size(), 1),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t c = r.begin(); c < r.end(); ++c) {
                        views[c] = scanView(scene, c, side);
                      }
                    });
  ScannerScan scan;
  scan.resolution = side;
  scan.diagonal = scene.diagonal;
  for (const Setup& s : scene.setups) scan.registration.push_back(s.registration);
  for (std::size_t c = 0; c < views.size(); ++c) {
    const Setup& setup = scene.setups[std::size_t(scene.cameras[c].setup)];
    scan.sensors.push_back(setup.registration * (setup.pose.inverse() * scene.cameras[c].position));
    ViewScan& v = views[c];
    scan.cloud.points.insert(scan.cloud.points.end(), v.points.begin(), v.points.end());
    scan.cloud.normals.insert(scan.cloud.normals.end(), v.normals.begin(), v.normals.end());
    scan.kinds.insert(scan.kinds.end(), v.kinds.begin(), v.kinds.end());
    scan.sensorOf.insert(scan.sensorOf.end(), v.points.size(), std::uint32_t(c));
    addCounts(scan.counts, v.counts);
  }
  scan.counts.kept = scan.cloud.size();
  return scan;
}

// Points the views must give so that `wanted` can be kept with the density
// ramp: the dense end keeps all its points, the rest keep a fraction of
// theirs (the ramp's mean weight, (1 - 1/F) / ln F, for F > 1).
// The mean keep weight F^-s of a density ramp over s in [0, 1] (1 without
// one): the fraction of the views' points kept when the dense end keeps all.
double rampKeptFraction(double densityVariation) {
  if (densityVariation <= 1.0) return 1.0;
  return (1.0 - 1.0 / densityVariation) / std::log(densityVariation);
}

// Points kept of `scanned` (every point when there is no density ramp).
std::size_t pointsToKeep(std::size_t scanned, double densityVariation) {
  return std::size_t(double(scanned) * rampKeptFraction(densityVariation));
}

// Points the views must give so that `wanted` can be kept with the density
// ramp (a 2 % margin with one).
std::size_t pointsToScan(std::size_t wanted, double densityVariation) {
  if (densityVariation <= 1.0) return wanted;
  return std::size_t(std::ceil(1.02 * double(wanted) / rampKeptFraction(densityVariation)));
}

// Keeps a random `count` of the scan's points, in their order. With a
// density ramp, a point at relative position s in [0, 1] along the box's
// longest side (of the surface points' box) is kept with a probability
// proportional to F^-s.
void keepSubset(ScannerScan& scan, std::size_t count, const ScannerOptions& o) {
  const std::size_t n = scan.cloud.size();
  if (count >= n) return;
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::mt19937_64 rng(mixSeed(o.seed, 2000));
  if (o.densityVariation > 1.0) {
    Aabb box;
    for (std::size_t k = 0; k < n; ++k) {
      if (scan.kinds[k] == ScanPointKind::Surface) box.extend(scan.cloud.points[k]);
    }
    int axis = 0;
    box.size().maxCoeff(&axis);
    const double lo = box.min[axis], span = std::max(box.size()[axis], 1e-300);
    const double logF = std::log(o.densityVariation);
    std::vector<double> weight(n);
    for (std::size_t k = 0; k < n; ++k) {
      const double s = std::clamp((scan.cloud.points[k][axis] - lo) / span, 0.0, 1.0);
      weight[k] = std::exp(-s * logF);
    }
    // Inclusion probabilities min(1, c w) summing to `count` (c by
    // bisection), then systematic sampling over a random order: exactly
    // those probabilities, so the kept density follows the ramp.
    const auto expected = [&](double c) {
      double sum = 0.0;
      for (double w : weight) sum += std::min(1.0, c * w);
      return sum;
    };
    double cLo = 0.0, cHi = 1.0;
    while (expected(cHi) < double(count)) cHi *= 2.0;
    for (int it = 0; it < 100; ++it) {
      const double mid = 0.5 * (cLo + cHi);
      (expected(mid) < double(count) ? cLo : cHi) = mid;
    }
    std::shuffle(order.begin(), order.end(), rng);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    double next = unit(rng), cumulative = 0.0;
    std::vector<std::size_t> chosen, rest;
    for (std::size_t k : order) {
      cumulative += std::min(1.0, cHi * weight[k]);
      if (cumulative >= next && chosen.size() < count) {
        chosen.push_back(k);
        next += 1.0;
      } else {
        rest.push_back(k);
      }
    }
    // Rounding can leave one short: the first of the rest (random order).
    for (std::size_t r = 0; chosen.size() < count && r < rest.size(); ++r) chosen.push_back(rest[r]);
    order = std::move(chosen);
  } else {
    for (std::size_t i = 0; i < count; ++i) {
      std::uniform_int_distribution<std::size_t> pick(i, n - 1);
      std::swap(order[i], order[pick(rng)]);
    }
  }
  order.resize(count);
  std::sort(order.begin(), order.end());
  ScannerScan kept;
  for (std::size_t k : order) {
    kept.cloud.points.push_back(scan.cloud.points[k]);
    if (scan.cloud.hasNormals()) kept.cloud.normals.push_back(scan.cloud.normals[k]);
    kept.kinds.push_back(scan.kinds[k]);
    kept.sensorOf.push_back(scan.sensorOf[k]);
  }
  scan.cloud = std::move(kept.cloud);
  scan.kinds = std::move(kept.kinds);
  scan.sensorOf = std::move(kept.sensorOf);
  scan.counts.kept = count;
}

}  // namespace

void ScannerOptions::validate() const {
  require(views >= 1 && views <= 10000, "views must be in [1, 10000], got " + std::to_string(views));
  require(!elevations.empty(), "elevations: at least one elevation is needed");
  for (double e : elevations) {
    require(std::isfinite(e) && e > 0.0 && e < 90.0,
            "elevation " + number(e) + " is not in (0, 90) degrees");
  }
  require(setups == 1 || setups == 2, "setups must be 1 or 2, got " + std::to_string(setups));
  require(std::isfinite(registrationTranslation) && registrationTranslation >= 0.0 &&
              registrationTranslation <= 1.0,
          "registration translation must be in [0, 1] (fraction of D)");
  require(std::isfinite(registrationRotation) && registrationRotation >= 0.0 &&
              registrationRotation <= 1.0,
          "registration rotation must be in [0, 1] radians");
  require(std::isfinite(depthNoise) && depthNoise >= 0.0 && depthNoise <= 1.0,
          "depth noise must be in [0, 1] (fraction of D)");
  require(std::isfinite(noiseIncidenceCap) && noiseIncidenceCap >= 1.0 &&
              noiseIncidenceCap <= 1e6,
          "noise incidence cap must be in [1, 1e6]");
  require(std::isfinite(maxIncidence) && maxIncidence > 0.0 && maxIncidence <= 90.0,
          "max incidence " + number(maxIncidence) + " is not in (0, 90] degrees");
  require(std::isfinite(mixedPixels) && mixedPixels >= 0.0 && mixedPixels <= 1.0,
          "mixed-pixel probability must be in [0, 1]");
  require(std::isfinite(depthEdge) && depthEdge > 0.0, "depth edge must be > 0 pixel footprints");
  require(std::isfinite(outliers) && outliers >= 0.0 && outliers <= 1.0,
          "outlier fraction must be in [0, 1]");
  require(std::isfinite(outlierMargin) && outlierMargin >= 0.0 && outlierMargin <= 10.0,
          "outlier margin must be in [0, 10] (fraction of D)");
  require(std::isfinite(fieldOfView) && fieldOfView > 0.0 && fieldOfView < 120.0,
          "field of view " + number(fieldOfView) + " is not in (0, 120) degrees");
  require(std::isfinite(standoff) && standoff >= 1.0 && standoff <= 100.0,
          "standoff must be in [1, 100]");
  require(std::isfinite(densityVariation) && densityVariation >= 1.0 && densityVariation <= 1000.0,
          "density variation must be in [1, 1000], got " + number(densityVariation));
  require(resolution >= 0 && resolution <= kMaxResolution,
          "resolution must be in [0, " + std::to_string(kMaxResolution) + "] pixels");
}

int ScannerScan::setupOf(std::uint32_t sensor) const {
  const std::size_t perSetup = sensors.size() / std::max<std::size_t>(registration.size(), 1);
  return perSetup == 0 ? 0 : int(sensor / perSetup);
}

ScannerScan scanPart(const RayCaster& caster, const ScannerOptions& options) {
  options.validate();
  const Aabb box = caster.bounds();
  require(box.isBounded() && !box.isEmpty(), "cannot scan a part without finite bounds");
  const double diagonal = box.diagonal();
  require(diagonal > 0.0, "cannot scan a part of size 0");
  Scene scene{caster, options, box, diagonal, 0.0, {}, {}};
  // Far enough that the bounding sphere fills the image, times the standoff.
  scene.range = options.standoff * 0.5 * diagonal / std::sin(0.5 * options.fieldOfView * kDegree);
  scene.setups = makeSetups(options, box, diagonal);
  scene.cameras = makeCameras(options, box, scene.range);

  const std::size_t kept = options.points;
  const std::size_t wanted = pointsToScan(kept, options.densityVariation);
  if (options.resolution > 0 || wanted == 0) {
    ScannerScan scan = scanAll(scene, options.resolution > 0 ? options.resolution : 256);
    if (scan.cloud.size() < kept) {
      throw std::invalid_argument("resolution " + std::to_string(scan.resolution) + " gives " +
                                  std::to_string(scan.cloud.size()) + " points, fewer than the " +
                                  std::to_string(kept) + " asked for");
    }
    keepSubset(scan, kept == 0 ? pointsToKeep(scan.cloud.size(), options.densityVariation) : kept,
               options);
    return scan;
  }
  // Points grow with the pixel count: size the image from a small run, then
  // grow it until the views give enough points.
  int side = kPilotResolution;
  ScannerScan scan = scanAll(scene, side);
  if (!scan.cloud.empty()) {
    const double grow = std::sqrt(1.05 * double(wanted) / double(scan.cloud.size()));
    const int sized = std::clamp(int(std::ceil(side * grow)), 8, kMaxResolution);
    if (sized != side) {
      side = sized;
      scan = scanAll(scene, side);
    }
  }
  while (scan.cloud.size() < wanted) {
    const double have = std::max<double>(double(scan.cloud.size()), 1.0);
    const double grow = std::clamp(std::sqrt(1.1 * double(wanted) / have), 1.1, 2.0);
    if (side >= kMaxResolution) {
      throw std::invalid_argument("the part gives too few points: " +
                                  std::to_string(scan.cloud.size()) + " at resolution " +
                                  std::to_string(side) + ", " + std::to_string(wanted) +
                                  " asked for");
    }
    side = std::min(int(std::ceil(side * grow)), kMaxResolution);
    scan = scanAll(scene, side);
  }
  keepSubset(scan, kept, options);
  return scan;
}

}  // namespace csgvox
