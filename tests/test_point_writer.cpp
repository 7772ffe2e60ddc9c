#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "io/errors.h"
#include "io/point_writer.h"
#include "io/scan_reader.h"
#include "temp_dir_test.h"

namespace csgvox {
namespace {

namespace fs = std::filesystem;

/// Points on a sphere with their outward normals.
PointCloud sphereCloud(std::size_t n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> gauss;
  PointCloud cloud;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 d = Vec3(gauss(rng), gauss(rng), gauss(rng)).normalized();
    cloud.points.push_back(Vec3(0.1, -20.0, 3.0) + 1.7 * d);
    cloud.normals.push_back(d);
  }
  return cloud;
}

std::string readFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

/// The data section of a PLY text (everything after "end_header\n").
std::string plyData(const std::string& ply) {
  const std::size_t at = ply.find("end_header\n");
  EXPECT_NE(at, std::string::npos);
  return ply.substr(at + 11);
}

/// Each coordinate of `a` equals `b` rounded to float.
void expectFloatRounded(const Vec3& a, const Vec3& b) {
  for (int i = 0; i < 3; ++i) EXPECT_EQ(a[i], static_cast<double>(static_cast<float>(b[i])));
}

class PointWriterTest : public test::TempDirTest {
 protected:
  /// Names of the files in the test directory.
  std::vector<std::string> listing() const {
    std::vector<std::string> names;
    for (const auto& entry : fs::directory_iterator(dir_)) names.push_back(entry.path().filename());
    std::sort(names.begin(), names.end());
    return names;
  }
};

const PointCloud kTwoPoints{{Vec3(1.5, -2.0, 3.25), Vec3(0.1, 1e-3, -7.0)},
                            {Vec3(0.0, 0.0, 1.0), Vec3(0.6, -0.8, 0.0)}};

TEST(PointWriter, WritesAsciiPly) {
  std::ostringstream out;
  writePointCloudPly(out, kTwoPoints, PlyEncoding::Ascii);
  EXPECT_EQ(out.str(),
            "ply\nformat ascii 1.0\ncomment written by csgvox\nelement vertex 2\n"
            "property float x\nproperty float y\nproperty float z\n"
            "property float nx\nproperty float ny\nproperty float nz\nend_header\n"
            "1.5 -2 3.25 0 0 1\n0.1 0.001 -7 0.6 -0.8 0\n");
}

TEST(PointWriter, WritesBinaryPlyInBothByteOrders) {
  const PointCloud cloud{{Vec3(1.5, -2.0, 3.25)}, {}};
  std::ostringstream little(std::ios::binary);
  writePointCloudPly(little, cloud, PlyEncoding::BinaryLittleEndian);
  EXPECT_NE(little.str().find("format binary_little_endian 1.0\n"), std::string::npos);
  EXPECT_EQ(little.str().find("property float nx"), std::string::npos);
  // 1.5f = 0x3FC00000, -2.0f = 0xC0000000, 3.25f = 0x40500000.
  EXPECT_EQ(plyData(little.str()),
            std::string("\x00\x00\xC0\x3F\x00\x00\x00\xC0\x00\x00\x50\x40", 12));
  std::ostringstream big(std::ios::binary);
  writePointCloudPly(big, cloud, PlyEncoding::BinaryBigEndian);
  EXPECT_NE(big.str().find("format binary_big_endian 1.0\n"), std::string::npos);
  EXPECT_EQ(plyData(big.str()),
            std::string("\x3F\xC0\x00\x00\xC0\x00\x00\x00\x40\x50\x00\x00", 12));
}

TEST(PointWriter, WritesColours) {
  const std::vector<Rgb8> colours = {{255, 0, 7}, {1, 2, 3}};
  std::ostringstream ascii;
  writePointCloudPly(ascii, kTwoPoints, colours, PlyEncoding::Ascii);
  EXPECT_NE(ascii.str().find("property float nz\nproperty uchar red\nproperty uchar green\n"
                             "property uchar blue\nend_header\n"),
            std::string::npos);
  EXPECT_EQ(plyData(ascii.str()), "1.5 -2 3.25 0 0 1 255 0 7\n0.1 0.001 -7 0.6 -0.8 0 1 2 3\n");

  std::ostringstream binary(std::ios::binary);
  writePointCloudPly(binary, kTwoPoints, colours);
  const std::string data = plyData(binary.str());
  ASSERT_EQ(data.size(), 2u * (6 * 4 + 3));
  EXPECT_EQ(data.substr(24, 3), std::string("\xFF\x00\x07", 3));
  EXPECT_EQ(data.substr(51, 3), std::string("\x01\x02\x03", 3));
}

TEST(PointWriter, WritesXyz) {
  std::ostringstream withNormals;
  writePointCloudXyz(withNormals, kTwoPoints);
  EXPECT_EQ(withNormals.str(), "1.5 -2 3.25 0 0 1\n0.1 0.001 -7 0.6 -0.8 0\n");
  std::ostringstream withoutNormals;
  writePointCloudXyz(withoutNormals, PointCloud{kTwoPoints.points, {}});
  EXPECT_EQ(withoutNormals.str(), "1.5 -2 3.25\n0.1 0.001 -7\n");
}

TEST(PointWriter, WritesEmptyCloud) {
  std::ostringstream out;
  writePointCloudPly(out, PointCloud{}, PlyEncoding::Ascii);
  EXPECT_NE(out.str().find("element vertex 0\n"), std::string::npos);
  EXPECT_EQ(plyData(out.str()), "");
}

TEST(PointWriter, RejectsMismatchedNormalsAndColours) {
  PointCloud bad = kTwoPoints;
  bad.normals.pop_back();
  std::ostringstream out;
  EXPECT_THROW(writePointCloudPly(out, bad), std::invalid_argument);
  EXPECT_THROW(writePointCloudXyz(out, bad), std::invalid_argument);
  const std::vector<Rgb8> oneColour = {{1, 2, 3}};
  EXPECT_THROW(writePointCloudPly(out, kTwoPoints, oneColour), std::invalid_argument);
}

TEST(PointWriter, ReportsAFailedStream) {
  std::ostringstream out;
  out.setstate(std::ios::badbit);
  EXPECT_THROW(writePointCloudPly(out, kTwoPoints), IoError);
  EXPECT_THROW(writePointCloudXyz(out, kTwoPoints), IoError);
}

TEST_F(PointWriterTest, PlyRoundTripsThroughTheReader) {
  const PointCloud cloud = sphereCloud(300, 5);
  const std::vector<std::pair<PlyEncoding, std::string>> encodings = {
      {PlyEncoding::Ascii, "ply-ascii"},
      {PlyEncoding::BinaryLittleEndian, "ply-binary-le"},
      {PlyEncoding::BinaryBigEndian, "ply-binary-be"}};
  for (const auto& [encoding, format] : encodings) {
    SCOPED_TRACE(format);
    const fs::path path = dir_ / "cloud.ply";
    writePointCloudPly(path, cloud, encoding);
    const Scan scan = readScan(path);
    EXPECT_EQ(scan.info.format, format);
    EXPECT_FALSE(scan.info.normalsEstimated);
    ASSERT_EQ(scan.cloud.size(), cloud.size());
    for (std::size_t i = 0; i < cloud.size(); ++i) {
      expectFloatRounded(scan.cloud.points[i], cloud.points[i]);
      EXPECT_NEAR((scan.cloud.normals[i] - cloud.normals[i]).norm(), 0.0, 1e-6);
    }
  }
  EXPECT_EQ(listing(), std::vector<std::string>{"cloud.ply"});  // no temporary files left
}

TEST_F(PointWriterTest, PlyWithoutNormalsRoundTrips) {
  const PointCloud full = sphereCloud(1000, 6);
  const fs::path path = dir_ / "points.ply";
  writePointCloudPly(path, PointCloud{full.points, {}});
  EXPECT_EQ(readFile(path).find("property float nx"), std::string::npos);
  const Scan scan = readScan(path);
  EXPECT_TRUE(scan.info.normalsEstimated);
  ASSERT_EQ(scan.cloud.size(), full.size());
  std::size_t agreeing = 0;
  for (std::size_t i = 0; i < full.size(); ++i) {
    expectFloatRounded(scan.cloud.points[i], full.points[i]);
    if (scan.cloud.normals[i].dot(full.normals[i]) > 0.9) ++agreeing;
  }
  EXPECT_GT(agreeing, 950u);
}

TEST_F(PointWriterTest, ColouredPlyRoundTrips) {
  const PointCloud cloud = sphereCloud(200, 7);
  std::vector<Rgb8> colours;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    colours.push_back({static_cast<std::uint8_t>(i), static_cast<std::uint8_t>(255 - i), 9});
  }
  const fs::path path = dir_ / "segments.ply";
  writePointCloudPly(path, cloud, colours);
  const std::string data = plyData(readFile(path));
  ASSERT_EQ(data.size(), cloud.size() * 27);
  EXPECT_EQ(static_cast<std::uint8_t>(data[27 * 100 + 24]), 100);
  EXPECT_EQ(static_cast<std::uint8_t>(data[27 * 100 + 25]), 155);
  const Scan scan = readScan(path);
  ASSERT_EQ(scan.cloud.size(), cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i)
    expectFloatRounded(scan.cloud.points[i], cloud.points[i]);
}

TEST_F(PointWriterTest, XyzRoundTripsExactly) {
  const PointCloud cloud = sphereCloud(300, 8);
  const fs::path path = dir_ / "cloud.xyz";
  writePointCloudXyz(path, cloud);
  const Scan scan = readScan(path);
  EXPECT_EQ(scan.info.format, "xyzn");
  EXPECT_EQ(scan.cloud.points, cloud.points);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    EXPECT_NEAR((scan.cloud.normals[i] - cloud.normals[i]).norm(), 0.0, 1e-15);
  }

  writePointCloudXyz(path, PointCloud{cloud.points, {}});
  const Scan bare = readScan(path);
  EXPECT_EQ(bare.info.format, "xyz");
  EXPECT_TRUE(bare.info.normalsEstimated);
  EXPECT_EQ(bare.cloud.points, cloud.points);
}

TEST_F(PointWriterTest, FailedWritesLeaveNoFile) {
  const fs::path path = dir_ / "keep.ply";
  { std::ofstream(path) << "old content"; }
  PointCloud bad = kTwoPoints;
  bad.normals.pop_back();
  EXPECT_THROW(writePointCloudPly(path, bad), std::invalid_argument);
  EXPECT_THROW(writePointCloudXyz(path, bad), std::invalid_argument);
  const std::vector<Rgb8> oneColour = {{1, 2, 3}};
  EXPECT_THROW(writePointCloudPly(path, kTwoPoints, oneColour), std::invalid_argument);
  EXPECT_EQ(readFile(path), "old content");
  EXPECT_EQ(listing(), std::vector<std::string>{"keep.ply"});

  const fs::path nowhere = dir_ / "missing_dir" / "cloud.ply";
  try {
    writePointCloudPly(nowhere, kTwoPoints);
    FAIL() << "no exception";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find(nowhere.string()), std::string::npos) << e.what();
  }
  fs::create_directories(dir_ / "folder.xyz");
  EXPECT_THROW(writePointCloudXyz(dir_ / "folder.xyz", kTwoPoints), IoError);
}

}  // namespace
}  // namespace csgvox
