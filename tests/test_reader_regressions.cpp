// Strictness of the scan and mesh readers on inputs that were accepted
// silently, misreported or hung, and on inputs found by the fuzz targets.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <future>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "io/errors.h"
#include "io/mesh_files.h"
#include "io/scan_reader.h"
#include "io/tree_json.h"
#include "temp_dir_test.h"

namespace csgvox {
namespace {

namespace fs = std::filesystem;

class ReaderRegressionTest : public test::TempDirTest {
 protected:
  /// Runs `read` expecting exception E with a one-line message that names
  /// `path` and contains every one of `keywords`.
  template <class E>
  static void expectError(const fs::path& path, const std::function<void()>& read,
                          const std::vector<std::string>& keywords) {
    SCOPED_TRACE(path.filename().string());
    std::string message;
    bool rightType = false;
    try {
      read();
    } catch (const E& e) {
      rightType = true;
      message = e.what();
    } catch (const std::exception& e) {
      message = std::string("wrong exception type: ") + e.what();
    }
    EXPECT_TRUE(rightType) << (message.empty() ? "no exception" : message);
    EXPECT_NE(message.find(path.string()), std::string::npos) << message;
    for (const std::string& keyword : keywords) {
      EXPECT_NE(message.find(keyword), std::string::npos)
          << "\"" << keyword << "\" not in: " << message;
    }
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  }

  template <class E>
  static void expectScanError(const fs::path& path, const std::vector<std::string>& keywords) {
    expectError<E>(
        path, [&] { readScan(path); }, keywords);
  }
};

/// `n` points on a unit sphere as "x y z nx ny nz" (or "x y z") lines.
std::vector<std::string> sphereLines(std::size_t n, bool normals) {
  std::vector<std::string> lines;
  for (std::size_t i = 0; i < n; ++i) {
    // A Fibonacci sphere: evenly spread and deterministic.
    const double z = 1.0 - 2.0 * (static_cast<double>(i) + 0.5) / static_cast<double>(n);
    const double r = std::sqrt(1.0 - z * z);
    const double phi = static_cast<double>(i) * std::numbers::pi * (3.0 - std::sqrt(5.0));
    std::ostringstream line;
    line.precision(17);
    line << r * std::cos(phi) << ' ' << r * std::sin(phi) << ' ' << z;
    if (normals) line << ' ' << r * std::cos(phi) << ' ' << r * std::sin(phi) << ' ' << z;
    lines.push_back(line.str());
  }
  return lines;
}

std::string joinLines(const std::vector<std::string>& lines) {
  std::string text;
  for (const std::string& line : lines) text += line + "\n";
  return text;
}

std::string asciiPlyHeader(std::size_t declared, bool normals) {
  std::string header = "ply\nformat ascii 1.0\nelement vertex " + std::to_string(declared) +
                       "\nproperty float x\nproperty float y\nproperty float z\n";
  if (normals) header += "property float nx\nproperty float ny\nproperty float nz\n";
  return header + "end_header\n";
}

// ---------------------------------------------------------------------------
// Extensions.

TEST_F(ReaderRegressionTest, PtsAndTxtAreReadAsXyz) {
  for (const char* name : {"scan.pts", "scan.txt", "scan.PTS"}) {
    const fs::path path = write(name, joinLines(sphereLines(200, true)));
    const Scan scan = readScan(path);
    EXPECT_EQ(scan.info.format, "xyzn") << name;
    EXPECT_EQ(scan.cloud.size(), 200u) << name;
    EXPECT_EQ(scanFileTypeFromPath(path), ScanFileType::Xyz) << name;
  }
}

// ---------------------------------------------------------------------------
// PLY: data beyond the header's counts, rows with extra values.

TEST_F(ReaderRegressionTest, PlyWithMoreVerticesThanItsHeaderDeclaresIsRejected) {
  const std::vector<std::string> rows = sphereLines(200, true);
  const fs::path ascii = write("more.ply", asciiPlyHeader(150, true) + joinLines(rows));
  expectScanError<ParseError>(
      ascii, {"line 161", "more PLY data than the header declares", "150 vertices"});
  expectError<ParseError>(ascii, [&] { readMesh(ascii); }, {"more PLY data"});

  // The same in binary: 150 declared, 200 written.
  std::string binary =
      "ply\nformat binary_little_endian 1.0\nelement vertex 150\nproperty float x\n"
      "property float y\nproperty float z\nend_header\n";
  for (const std::string& row : sphereLines(200, false)) {
    std::istringstream values(row);
    for (int k = 0; k < 3; ++k) {
      double v = 0.0;
      values >> v;
      const float f = static_cast<float>(v);
      binary.append(reinterpret_cast<const char*>(&f), sizeof f);
    }
  }
  const fs::path bin = write("more-binary.ply", binary);
  expectScanError<ParseError>(bin, {"more PLY data than the header declares", "600 bytes"});

  // Trailing blank lines are not data.
  const fs::path blank = write("blank.ply", asciiPlyHeader(200, true) + joinLines(rows) + "\n\n");
  EXPECT_EQ(readScan(blank).cloud.size(), 200u);
}

TEST_F(ReaderRegressionTest, PlyRowWithAnExtraValueIsReportedAsSuch) {
  std::vector<std::string> rows = sphereLines(200, true);
  rows[41] += " 7";  // line 52 of the file (10 header lines)
  const fs::path path = write("seven.ply", asciiPlyHeader(200, true) + joinLines(rows));
  expectScanError<ParseError>(path,
                              {"line 52", "vertex 42 of 200", "has 7 values", "x y z nx ny nz"});
  std::string message;
  try {
    readScan(path);
  } catch (const ParseError& e) {
    message = e.what();
  }
  EXPECT_EQ(message.find("zero-length"), std::string::npos) << message;
}

TEST_F(ReaderRegressionTest, PlyRowsWithMissingOrMalformedValuesNameTheLine) {
  std::vector<std::string> rows = sphereLines(200, false);
  rows[9] = "1 2";
  expectScanError<ParseError>(write("short.ply", asciiPlyHeader(200, false) + joinLines(rows)),
                              {"line 17", "has 2 values"});
  rows = sphereLines(200, false);
  rows[9] = "1.5.5 2 3";
  expectScanError<ParseError>(write("number.ply", asciiPlyHeader(200, false) + joinLines(rows)),
                              {"line 17", "\"1.5.5\" is not a float value"});
  // A face list longer than its line.
  const std::string mesh =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n";
  const fs::path face = write("face.ply", mesh);
  expectScanError<ParseError>(face, {"line 13", "face 1 of 1", "vertex_indices"});
  expectError<ParseError>(face, [&] { readMesh(face); }, {"line 13"});
}

// Found by fuzz_ply_binary: an element without properties and a huge count
// made CGAL loop over its empty rows for ever.
TEST_F(ReaderRegressionTest, PlyElementWithoutPropertiesIsRejected) {
  const std::string header =
      "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "element junk 999999999999999\nend_header\n";
  std::string binary = "ply\nformat binary_little_endian 1.0\n" + header;
  const float coords[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  binary.append(reinterpret_cast<const char*>(coords), sizeof coords);
  const fs::path bin = write("junk.ply", binary);
  const auto started = std::chrono::steady_clock::now();
  expectScanError<ParseError>(bin,
                              {"element \"junk\" declares 999999999999999 rows but no properties"});
  expectError<ParseError>(bin, [&] { readMesh(bin); }, {"no properties"});
  const fs::path ascii =
      write("junk_ascii.ply", "ply\nformat ascii 1.0\n" + header + "0 0 0\n1 0 0\n0 1 0\n");
  expectScanError<ParseError>(ascii, {"no properties"});
  EXPECT_LT(std::chrono::steady_clock::now() - started, std::chrono::seconds(10));
}

// ---------------------------------------------------------------------------
// XYZ: every line is checked, not only the first.

TEST_F(ReaderRegressionTest, XyzLineWithATrailingTokenOrAMalformedNumberIsRejected) {
  std::vector<std::string> lines = sphereLines(200, false);
  lines[56] += " 4";
  expectScanError<ParseError>(write("token.xyz", joinLines(lines)), {"line 57", "has 4 values"});

  lines = sphereLines(200, false);
  lines[79] = "1.5.5 2 3";
  expectScanError<ParseError>(write("number.xyz", joinLines(lines)),
                              {"line 80", "\"1.5.5\" is not a finite number"});

  lines = sphereLines(200, true);
  lines[99] = "0 0 1 0 0 1x";
  expectScanError<ParseError>(write("suffix.xyzn", joinLines(lines)), {"line 100", "\"1x\""});

  lines = sphereLines(200, true);
  lines[120] = "0 0 1 0 0 nan";
  expectScanError<ParseError>(write("nan.xyzn", joinLines(lines)), {"line 121", "\"nan\""});
}

TEST_F(ReaderRegressionTest, XyzMixingThreeAndSixColumnsIsRejected) {
  std::vector<std::string> lines = sphereLines(200, true);
  lines[150] = "0.5 0.5 0.5";
  expectScanError<ParseError>(write("mixed.xyz", joinLines(lines)),
                              {"line 151 has 3 values but line 1 has 6"});
  lines = sphereLines(200, false);
  lines[3] = "0 0 1 0 0 1";
  expectScanError<ParseError>(write("mixed3.xyz", "# comment\n" + joinLines(lines)),
                              {"line 5 has 6 values but line 2 has 3"});
}

TEST_F(ReaderRegressionTest, XyzPointCountLineAndCommentsAreStillSkipped) {
  const fs::path path =
      write("count.xyz", "200\n# a comment\n\r\n" + joinLines(sphereLines(200, true)));
  const Scan scan = readScan(path);
  EXPECT_EQ(scan.cloud.size(), 200u);
  EXPECT_EQ(scan.info.format, "xyzn");
}

// ---------------------------------------------------------------------------
// Files that are not regular files.

/// Runs `read` on another thread; if it has not returned after a few
/// seconds, unblocks it by opening the FIFO for writing and fails.
void expectReturnsPromptly(const fs::path& fifo, const std::function<void()>& read) {
  auto done = std::async(std::launch::async, read);
  if (done.wait_for(std::chrono::seconds(5)) == std::future_status::ready) {
    done.get();
    return;
  }
  ADD_FAILURE() << "reading " << fifo << " blocked";
  // Unblock each open of the FIFO by a writer that closes at once (EOF).
  while (done.wait_for(std::chrono::milliseconds(100)) != std::future_status::ready) {
    const int fd = ::open(fifo.c_str(), O_WRONLY | O_NONBLOCK);
    if (fd >= 0) ::close(fd);
  }
  try {
    done.get();
  } catch (const std::exception&) {
  }
}

TEST_F(ReaderRegressionTest, FifoWithoutAWriterIsRejectedWithoutBlocking) {
  for (const char* name : {"scan.ply", "mesh.stl", "tree.json"}) {
    const fs::path fifo = dir_ / name;
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0) << name;
  }
  const fs::path scan = dir_ / "scan.ply";
  const fs::path mesh = dir_ / "mesh.stl";
  const fs::path tree = dir_ / "tree.json";
  expectReturnsPromptly(
      scan, [&] { expectError<IoError>(scan, [&] { readScan(scan); }, {"not a regular file"}); });
  expectReturnsPromptly(
      mesh, [&] { expectError<IoError>(mesh, [&] { readMesh(mesh); }, {"not a regular file"}); });
  expectReturnsPromptly(tree, [&] {
    expectError<IoError>(tree, [&] { readTreeJson(tree); }, {"not a regular file"});
  });
}

TEST_F(ReaderRegressionTest, DeviceFileIsRejectedAsNotARegularFile) {
  ASSERT_TRUE(fs::exists("/dev/zero"));
  const fs::path zero = dir_ / "zero.ply";
  fs::create_symlink("/dev/zero", zero);
  expectScanError<IoError>(zero, {"not a regular file"});
  expectError<IoError>(zero, [&] { readMesh(zero); }, {"not a regular file"});
}

// ---------------------------------------------------------------------------
// readMesh uses the strict mesh readers.

TEST_F(ReaderRegressionTest, ReadMeshRejectsWhatTheScanReaderRejects) {
  // A garbled count: refused from the file size, nothing allocated.
  const fs::path off =
      write("huge.off", "OFF\n4000000000 4000000000 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  expectError<ParseError>(off, [&] { readMesh(off); }, {"truncated or garbled OFF"});
  // A wide list length larger than the file.
  std::string ply =
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
      "property float y\nproperty float z\nelement face 1\nproperty list int int vertex_indices\n"
      "end_header\n";
  ply += std::string(36, '\0');
  const std::int32_t length = 1 << 30;
  ply.append(reinterpret_cast<const char*>(&length), 4);
  ply += std::string(12, '\0');
  const fs::path list = write("list.ply", ply);
  expectError<ParseError>(list, [&] { readMesh(list); }, {"a list is longer than the rest"});
  // Binary STL with a NaN coordinate.
  std::string stl(80, ' ');
  const std::uint32_t one = 1;
  stl.append(reinterpret_cast<const char*>(&one), 4);
  const float coords[12] = {0, 0, 1, 0, 0, 0, 1, 0, 0, std::nanf(""), 1, 0};
  stl.append(reinterpret_cast<const char*>(coords), sizeof coords);
  stl.append(2, '\0');
  const fs::path nan = write("nan.stl", stl);
  expectError<ParseError>(nan, [&] { readMesh(nan); }, {"triangle 1 has a non-finite coordinate"});
}

TEST_F(ReaderRegressionTest, ReadMeshFromAStreamMatchesTheFile) {
  const std::string off = "OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n3 0 2 1\n";
  const fs::path path = write("quad.off", off);
  const TriangleMesh fromFile = readMesh(path);
  std::istringstream in(off);
  const TriangleMesh fromStream = readMesh(in, ScanFileType::Off, "quad");
  ASSERT_EQ(fromFile.triangles.size(), 3u);  // the quad as a fan of 2, then the triangle
  EXPECT_EQ(fromFile.triangles, fromStream.triangles);
  EXPECT_EQ(fromFile.vertices, fromStream.vertices);
  std::istringstream xyz("0 0 0\n");
  EXPECT_THROW(readMesh(xyz, ScanFileType::Xyz), std::invalid_argument);
}

}  // namespace
}  // namespace csgvox
