#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "io/errors.h"
#include "io/scan_reader.h"
#include "part_list.h"
#include "primitives/normal_estimation.h"
#include "temp_dir_test.h"

namespace csgvox {
namespace {

namespace fs = std::filesystem;

// ---------------------------------------------------------------------------
// Synthetic shapes with their true outward normals.

struct Sample {
  std::vector<Vec3> points;
  std::vector<Vec3> normals;
};

Sample samplePoints(std::size_t n, const Vec3& center, double radius, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> gauss;
  Sample s;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 d = Vec3(gauss(rng), gauss(rng), gauss(rng)).normalized();
    s.points.push_back(center + radius * d);
    s.normals.push_back(d);
  }
  return s;
}

/// Points on the surface of an axis-aligned box, uniform by area.
Sample boxPoints(std::size_t n, const Vec3& center, const Vec3& half, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  const std::array<double, 3> faceArea = {half.y() * half.z(), half.x() * half.z(),
                                          half.x() * half.y()};
  std::discrete_distribution<int> pickAxis(faceArea.begin(), faceArea.end());
  Sample s;
  for (std::size_t i = 0; i < n; ++i) {
    const int axis = pickAxis(rng);
    const double sign = uniform(rng) < 0.0 ? -1.0 : 1.0;
    Vec3 local(uniform(rng), uniform(rng), uniform(rng));
    local[axis] = sign;
    s.points.push_back(center + local.cwiseProduct(half));
    Vec3 normal = Vec3::Zero();
    normal[axis] = sign;
    s.normals.push_back(normal);
  }
  return s;
}

/// Fraction of normals within ~25 degrees of the true ones.
double agreeingFraction(const std::vector<Vec3>& estimated, const std::vector<Vec3>& truth) {
  EXPECT_EQ(estimated.size(), truth.size());
  std::size_t good = 0;
  for (std::size_t i = 0; i < std::min(estimated.size(), truth.size()); ++i) {
    if (estimated[i].dot(truth[i]) > 0.9) ++good;
  }
  return static_cast<double>(good) / static_cast<double>(truth.size());
}

void expectUnitNormals(const PointCloud& cloud) {
  ASSERT_TRUE(cloud.hasNormals());
  for (const Vec3& n : cloud.normals) ASSERT_NEAR(n.norm(), 1.0, 1e-9);
}

void expectNear(const Vec3& a, const Vec3& b, double tolerance) {
  EXPECT_NEAR(a.x(), b.x(), tolerance);
  EXPECT_NEAR(a.y(), b.y(), tolerance);
  EXPECT_NEAR(a.z(), b.z(), tolerance);
}

// ---------------------------------------------------------------------------
// File builders.

enum class Data { Ascii, LittleEndian, BigEndian };

template <class T>
void appendBinary(std::string& out, T value, bool bigEndian) {
  std::array<char, sizeof(T)> bytes;
  std::memcpy(bytes.data(), &value, sizeof(T));
  if (bigEndian) std::reverse(bytes.begin(), bytes.end());
  out.append(bytes.data(), bytes.size());
}

std::string number(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

struct PlyOptions {
  Data data = Data::Ascii;
  bool useDouble = false;
  bool withNormals = true;
  bool extraProperties = false;  // interleaved confidence, colour, label and a list
};

/// A PLY point cloud. With extra properties the vertex layout is
/// confidence x red y z [nx label ny nz] ids(list).
std::string makePly(const Sample& s, const PlyOptions& o) {
  const char* type = o.useDouble ? "double" : "float";
  std::string text = "ply\nformat ";
  text += o.data == Data::Ascii          ? "ascii"
          : o.data == Data::LittleEndian ? "binary_little_endian"
                                         : "binary_big_endian";
  text += " 1.0\ncomment synthetic\nelement vertex " + std::to_string(s.points.size()) + "\n";
  auto prop = [&](const std::string& t, const std::string& name) {
    text += "property " + t + " " + name + "\n";
  };
  if (o.extraProperties) prop("float", "confidence");
  prop(type, "x");
  if (o.extraProperties) prop("uchar", "red");
  prop(type, "y");
  prop(type, "z");
  if (o.withNormals) {
    prop(type, "nx");
    if (o.extraProperties) prop("int", "label");
    prop(type, "ny");
    prop(type, "nz");
  }
  if (o.extraProperties) text += "property list uchar int ids\n";
  text += "element face 0\nproperty list uchar int vertex_indices\nend_header\n";

  const bool be = o.data == Data::BigEndian;
  for (std::size_t i = 0; i < s.points.size(); ++i) {
    std::vector<std::pair<char, double>> row;  // 'f' coordinate, 'c' float, 'u' uchar, 'i' int
    const Vec3& p = s.points[i];
    if (o.extraProperties) row.push_back({'c', 0.25});
    row.push_back({'f', p.x()});
    if (o.extraProperties) row.push_back({'u', 200});
    row.push_back({'f', p.y()});
    row.push_back({'f', p.z()});
    if (o.withNormals) {
      const Vec3& n = s.normals[i];
      row.push_back({'f', n.x()});
      if (o.extraProperties) row.push_back({'i', -7});
      row.push_back({'f', n.y()});
      row.push_back({'f', n.z()});
    }
    if (o.extraProperties) {  // a list of two ints
      row.push_back({'u', 2});
      row.push_back({'i', 11});
      row.push_back({'i', 12});
    }
    if (o.data == Data::Ascii) {
      for (std::size_t v = 0; v < row.size(); ++v) {
        if (v > 0) text += ' ';
        text += number(row[v].second);
      }
      text += "\n";
    } else {
      for (const auto& [kind, value] : row) {
        if (kind == 'f' && o.useDouble) appendBinary(text, value, be);
        if (kind == 'f' && !o.useDouble) appendBinary(text, static_cast<float>(value), be);
        if (kind == 'c') appendBinary(text, static_cast<float>(value), be);
        if (kind == 'u') text.push_back(static_cast<char>(static_cast<std::uint8_t>(value)));
        if (kind == 'i') appendBinary(text, static_cast<std::int32_t>(value), be);
      }
    }
  }
  return text;
}

/// "x y z" with every digit needed to read back the same doubles.
std::string coordinates(const Vec3& v) {
  std::string text = number(v.x());
  text += ' ';
  text += number(v.y());
  text += ' ';
  text += number(v.z());
  return text;
}

std::string makeXyz(const Sample& s, bool withNormals) {
  std::string text;
  for (std::size_t i = 0; i < s.points.size(); ++i) {
    text += coordinates(s.points[i]);
    if (withNormals) {
      text += ' ';
      text += coordinates(s.normals[i]);
    }
    text += '\n';
  }
  return text;
}

/// A box mesh: 8 corners, 6 quads counter-clockwise seen from outside.
struct BoxMesh {
  Vec3 center;
  Vec3 half;
  std::vector<Vec3> vertices;
  std::vector<std::vector<int>> faces;

  explicit BoxMesh(const Vec3& c = Vec3(10.0, -5.0, 3.0), const Vec3& h = Vec3(2.0, 1.0, 0.5))
      : center(c), half(h) {
    const int corners[8][3] = {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1},
                               {-1, -1, 1},  {1, -1, 1},  {1, 1, 1},  {-1, 1, 1}};
    for (const auto& c : corners) {
      vertices.push_back(center + Vec3(c[0], c[1], c[2]).cwiseProduct(half));
    }
    faces = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4}, {2, 3, 7, 6}, {0, 4, 7, 3}, {1, 2, 6, 5}};
  }
  std::vector<std::array<int, 3>> triangles() const {
    std::vector<std::array<int, 3>> t;
    for (const auto& f : faces) {
      t.push_back({f[0], f[1], f[2]});
      t.push_back({f[0], f[2], f[3]});
    }
    return t;
  }
  void reverseFace(std::size_t f) { std::reverse(faces[f].begin(), faces[f].end()); }
};

std::string makeOff(const BoxMesh& m) {
  std::string text = "OFF\n# a box\n";
  text += std::to_string(m.vertices.size());
  text += ' ';
  text += std::to_string(m.faces.size());
  text += " 0\n";
  for (const Vec3& v : m.vertices) {
    text += coordinates(v);
    text += '\n';
  }
  for (const auto& f : m.faces) {
    text += std::to_string(f.size());
    for (int i : f) {
      text += ' ';
      text += std::to_string(i);
    }
    text += '\n';
  }
  return text;
}

std::string makeObj(const BoxMesh& m) {
  std::string text = "# box\r\nmtllib box.mtl\r\no box\r\n";
  for (const Vec3& v : m.vertices) {
    text += "v ";
    text += coordinates(v);
    text += "\r\n";
  }
  text += "vn 0 0 1\r\nvt 0 0\r\ng sides\r\nusemtl steel\r\ns off\r\n";
  for (std::size_t f = 0; f < m.faces.size(); ++f) {
    text += "f";
    for (int i : m.faces[f]) {
      // Mixed index styles and separators, as exporters write them.
      text += f % 2 ? '\t' : ' ';
      text += std::to_string(i + 1);
      text += f % 3 == 0 ? "/1/1" : "//1";
    }
    text += "\r\n";
  }
  return text;
}

std::string makeAsciiStl(const BoxMesh& m) {
  std::string text = "solid box\n";
  for (const auto& t : m.triangles()) {
    text += "  facet normal 0 0 0\n    outer loop\n";
    for (int i : t) {
      const Vec3& v = m.vertices[i];
      text += "      vertex ";
      text += coordinates(v);
      text += '\n';
    }
    text += "    endloop\n  endfacet\n";
  }
  return text + "endsolid box\n";
}

std::string makeBinaryStl(const BoxMesh& m, const std::string& headerText = "binary box") {
  std::string text = headerText;
  text.resize(80, ' ');
  const auto triangles = m.triangles();
  appendBinary(text, static_cast<std::uint32_t>(triangles.size()), false);
  for (const auto& t : triangles) {
    for (int i = 0; i < 3; ++i) appendBinary(text, 0.0f, false);
    for (int i : t) {
      for (int a = 0; a < 3; ++a) appendBinary(text, static_cast<float>(m.vertices[i][a]), false);
    }
    appendBinary(text, std::uint16_t{0}, false);
  }
  return text;
}

/// A PLY mesh; `intLengths` writes the face lists with int lengths.
std::string makePlyMesh(const BoxMesh& m, Data data, bool intLengths = false) {
  std::string text = "ply\nformat ";
  text += data == Data::Ascii ? "ascii" : "binary_little_endian";
  text +=
      " 1.0\nelement vertex 8\nproperty float x\nproperty float y\nproperty "
      "float z\nproperty float nx\nproperty float ny\nproperty float nz\n"
      "element face 6\nproperty list ";
  text += intLengths ? "int" : "uchar";
  text += " int vertex_indices\nend_header\n";
  for (const Vec3& v : m.vertices) {
    if (data == Data::Ascii) {
      text += coordinates(v);
      text += " 0 0 1\n";
    } else {
      for (int a = 0; a < 3; ++a) appendBinary(text, static_cast<float>(v[a]), false);
      for (float n : {0.0f, 0.0f, 1.0f}) appendBinary(text, n, false);
    }
  }
  for (const auto& f : m.faces) {
    if (data == Data::Ascii) {
      text += '4';
      for (int i : f) {
        text += ' ';
        text += std::to_string(i);
      }
      text += '\n';
    } else {
      if (intLengths) {
        appendBinary(text, std::int32_t{4}, false);
      } else {
        text.push_back(4);
      }
      for (int i : f) appendBinary(text, static_cast<std::int32_t>(i), false);
    }
  }
  return text;
}

// ---------------------------------------------------------------------------

class ScanReaderTest : public test::TempDirTest {
 protected:
  /// Reads `path` expecting exception E whose single-line message names
  /// the file and contains `keyword`. Also checks nothing reached stderr.
  template <class E>
  void expectError(const fs::path& path, const std::string& keyword,
                   const ReadOptions& options = {}) {
    SCOPED_TRACE(path.filename().string());
    ::testing::internal::CaptureStderr();
    std::string message;
    bool rightType = false;
    try {
      readScan(path, options);
    } catch (const E& e) {
      rightType = true;
      message = e.what();
    } catch (const std::exception& e) {
      message = std::string("wrong exception type: ") + e.what();
    }
    const std::string err = ::testing::internal::GetCapturedStderr();
    EXPECT_TRUE(rightType) << (message.empty() ? "no exception" : message);
    EXPECT_NE(message.find(path.filename().string()), std::string::npos) << message;
    EXPECT_NE(message.find(keyword), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    EXPECT_EQ(err, "") << "the reader printed to stderr";
  }

  /// Checks that every point of a scan of BoxMesh lies on a face and
  /// carries that face's outward normal.
  static void expectOnBoxWithOutwardNormals(const PointCloud& cloud, const BoxMesh& m) {
    ASSERT_TRUE(cloud.hasNormals());
    std::size_t onZ = 0;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
      const Vec3& n = cloud.normals[i];
      int axis = 0;
      n.cwiseAbs().maxCoeff(&axis);
      ASSERT_NEAR(std::abs(n[axis]), 1.0, 1e-9) << "normal not axis-aligned: " << n.transpose();
      const Vec3 local = (cloud.points[i] - m.center).cwiseQuotient(m.half);
      ASSERT_NEAR(local[axis], n[axis], 1e-9)
          << "point " << i << " not on the face its normal names";
      ASSERT_LE(local.cwiseAbs().maxCoeff(), 1.0 + 1e-9);
      if (axis == 2) ++onZ;
    }
    // Area weighting: the ±z faces hold 16 of the box's 28 area units.
    EXPECT_NEAR(static_cast<double>(onZ) / static_cast<double>(cloud.size()), 16.0 / 28.0, 0.03);
  }
};

// ---------------------------------------------------------------------------
// Point clouds.

TEST_F(ScanReaderTest, ReadsEveryPlyEncodingAndPrecision) {
  const Sample s = samplePoints(150, Vec3(1.0, -2.0, 0.5), 3.0, 7);
  const std::vector<std::pair<Data, std::string>> datas = {{Data::Ascii, "ply-ascii"},
                                                           {Data::LittleEndian, "ply-binary-le"},
                                                           {Data::BigEndian, "ply-binary-be"}};
  for (const auto& [data, format] : datas) {
    for (bool useDouble : {false, true}) {
      for (bool extras : {false, true}) {
        SCOPED_TRACE(format + (useDouble ? " double" : " float") + (extras ? " extras" : ""));
        const fs::path path = write("cloud.ply", makePly(s, {data, useDouble, true, extras}));
        const Scan scan = readScan(path);
        EXPECT_EQ(scan.info.format, format);
        EXPECT_FALSE(scan.info.fromMesh);
        EXPECT_FALSE(scan.info.normalsEstimated);
        EXPECT_EQ(scan.info.pointsRead, 150u);
        ASSERT_EQ(scan.cloud.size(), 150u);
        ASSERT_TRUE(scan.cloud.hasNormals());
        const double tolerance = useDouble ? 1e-12 : 1e-6;
        for (std::size_t i = 0; i < s.points.size(); ++i) {
          expectNear(scan.cloud.points[i], s.points[i], tolerance * 4.0);
          expectNear(scan.cloud.normals[i], s.normals[i], tolerance);
        }
      }
    }
  }
}

// Binary files whose rows have a fixed size are read in one block; the
// values are those CGAL's reader gives (here, on the same data with a list
// in each row), bit for bit, after an element of other fixed rows too.
TEST_F(ScanReaderTest, FixedSizeBinaryRowsReadAsCgalReadsThem) {
  const Sample s = samplePoints(120, Vec3(1.0, -2.0, 0.5), 3.0, 9);
  for (const Data data : {Data::LittleEndian, Data::BigEndian}) {
    for (const bool useDouble : {false, true}) {
      SCOPED_TRACE(std::string(data == Data::BigEndian ? "be" : "le") +
                   (useDouble ? " double" : " float"));
      const bool be = data == Data::BigEndian;
      const std::string type = useDouble ? "double" : "float";
      std::string text =
          std::string("ply\nformat ") + (be ? "binary_big_endian" : "binary_little_endian") +
          " 1.0\nelement camera 2\nproperty float a\nproperty uchar b\n" + "element vertex " +
          std::to_string(s.points.size()) + "\nproperty float confidence\nproperty " + type +
          " x\nproperty uchar red\nproperty " + type + " y\nproperty " + type + " z\nproperty " +
          type + " nx\nproperty int label\nproperty " + type + " ny\nproperty " + type +
          " nz\nend_header\n";
      for (int c = 0; c < 2; ++c) {
        appendBinary(text, 1.5f, be);
        appendBinary(text, std::uint8_t(7), be);
      }
      const auto coordinate = [&](double v) {
        if (useDouble) {
          appendBinary(text, v, be);
        } else {
          appendBinary(text, float(v), be);
        }
      };
      for (std::size_t i = 0; i < s.points.size(); ++i) {
        appendBinary(text, 0.25f, be);
        coordinate(s.points[i].x());
        appendBinary(text, std::uint8_t(200), be);
        coordinate(s.points[i].y());
        coordinate(s.points[i].z());
        coordinate(s.normals[i].x());
        appendBinary(text, std::int32_t(-7), be);
        coordinate(s.normals[i].y());
        coordinate(s.normals[i].z());
      }
      const Scan fixed = readScan(write("fixed.ply", text));
      const Scan cgal = readScan(write("lists.ply", makePly(s, {data, useDouble, true, true})));
      ASSERT_EQ(fixed.cloud.size(), s.points.size());
      ASSERT_EQ(cgal.cloud.size(), s.points.size());
      for (std::size_t i = 0; i < s.points.size(); ++i) {
        ASSERT_EQ(fixed.cloud.points[i], cgal.cloud.points[i]) << i;
        ASSERT_EQ(fixed.cloud.normals[i], cgal.cloud.normals[i]) << i;
      }
      // Cut inside the vertex rows: one line naming the file.
      expectError<ParseError>(write("cut.ply", text.substr(0, text.size() - 10)), "cut.ply");
    }
  }
}

TEST_F(ScanReaderTest, NormalisesGivenNormals) {
  Sample s = samplePoints(120, Vec3::Zero(), 1.0, 3);
  for (std::size_t i = 0; i < s.normals.size(); ++i) s.normals[i] *= 0.1 + static_cast<double>(i);
  const Scan scan = readScan(write("long_normals.ply", makePly(s, {Data::LittleEndian, true})));
  expectUnitNormals(scan.cloud);
  for (std::size_t i = 0; i < s.points.size(); ++i) {
    expectNear(scan.cloud.normals[i], s.normals[i].normalized(), 1e-12);
  }
}

TEST_F(ScanReaderTest, EstimatesNormalsForPlyWithoutThem) {
  const Sample s = samplePoints(2000, Vec3(0.5, 0.5, 0.5), 2.0, 11);
  for (Data data : {Data::Ascii, Data::BigEndian}) {
    const Scan scan = readScan(write("no_normals.ply", makePly(s, {data, false, false, true})));
    EXPECT_TRUE(scan.info.normalsEstimated);
    ASSERT_EQ(scan.cloud.size(), s.points.size());
    expectUnitNormals(scan.cloud);
    EXPECT_GT(agreeingFraction(scan.cloud.normals, s.normals), 0.95);
  }
}

TEST_F(ScanReaderTest, ReadsXyzWithoutNormals) {
  const Sample s = samplePoints(1500, Vec3(-3.0, 2.0, 1.0), 0.5, 5);
  // A count line, comments, blank lines, CRLF and tabs.
  std::string text = "1500\r\n# exported\r\n\r\n";
  std::string body = makeXyz(s, false);
  std::replace(body.begin(), body.begin() + 40, ' ', '\t');
  for (char c : body) text += c == '\n' ? std::string("\r\n") : std::string(1, c);
  text += "\r\n   \r\n";
  const Scan scan = readScan(write("scan.xyz", text));
  EXPECT_EQ(scan.info.format, "xyz");
  EXPECT_TRUE(scan.info.normalsEstimated);
  EXPECT_EQ(scan.info.pointsRead, 1500u);
  ASSERT_EQ(scan.cloud.size(), 1500u);
  for (std::size_t i = 0; i < s.points.size(); ++i) {
    ASSERT_EQ(scan.cloud.points[i], s.points[i]);  // text with 17 digits is exact
  }
  EXPECT_GT(agreeingFraction(scan.cloud.normals, s.normals), 0.95);
}

TEST_F(ScanReaderTest, ReadsXyzWithNormals) {
  const Sample s = samplePoints(200, Vec3(0.0, 0.0, 7.0), 1.5, 9);
  for (const char* name : {"scan.xyz", "scan.XYZN"}) {
    const Scan scan = readScan(write(name, "# x y z nx ny nz\n" + makeXyz(s, true)));
    EXPECT_EQ(scan.info.format, "xyzn");
    EXPECT_FALSE(scan.info.normalsEstimated);
    ASSERT_EQ(scan.cloud.size(), 200u);
    for (std::size_t i = 0; i < s.points.size(); ++i) {
      ASSERT_EQ(scan.cloud.points[i], s.points[i]);
      expectNear(scan.cloud.normals[i], s.normals[i], 1e-15);
    }
  }
}

TEST_F(ScanReaderTest, ReplacesNormalsThatDisagreeWithTheSurface) {
  // The bundled flange with every normal turned in a random direction:
  // detection found nothing in them, after half a minute. The reader sees
  // that they disagree with the surface and estimates them instead.
  const Scan truth = readScan(fs::path(CSGVOX_DATA_DIR) / "flange" / "scan.ply");
  Sample s{truth.cloud.points, truth.cloud.normals};
  std::mt19937_64 rng(5);
  std::normal_distribution<double> gauss;
  for (Vec3& n : s.normals) n = Vec3(gauss(rng), gauss(rng), gauss(rng)).normalized();
  const fs::path path = write("random_normals.ply", makePly(s, {Data::LittleEndian, true}));
  const Scan scan = readScan(path);
  EXPECT_TRUE(scan.info.normalsReplaced);
  EXPECT_TRUE(scan.info.normalsEstimated);
  EXPECT_LT(scan.info.normalAgreement, 0.2);
  ASSERT_EQ(scan.cloud.size(), truth.cloud.size());
  EXPECT_GT(agreeingFraction(scan.cloud.normals, truth.cloud.normals), 0.9);
  // Asked to, the reader keeps them.
  ReadOptions keep;
  keep.minNormalAgreement = 0.0;
  const Scan kept = readScan(path, keep);
  EXPECT_FALSE(kept.info.normalsReplaced);
  EXPECT_FALSE(kept.info.normalsEstimated);
  EXPECT_EQ(kept.info.normalAgreement, scan.info.normalAgreement);
  EXPECT_GT(agreeingFraction(kept.cloud.normals, s.normals), 0.999);
  keep.minNormalAgreement = 1.5;
  EXPECT_THROW(readScan(path, keep), std::invalid_argument);
}

TEST_F(ScanReaderTest, KeepsTheNormalsOfEveryBundledScan) {
  // Sampled normals, clean and noisy, thin walls included: the given
  // normals agree with the surface on at least 72 % of the points (noisy
  // stepped_shaft the least; random normals 13-18 %), and are kept as given.
  std::vector<fs::path> scans;
  for (const auto& part : test::partNames()) {
    scans.push_back(test::dataDir() / part / "scan.ply");
    scans.push_back(test::dataDir() / part / "scan_noisy.ply");
  }
  for (const char* part : {"pin_base", "sheet_bracket", "slotted_plate", "thin_tray"}) {
    scans.push_back(test::dataDir() / "thin" / part / "scan.ply");
    scans.push_back(test::dataDir() / "thin" / part / "scan_noisy.ply");
  }
  for (const fs::path& path : scans) {
    SCOPED_TRACE(path.string());
    const Scan scan = readScan(path);
    EXPECT_FALSE(scan.info.normalsReplaced);
    EXPECT_FALSE(scan.info.normalsEstimated);
    EXPECT_GT(scan.info.normalAgreement, 0.7);
  }
}

TEST_F(ScanReaderTest, ExtensionIsCaseInsensitive) {
  const Sample s = samplePoints(100, Vec3::Zero(), 1.0, 1);
  EXPECT_EQ(readScan(write("UPPER.PLY", makePly(s, {}))).cloud.size(), 100u);
  EXPECT_EQ(scanFileTypeFromPath("a/b.Stl"), ScanFileType::Stl);
  EXPECT_EQ(scanFileTypeFromPath("a/b.xyzn"), ScanFileType::Xyz);
}

TEST_F(ScanReaderTest, ReadsFromStream) {
  const Sample s = samplePoints(130, Vec3::Zero(), 1.0, 4);
  std::istringstream in(makePly(s, {Data::LittleEndian, false, true, false}));
  const Scan scan = readScan(in, ScanFileType::Ply, "memory");
  EXPECT_EQ(scan.cloud.size(), 130u);
  std::istringstream bad("ply\nformat ascii 1.0\n");
  try {
    readScan(bad, ScanFileType::Ply, "memory-scan");
    FAIL() << "no exception";
  } catch (const ParseError& e) {
    EXPECT_NE(std::string(e.what()).find("memory-scan"), std::string::npos);
  }
}

// ---------------------------------------------------------------------------
// Meshes.

TEST_F(ScanReaderTest, SamplesEveryMeshFormat) {
  const BoxMesh m;
  // Counts on the keyword line, colours after coordinates and faces, comments.
  std::string variantOff = makeOff(m);
  variantOff.replace(0, variantOff.find(" 0\n") + 3, "COFF 8 6 0 # counts\n");
  std::string coloured;
  for (std::size_t at = 0, end; (end = variantOff.find('\n', at)) != std::string::npos;
       at = end + 1) {
    coloured += variantOff.substr(at, end - at);
    coloured += at == 0 ? "\n" : " 0.5 0.5 0.5 1\n";
  }
  variantOff = coloured;
  struct Case {
    std::string name, content, format;
    std::size_t faces, vertices;
  };
  const std::vector<Case> cases = {
      {"box.off", makeOff(m), "off-mesh", 6, 8},
      {"box.obj", makeObj(m), "obj-mesh", 6, 8},
      {"box.stl", makeAsciiStl(m), "stl-ascii-mesh", 12, 8},
      {"box_binary.stl", makeBinaryStl(m), "stl-binary-mesh", 12, 8},
      {"box_solid_header.stl", makeBinaryStl(m, "solid box exported by CAD"), "stl-binary-mesh", 12,
       8},
      {"box_ascii.ply", makePlyMesh(m, Data::Ascii), "ply-ascii-mesh", 6, 8},
      {"box_binary.ply", makePlyMesh(m, Data::LittleEndian), "ply-binary-le-mesh", 6, 8},
      {"box_int_lengths.ply", makePlyMesh(m, Data::LittleEndian, true), "ply-binary-le-mesh", 6, 8},
      {"box_int_lengths_ascii.ply", makePlyMesh(m, Data::Ascii, true), "ply-ascii-mesh", 6, 8},
      {"box_variant.off", variantOff, "off-mesh", 6, 8},
  };
  ReadOptions options;
  options.meshSamples = 4000;
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const Scan scan = readScan(write(c.name, c.content), options);
    EXPECT_EQ(scan.info.format, c.format);
    EXPECT_TRUE(scan.info.fromMesh);
    EXPECT_FALSE(scan.info.normalsEstimated);
    EXPECT_EQ(scan.info.meshFaces, c.faces);
    EXPECT_EQ(scan.info.pointsRead, c.vertices);
    ASSERT_EQ(scan.cloud.size(), 4000u);
    expectOnBoxWithOutwardNormals(scan.cloud, m);
  }
}

TEST_F(ScanReaderTest, OrientsInvertedAndInconsistentMeshesOutwards) {
  ReadOptions options;
  options.meshSamples = 3000;
  BoxMesh inverted;
  for (std::size_t f = 0; f < inverted.faces.size(); ++f) inverted.reverseFace(f);
  expectOnBoxWithOutwardNormals(readScan(write("inverted.off", makeOff(inverted)), options).cloud,
                                inverted);
  BoxMesh oneFlipped;
  oneFlipped.reverseFace(1);
  expectOnBoxWithOutwardNormals(readScan(write("flipped.obj", makeObj(oneFlipped)), options).cloud,
                                oneFlipped);
  BoxMesh allButOne = inverted;
  allButOne.reverseFace(3);
  expectOnBoxWithOutwardNormals(
      readScan(write("mostly.stl", makeBinaryStl(allButOne)), options).cloud, allButOne);
}

TEST_F(ScanReaderTest, KeepsEachShellOrientedAsTheFileHasIt) {
  // A box with a box-shaped cavity (faces pointing into the cavity) and a
  // separate small box whose first face is reversed.
  const BoxMesh outer;
  BoxMesh cavity(outer.center, Vec3(0.5, 0.25, 0.125));
  for (std::size_t f = 0; f < cavity.faces.size(); ++f) cavity.reverseFace(f);
  BoxMesh separate(Vec3(30.0, 0.0, 0.0), Vec3(1.0, 0.5, 0.25));
  separate.reverseFace(0);

  std::string off = "OFF\n24 18 0\n";
  for (const BoxMesh* m : std::array<const BoxMesh*, 3>{&outer, &cavity, &separate}) {
    for (const Vec3& v : m->vertices) {
      off += coordinates(v);
      off += '\n';
    }
  }
  int base = 0;
  for (const BoxMesh* m : std::array<const BoxMesh*, 3>{&outer, &cavity, &separate}) {
    for (const auto& f : m->faces) {
      off += '4';
      for (int i : f) {
        off += ' ';
        off += std::to_string(base + i);
      }
      off += '\n';
    }
    base += 8;
  }
  ReadOptions options;
  options.meshSamples = 6000;
  const Scan scan = readScan(write("shells.off", off), options);
  std::array<std::size_t, 3> hits{};
  for (std::size_t i = 0; i < scan.cloud.size(); ++i) {
    const Vec3& p = scan.cloud.points[i];
    const Vec3& n = scan.cloud.normals[i];
    // Which shell, and which way its faces should point (-1: into the cavity).
    const bool far = p.x() > 20.0;
    const bool inner =
        !far && ((p - outer.center).cwiseAbs().array() < outer.half.array() - 1e-6).all();
    const BoxMesh& m = far ? separate : inner ? cavity : outer;
    const double sign = inner ? -1.0 : 1.0;
    ++hits[far ? 2 : inner ? 1 : 0];
    int axis = 0;
    n.cwiseAbs().maxCoeff(&axis);
    ASSERT_NEAR(std::abs(n[axis]), 1.0, 1e-9);
    const Vec3 local = (p - m.center).cwiseQuotient(m.half);
    ASSERT_NEAR(local[axis], sign * n[axis], 1e-9)
        << "point " << p.transpose() << " normal " << n.transpose();
  }
  EXPECT_GT(hits[0], 0u);
  EXPECT_GT(hits[1], 0u);
  EXPECT_GT(hits[2], 0u);
}

TEST_F(ScanReaderTest, MeshSamplingIsSeeded) {
  const BoxMesh m;
  const fs::path path = write("box.off", makeOff(m));
  ReadOptions options;
  options.meshSamples = 500;
  const Scan a = readScan(path, options);
  const Scan b = readScan(path, options);
  options.seed = 2;
  const Scan c = readScan(path, options);
  EXPECT_EQ(a.cloud.points, b.cloud.points);
  EXPECT_EQ(a.cloud.normals, b.cloud.normals);
  EXPECT_NE(a.cloud.points, c.cloud.points);
}

TEST_F(ScanReaderTest, MeshSamplingIsAreaWeighted) {
  // Two separate triangles with areas 1 and 3.
  const std::string off =
      "OFF\n6 2 0\n0 0 0\n1 0 0\n0 2 0\n10 0 0\n13 0 0\n10 2 0\n3 0 1 2\n3 3 4 5\n";
  ReadOptions options;
  options.meshSamples = 20000;
  const Scan scan = readScan(write("two.off", off), options);
  std::size_t inSmall = 0;
  for (const Vec3& p : scan.cloud.points) {
    ASSERT_NEAR(p.z(), 0.0, 1e-12);
    if (p.x() < 5.0) {
      ++inSmall;
      ASSERT_LE(p.x() / 1.0 + p.y() / 2.0, 1.0 + 1e-12);
    } else {
      ASSERT_LE((p.x() - 10.0) / 3.0 + p.y() / 2.0, 1.0 + 1e-12);
    }
  }
  EXPECT_NEAR(static_cast<double>(inSmall) / 20000.0, 0.25, 0.015);
}

// ---------------------------------------------------------------------------
// Normal estimation.

TEST(EstimateNormals, SphereNormalsPointOutwards) {
  const Sample s = samplePoints(3000, Vec3(0.3, -0.2, 0.1), 1.0, 21);
  PointCloud cloud{s.points, {}};
  estimateNormals(cloud, 18);
  expectUnitNormals(cloud);
  EXPECT_GT(agreeingFraction(cloud.normals, s.normals), 0.95);
}

TEST(EstimateNormals, BoxNormalsPointOutwards) {
  for (std::uint64_t seed : {1, 2, 3}) {
    const Sample s = boxPoints(6000, Vec3(100.0, -50.0, 20.0), Vec3(2.0, 1.0, 0.5), seed);
    PointCloud cloud{s.points, {}};
    estimateNormals(cloud, 18);
    expectUnitNormals(cloud);
    EXPECT_GT(agreeingFraction(cloud.normals, s.normals), 0.95) << "seed " << seed;
  }
}

TEST(EstimateNormals, OpenTubeNormalsPointOutwards) {
  // A pipe scanned without its ends: the highest points lie on the rim, where
  // the normals are horizontal, so only the final outward vote decides.
  for (std::uint64_t seed : {1, 2, 3, 4}) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> uniform(-1.0, 1.0);
    Sample s;
    for (int i = 0; i < 3000; ++i) {
      const double angle = uniform(rng) * std::numbers::pi;
      const Vec3 radial(std::cos(angle), std::sin(angle), 0.0);
      s.points.push_back(Vec3(1.0, 2.0, 3.0) + 0.5 * radial + Vec3(0.0, 0.0, 1.5 * uniform(rng)));
      s.normals.push_back(radial);
    }
    PointCloud cloud{s.points, {}};
    estimateNormals(cloud, 18);
    EXPECT_GT(agreeingFraction(cloud.normals, s.normals), 0.95) << "seed " << seed;
  }
}

TEST(EstimateNormals, SeparatePiecesAreOrientedToo) {
  // Two spheres far apart: the neighbour graph has two pieces.
  Sample a = samplePoints(1500, Vec3(0.0, 0.0, 0.0), 1.0, 31);
  const Sample b = samplePoints(1500, Vec3(6.0, 1.0, -2.0), 0.7, 32);
  a.points.insert(a.points.end(), b.points.begin(), b.points.end());
  a.normals.insert(a.normals.end(), b.normals.begin(), b.normals.end());
  PointCloud cloud{a.points, {}};
  estimateNormals(cloud, 18);
  const std::vector<Vec3> second(cloud.normals.begin() + 1500, cloud.normals.end());
  EXPECT_GT(agreeingFraction(cloud.normals, a.normals), 0.95);
  EXPECT_GT(agreeingFraction(second, b.normals), 0.95);
}

TEST(EstimateNormals, CavityNormalsPointIntoTheCavity) {
  // A hollow ball: outer surface radius 2, cavity radius 1. The cavity is a
  // separate piece whose highest point has its outward normal pointing down.
  Sample outer = samplePoints(4000, Vec3::Zero(), 2.0, 61);
  const Sample cavity = samplePoints(1000, Vec3::Zero(), 1.0, 62);
  for (std::size_t i = 0; i < cavity.points.size(); ++i) {
    outer.points.push_back(cavity.points[i]);
    outer.normals.push_back(-cavity.normals[i]);
  }
  PointCloud cloud{outer.points, {}};
  estimateNormals(cloud, 18);
  const std::vector<Vec3> estimated(cloud.normals.begin() + 4000, cloud.normals.end());
  const std::vector<Vec3> truth(outer.normals.begin() + 4000, outer.normals.end());
  EXPECT_GT(agreeingFraction(cloud.normals, outer.normals), 0.95);
  EXPECT_GT(agreeingFraction(estimated, truth), 0.95);
}

TEST(EstimateNormals, NoisyThinWalledScansInData) {
  // Parts with thin walls, sampled with noise (sigma 0.5 % of the diagonal):
  // propagating orientations with the classic weight 1 - |n_i . n_j| turned
  // about 40 % of the funnel's and the pipe tee's normals inwards.
  for (const char* part : {"funnel", "pipe_tee", "housing_complex"}) {
    SCOPED_TRACE(part);
    const Scan scan = readScan(fs::path(CSGVOX_DATA_DIR) / part / "scan_noisy.ply");
    ASSERT_TRUE(scan.cloud.hasNormals());
    PointCloud cloud{scan.cloud.points, {}};
    estimateNormals(cloud, 18);
    std::size_t inwards = 0;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
      if (cloud.normals[i].dot(scan.cloud.normals[i]) < -0.5) ++inwards;
    }
    EXPECT_LT(static_cast<double>(inwards) / static_cast<double>(cloud.size()), 0.01);
    EXPECT_GT(agreeingFraction(cloud.normals, scan.cloud.normals), 0.7);  // noise limits accuracy
  }
}

TEST(EstimateNormals, ReplacesExistingNormalsAndIsDeterministic) {
  const Sample s = samplePoints(800, Vec3::Zero(), 1.0, 41);
  PointCloud first{s.points, std::vector<Vec3>(s.points.size(), Vec3(0.0, 0.0, -1.0))};
  PointCloud second{s.points, {}};
  estimateNormals(first, 12);
  estimateNormals(second, 12);
  EXPECT_EQ(first.normals, second.normals);
  EXPECT_GT(agreeingFraction(first.normals, s.normals), 0.95);
}

TEST(EstimateNormals, HandlesDuplicatePoints) {
  Sample s = samplePoints(600, Vec3::Zero(), 1.0, 51);
  for (std::size_t i = 0; i < 200; ++i) {  // every one of the first 200 points three times
    s.points.push_back(s.points[i]);
    s.points.push_back(s.points[i]);
    s.normals.push_back(s.normals[i]);
    s.normals.push_back(s.normals[i]);
  }
  PointCloud cloud{s.points, {}};
  estimateNormals(cloud, 8);
  expectUnitNormals(cloud);
  EXPECT_GT(agreeingFraction(cloud.normals, s.normals), 0.95);
}

TEST(EstimateNormals, RejectsBadArguments) {
  PointCloud cloud{samplePoints(10, Vec3::Zero(), 1.0, 1).points, {}};
  EXPECT_THROW(estimateNormals(cloud, 18), std::invalid_argument);  // too few points
  EXPECT_THROW(estimateNormals(cloud, 5), std::invalid_argument);   // too few neighbours
  cloud.points.resize(50, Vec3(std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0));
  EXPECT_THROW(estimateNormals(cloud, 6), std::invalid_argument);
}

// ---------------------------------------------------------------------------
// Bad input.

TEST_F(ScanReaderTest, RejectsMissingFilesDirectoriesAndUnknownExtensions) {
  expectError<IoError>(dir_ / "missing.ply", "no such file");
  fs::create_directories(dir_ / "folder.ply");
  expectError<IoError>(dir_ / "folder.ply", "directory");
  expectError<IoError>(write("notes.doc", "1 2 3\n"), "unsupported");
  expectError<IoError>(write("noextension", "1 2 3\n"), "unsupported");
}

TEST_F(ScanReaderTest, RejectsEmptyFiles) {
  for (const char* name : {"empty.ply", "empty.xyz", "empty.off", "empty.obj", "empty.stl"}) {
    expectError<ParseError>(write(name, ""), "empty");
  }
  expectError<ParseError>(write("comments.xyz", "# nothing\n\n"), "0 points");
  expectError<ParseError>(write("blank.stl", "  \n\n "), "not an STL");
}

TEST_F(ScanReaderTest, RejectsTruncatedPly) {
  const Sample s = samplePoints(150, Vec3::Zero(), 1.0, 2);
  for (Data data : {Data::LittleEndian, Data::BigEndian}) {
    const std::string full = makePly(s, {data, false, true, false});
    // Cut inside the last vertex, and exactly at a vertex boundary.
    expectError<ParseError>(write("cut.ply", full.substr(0, full.size() - 5)), "truncated");
    expectError<ParseError>(write("cut_row.ply", full.substr(0, full.size() - 24)), "truncated");
  }
  // ASCII: drop the last 10 vertex lines.
  std::string ascii = makePly(s, {Data::Ascii, false, true, false});
  std::size_t cut = ascii.size() - 1;
  for (int i = 0; i < 10; ++i) cut = ascii.rfind('\n', cut - 1);
  expectError<ParseError>(write("short.ply", ascii.substr(0, cut + 1)), "140 of 150");
  // ASCII: a vertex line missing a value.
  std::string missing = ascii;
  const std::size_t firstGap = missing.find(' ', missing.find("end_header\n"));
  missing.erase(firstGap, missing.find(' ', firstGap + 1) - firstGap);  // drops " y" of vertex 1
  expectError<ParseError>(write("missing_value.ply", missing), "vertex 1 of 150 has 5 values");
  // A header promising far more vertices than the file holds.
  std::string huge = ascii;
  huge.replace(huge.find("vertex 150"), 10, "vertex 99999999999");
  expectError<ParseError>(write("huge.ply", huge), "truncated");
}

TEST_F(ScanReaderTest, RejectsGarbledPlyHeaders) {
  const Sample s = samplePoints(120, Vec3::Zero(), 1.0, 2);
  const std::string good = makePly(s, {Data::LittleEndian, false, true, false});
  auto replaced = [&](const std::string& from, const std::string& to) {
    std::string text = good;
    text.replace(text.find(from), from.size(), to);
    return text;
  };
  expectError<ParseError>(write("magic.ply", replaced("ply\n", "plx\n")), "not a PLY");
  expectError<ParseError>(write("format.ply", replaced("binary_little_endian", "binary")),
                          "format");
  expectError<ParseError>(write("no_end.ply", replaced("end_header", "end_headr")), "garbled");
  expectError<ParseError>(write("header_only.ply", good.substr(0, good.find("end_header") + 10)),
                          "truncated");
  expectError<ParseError>(write("type.ply", replaced("float nx", "float16 nx")), "float16");
  expectError<ParseError>(write("int_x.ply", replaced("float x", "int x")), "\"x\"");
  expectError<ParseError>(write("no_nz.ply", replaced("property float nz\n", "")), "nx ny nz");
  expectError<ParseError>(write("no_z.ply", replaced("property float z\n", "")), "\"z\"");
  expectError<ParseError>(write("negative.ply", replaced("vertex 120", "vertex -120")), "garbled");
  expectError<ParseError>(write("text.ply", "hello world\nthis is not a scan\n"), "not a PLY");
  std::string binaryJunk(5000, '\x07');
  expectError<ParseError>(write("junk.ply", "ply\n" + binaryJunk), "PLY");
}

TEST_F(ScanReaderTest, RejectsNonFiniteCoordinates) {
  Sample s = samplePoints(150, Vec3::Zero(), 1.0, 2);
  std::string ascii = makePly(s, {Data::Ascii, true, true, false});
  const std::size_t row = ascii.find("end_header\n") + 11;
  std::string nanText = ascii;
  nanText.replace(row, nanText.find(' ', row) - row, "nan");
  expectError<ParseError>(write("nan_ascii.ply", nanText), "finite");
  std::string infText = ascii;
  infText.replace(row, infText.find(' ', row) - row, "inf");
  expectError<ParseError>(write("inf_ascii.ply", infText), "finite");

  Sample bad = s;
  bad.points[42].y() = std::numeric_limits<double>::quiet_NaN();
  expectError<ParseError>(write("nan_binary.ply", makePly(bad, {Data::LittleEndian, false, true})),
                          "point 43 has a non-finite coordinate");
  bad.points[42].y() = std::numeric_limits<double>::infinity();
  expectError<ParseError>(write("inf_binary.ply", makePly(bad, {Data::BigEndian, true, false})),
                          "point 43");

  std::string xyz = makeXyz(s, false);
  std::string xyzNan = "nan 0 0\n" + xyz;
  expectError<ParseError>(write("nan.xyz", xyzNan), "line 1");
  std::string xyzInf = xyz + "1 inf 0\n";
  expectError<ParseError>(write("inf.xyz", xyzInf), "line 151");

  BoxMesh m;
  m.vertices[5].x() = std::numeric_limits<double>::quiet_NaN();
  expectError<ParseError>(write("nan_binary.stl", makeBinaryStl(m)), "non-finite");
  expectError<ParseError>(write("nan.off", makeOff(m)), "finite");
  expectError<ParseError>(write("nan.obj", makeObj(m)), "line 9");
  expectError<ParseError>(write("nan_ascii.stl", makeAsciiStl(m)), "finite");
  expectError<ParseError>(write("nan_mesh.ply", makePlyMesh(m, Data::LittleEndian)),
                          "vertex 6 has a non-finite coordinate");
}

TEST_F(ScanReaderTest, RejectsBadNormals) {
  Sample s = samplePoints(150, Vec3::Zero(), 1.0, 2);
  s.normals[17] = Vec3::Zero();
  expectError<ParseError>(write("zero.ply", makePly(s, {Data::LittleEndian, false, true})),
                          "point 18 has a zero-length");
  expectError<ParseError>(write("zero.xyz", makeXyz(s, true)), "line 18 has a zero-length");
  s.normals[17] = Vec3(std::numeric_limits<double>::quiet_NaN(), 1.0, 0.0);
  expectError<ParseError>(write("nan_normal.ply", makePly(s, {Data::BigEndian, true, true})),
                          "point 18 has a non-finite normal");
  // A line without normals in a file with normals.
  Sample t = samplePoints(150, Vec3::Zero(), 1.0, 2);
  std::string text = makeXyz(t, true);
  text += "0.5 0.5 0.5\n";
  expectError<ParseError>(write("mixed.xyz", text), "line 151 has 3 values but line 1 has 6");
}

TEST_F(ScanReaderTest, RejectsGarbledXyz) {
  const Sample s = samplePoints(150, Vec3::Zero(), 1.0, 2);
  expectError<ParseError>(write("four.xyz", "1 2 3 4\n" + makeXyz(s, false)),
                          "line 1 has 4 values");
  std::string text = makeXyz(s, false);
  text.insert(text.find('\n', 100) + 1, "1 2 three\n");
  const auto line =
      std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(text.find("three")),
                 '\n') +
      1;
  expectError<ParseError>(write("word.xyz", text), "line " + std::to_string(line));
  expectError<ParseError>(write("five.xyz", makeXyz(s, false) + "1 2 3 4 5\n"), "line 151");
  // CGAL alone would skip this line as a point count.
  expectError<ParseError>(write("first.xyz", "5 nan 0\n" + makeXyz(s, false)), "line 1:");
}

TEST_F(ScanReaderTest, RejectsTooFewPoints) {
  const Sample s = samplePoints(50, Vec3::Zero(), 1.0, 2);
  expectError<ParseError>(write("few.xyz", makeXyz(s, true)), "at least 100");
  expectError<ParseError>(write("few.ply", makePly(s, {Data::LittleEndian, false, true})),
                          "at least 100");
  ReadOptions relaxed;
  relaxed.minPoints = 10;
  EXPECT_EQ(readScan(write("few_ok.xyz", makeXyz(s, true)), relaxed).cloud.size(), 50u);
  // Enough points for minPoints, too few to estimate normals.
  relaxed.normalNeighbors = 60;
  expectError<ParseError>(write("few_for_k.xyz", makeXyz(s, false)), "estimate normals", relaxed);
  ReadOptions badOptions;
  badOptions.normalNeighbors = 2;
  EXPECT_THROW(readScan(write("ok.xyz", makeXyz(s, true)), badOptions), std::invalid_argument);
}

TEST_F(ScanReaderTest, RejectsMeshesWithoutFacesOrArea) {
  expectError<ParseError>(write("points.off", "OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n"), "no faces");
  expectError<ParseError>(write("points.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n"), "no faces");
  expectError<ParseError>(write("nothing.stl", "solid empty\nendsolid empty\n"), "no faces");
  std::string header(80, ' ');
  expectError<ParseError>(write("nothing_binary.stl", header + std::string(4, '\0')), "no faces");
  expectError<ParseError>(
      write("flat.off", "OFF\n4 2 0\n0 0 0\n1 0 0\n2 0 0\n3 0 0\n3 0 1 2\n3 1 2 3\n"), "zero area");
  expectError<ParseError>(
      write("point_faces.off", "OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 0 0\n2 0 1\n"), "zero area");
  BoxMesh collapsed;
  for (Vec3& v : collapsed.vertices) v.z() = 0.0;  // every face degenerates or doubles
  for (Vec3& v : collapsed.vertices) v.y() = 0.0;
  expectError<ParseError>(write("collapsed.stl", makeAsciiStl(collapsed)), "zero area");
}

TEST_F(ScanReaderTest, RejectsBrokenMeshFiles) {
  const BoxMesh m;
  const std::string binary = makeBinaryStl(m);
  expectError<ParseError>(write("cut.stl", binary.substr(0, binary.size() - 30)), "truncated");
  const std::string ascii = makeAsciiStl(m);
  expectError<ParseError>(write("cut_ascii.stl", ascii.substr(0, ascii.size() / 2)), "truncated");
  expectError<ParseError>(write("junk.stl", std::string(200, 'x')), "truncated");

  const std::string off = makeOff(m);
  expectError<ParseError>(write("cut.off", off.substr(0, off.size() - 20)), "truncated");
  expectError<ParseError>(write("huge.off", "OFF\n3 300000000 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"),
                          "300000000 faces");
  expectError<ParseError>(write("header.off", "FOO\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"),
                          "not an OFF");
  expectError<ParseError>(write("index.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n"),
                          "out of range");

  // CGAL's OBJ reader lets an index one past the last vertex through.
  expectError<ParseError>(
      write("index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n"),
      "face 1 refers to vertex 4 (counting from 1), but the file has 3 vertices");
  expectError<ParseError>(write("statement.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nbogus 1\nf 1 2 3\n"),
                          "line 4");
  expectError<ParseError>(write("short_vertex.obj", "v 0 0 0\nv 1 0\nv 0 1 0\nf 1 2 3\n"),
                          "line 2");

  std::string plyMesh = makePlyMesh(m, Data::LittleEndian);
  expectError<ParseError>(write("cut_mesh.ply", plyMesh.substr(0, plyMesh.size() - 3)),
                          "face 6 of 6");
  std::string asciiMesh = makePlyMesh(m, Data::Ascii);
  asciiMesh.replace(asciiMesh.rfind("4 "), 2, "4 9");
  expectError<ParseError>(write("index_mesh.ply", asciiMesh), "refers to vertex");
  // Garbled list lengths, which CGAL would try to allocate.
  std::string longList = makePlyMesh(m, Data::LittleEndian, true);
  longList.replace(longList.size() - 20, 4, std::string("\xFF\xFF\xFF\x7F", 4));
  expectError<ParseError>(write("long_list.ply", longList), "list is longer");
  std::string negativeList = makePlyMesh(m, Data::LittleEndian, true);
  negativeList.replace(negativeList.size() - 20, 4, std::string("\xFB\xFF\xFF\xFF", 4));
  expectError<ParseError>(write("negative_list.ply", negativeList), "list is longer");
  std::string longAscii = makePlyMesh(m, Data::Ascii, true);
  longAscii.replace(longAscii.rfind("\n4 ") + 1, 1, "2000000000");
  expectError<ParseError>(write("long_list_ascii.ply", longAscii), "list is longer");
  std::string longFace = makeOff(m);
  longFace.replace(longFace.rfind("\n4 ") + 1, 1, "4294967295");
  expectError<ParseError>(write("long_face.off", longFace), "line 17");
  expectError<ParseError>(write("binary.off", "OFF BINARY\n" + std::string(40, '\0')),
                          "binary OFF");
  std::string ushortIndices = makePlyMesh(m, Data::Ascii);
  ushortIndices.replace(ushortIndices.find("uchar int"), 9, "uchar ushort");
  expectError<ParseError>(write("ushort.ply", ushortIndices), "vertex_indices");
}

}  // namespace
}  // namespace csgvox

namespace csgvox {
namespace {

TEST(ReadScan, OneViewOfAFlatFaceIsRejectedWithOneLine) {
  // 5000 points on a 50 x 30 plane with noise: no solid to reconstruct.
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, 0.02);
  std::stringstream xyz;
  for (int i = 0; i < 5000; ++i)
    xyz << 50 * u(rng) << ' ' << 30 * u(rng) << ' ' << noise(rng) << '\n';
  try {
    readScan(xyz, ScanFileType::Xyz, "face.xyz");
    ADD_FAILURE() << "no error";
  } catch (const ParseError& e) {
    const std::string message = e.what();
    EXPECT_EQ(message.rfind("face.xyz: all 5000 points lie on one plane", 0), 0u) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos);
  }
}

TEST(ReadScan, AThinPlateIsNotAFlatFace) {
  // Both faces of a plate 1 thick (50 times the noise, about the spacing),
  // 50 x 30. (Faces closer than their spacing and noise read as one.)
  std::mt19937 rng(6);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, 0.02);
  std::stringstream xyz;
  for (int i = 0; i < 6000; ++i) {
    xyz << 50 * u(rng) << ' ' << 30 * u(rng) << ' ' << (i % 2) * 1.0 + noise(rng) << '\n';
  }
  EXPECT_NO_THROW(readScan(xyz, ScanFileType::Xyz, "plate.xyz"));
}

}  // namespace
}  // namespace csgvox
