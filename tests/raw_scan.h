#pragma once
// Scanner-like raw scans of the bundled parts for tests: the face the part
// stood on unseen, 30 % of the part sampled ten times more sparsely, half
// the points seen again from a second setup registered with a small error
// (0.05 % of D, 0.0005 rad), Gaussian noise, mixed pixels behind silhouette
// points, and scattered outliers in the bounding box.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "io/tree_json.h"
#include "mesh/surface_sampler.h"

namespace csgvox::test {

/// What a raw scan holds.
struct RawScan {
  std::vector<Vec3> points;
  std::vector<Vec3> normals;  ///< true outward normals (zero for injected points)
  std::vector<int> kind;      ///< 0 surface, 1 scattered outlier, 2 mixed pixel
  double diagonal = 0.0;
  std::size_t count(int k) const { return std::size_t(std::count(kind.begin(), kind.end(), k)); }
};

/// Options of makeRawScan; fractions of D where they are lengths.
struct RawScanOptions {
  std::size_t points = 10000;  ///< points sampled before anything is removed or added
  double noise = 0.001;        ///< Gaussian noise sigma
  double outliers = 0.01;      ///< scattered outliers, fraction of the points
  double mixedPixels = 0.005;  ///< mixed pixels, fraction of the points
  bool unseenFace = true;      ///< drop the face the part stood on
  bool doubled = true;         ///< a second setup, slightly misregistered
  bool sparseRegion = true;    ///< 30 % of the part ten times more sparsely
  std::uint64_t seed = 1;
};

/// A raw scan of data/<part>/tree.json.
inline RawScan makeRawScan(const std::string& part, const RawScanOptions& o = {}) {
  const CsgTree tree =
      readTreeJson(std::filesystem::path(CSGVOX_DATA_DIR) / part / "tree.json");
  SampleOptions so;
  so.points = o.points;
  so.seed = o.seed;
  const SurfaceSample sample = sampleSurface(tree, so);
  const std::vector<Vec3>& p = sample.cloud.points;
  const std::vector<Vec3>& n = sample.cloud.normals;
  const double d = sample.diagonal;
  Aabb box;
  for (const Vec3& q : p) box.extend(q);
  std::mt19937_64 rng(o.seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> gauss(0.0, 1.0);
  // The face the part stood on: the box side with the most points facing it.
  int down = 0;
  std::size_t most = 0;
  for (int a = 0; a < 3; ++a) {
    std::size_t count = 0;
    for (std::size_t i = 0; i < p.size(); ++i) {
      count += p[i][a] < box.min[a] + 0.01 * d && n[i][a] < -0.9;
    }
    if (count > most) most = count, down = a;
  }
  int longest = 0;
  box.size().maxCoeff(&longest);
  RawScan raw;
  raw.diagonal = d;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (o.unseenFace && p[i][down] < box.min[down] + 0.01 * d) continue;
    const bool sparse = p[i][longest] < box.min[longest] + 0.3 * box.size()[longest];
    if (o.sparseRegion && sparse && unit(rng) >= 0.1) continue;
    raw.points.push_back(p[i]);
    raw.normals.push_back(n[i]);
    raw.kind.push_back(0);
  }
  if (o.doubled) {
    const Vec3 axis = Vec3(gauss(rng), gauss(rng), gauss(rng)).normalized();
    const Vec3 shift = 0.0005 * d * Vec3(gauss(rng), gauss(rng), gauss(rng)).normalized();
    const Eigen::AngleAxisd turn(0.0005, axis);
    const Vec3 centre = box.center();
    const std::size_t seen = raw.points.size();
    for (std::size_t i = 0; i < seen; ++i) {
      if (unit(rng) >= 0.5) continue;
      raw.points.push_back(centre + turn * (raw.points[i] - centre) + shift);
      raw.normals.push_back(turn * raw.normals[i]);
      raw.kind.push_back(0);
    }
  }
  for (Vec3& q : raw.points) q += o.noise * d * Vec3(gauss(rng), gauss(rng), gauss(rng));
  const std::size_t m = raw.points.size();
  const Vec3 view = Vec3(1.0, 0.5, 0.6).normalized();
  std::vector<std::size_t> silhouette;
  for (std::size_t i = 0; i < m; ++i) {
    if (std::abs(raw.normals[i].dot(view)) < 0.15) silhouette.push_back(i);
  }
  for (std::size_t c = 0; c < std::size_t(o.mixedPixels * double(m)) && !silhouette.empty();
       ++c) {
    const Vec3 edge = raw.points[silhouette[std::size_t(unit(rng) * double(silhouette.size()))]];
    raw.points.push_back(edge - view * d * (0.01 + 0.04 * unit(rng)));
    raw.normals.push_back(Vec3::Zero());
    raw.kind.push_back(2);
  }
  const Aabb around = box.grown(0.05 * d);
  for (std::size_t c = 0; c < std::size_t(o.outliers * double(m)); ++c) {
    const Vec3 u(unit(rng), unit(rng), unit(rng));
    raw.points.push_back(around.min + u.cwiseProduct(around.size()));
    raw.normals.push_back(Vec3::Zero());
    raw.kind.push_back(1);
  }
  return raw;
}

}  // namespace csgvox::test
