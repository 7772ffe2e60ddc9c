// Detection on normals estimated from raw points: near sharp edges they
// blend the two faces, and without DetectOptions::estimatedNormals the later
// RANSAC stages explain those strips by small spurious surfaces.

#include <gtest/gtest.h>

#include "io/tree_json.h"
#include "mesh/surface_sampler.h"
#include "part_list.h"
#include "primitives/normal_estimation.h"
#include "primitives/surface_detection.h"

namespace csgvox {
namespace {

// 20 000 points of a bundled part, normals dropped and estimated again.
PointCloud rawSample(const std::string& part) {
  SampleOptions so;
  so.points = 20000;
  PointCloud cloud = sampleSurface(readTreeJson(test::dataDir() / part / "tree.json"), so).cloud;
  cloud.normals.clear();
  estimateNormals(cloud, 18);
  return cloud;
}

TEST(DetectionOnEstimatedNormals, EdgeStripsDoNotBecomeSpuriousSurfaces) {
  const PointCloud cloud = rawSample("l_bracket");
  DetectOptions trusting;
  const DetectionResult plain = detectSurfaces(cloud, trusting);
  DetectOptions estimated;
  estimated.estimatedNormals = true;
  const DetectionResult raw = detectSurfaces(cloud, estimated);
  ASSERT_TRUE(raw.ok()) << raw.message;
  // Its 7 primitives have 13 faces (9 planes, 4 cylinders), as exact
  // normals give; trusting the estimated normals gives three times as many.
  EXPECT_LE(raw.surfaces.size(), 15u) << raw.message;
  EXPECT_GT(plain.surfaces.size(), raw.surfaces.size() + 10) << plain.message;
  std::size_t planes = 0;
  for (const Surface& s : raw.surfaces) planes += s.type() == SurfaceType::Plane;
  EXPECT_GE(planes, 9u) << raw.message;
}

// Given normals are trusted as before: the flag only matters for estimated
// ones, and a scan with exact normals gives the same surfaces either way
// when nothing is left over.
TEST(DetectionOnEstimatedNormals, ExactNormalsGiveTheSameSurfaces) {
  SampleOptions so;
  so.points = 10000;
  const PointCloud cloud =
      sampleSurface(readTreeJson(test::dataDir() / "plate_holes" / "tree.json"), so).cloud;
  DetectOptions estimated;
  estimated.estimatedNormals = true;
  const DetectionResult a = detectSurfaces(cloud);
  const DetectionResult b = detectSurfaces(cloud, estimated);
  ASSERT_EQ(a.surfaces.size(), b.surfaces.size());
  for (std::size_t i = 0; i < a.surfaces.size(); ++i) {
    EXPECT_EQ(a.surfaces[i].inliers, b.surfaces[i].inliers) << i;
  }
}

}  // namespace
}  // namespace csgvox
