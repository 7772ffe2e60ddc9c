// Tests of io/mesh_export.h, io/triangle_mesh.h and io/mesh_solid.h: meshes of
// primitives and CSG trees are closed and measure like the solid; mesh files
// round-trip; MeshSolid agrees with the tree it was meshed from.

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "io/errors.h"
#include "io/mesh_files.h"
#include "mesh/mesh_export.h"
#include "mesh/mesh_solid.h"
#include "test_helpers.h"

namespace csgvox {
namespace {

namespace fs = std::filesystem;
using test::Rng;

constexpr double kPi = std::numbers::pi;

Mat3 rotation(double angle, const Vec3& axis) {
  return Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
}

/// Relative difference of a measured value from the expected one.
double relativeError(double measured, double expected) {
  return std::abs(measured - expected) / std::abs(expected);
}

/// Volume of a tree's solid from `samples` seeded random points in its bounds.
double monteCarloVolume(const CsgTree& tree, int samples, std::uint64_t seed) {
  const Aabb box = tree.bounds();
  Rng rng(seed);
  int inside = 0;
  for (int i = 0; i < samples; ++i) inside += tree.contains(test::randomPoint(rng, box));
  return box.size().prod() * inside / samples;
}

/// Euler characteristic V - E + F of a closed triangle mesh (2 - 2 * genus
/// for one connected surface).
long eulerCharacteristic(const TriangleMesh& mesh) {
  const long faces = static_cast<long>(mesh.triangles.size());
  return static_cast<long>(mesh.vertices.size()) - 3 * faces / 2 + faces;
}

/// Exact volume and area of a box cut by a half-space: each face is clipped
/// by the plane, and the cap closes the polyhedron, so its area vector is
/// minus the sum of the clipped faces' area vectors.
struct Measures {
  double volume = 0.0;
  double area = 0.0;
};

Measures clippedBoxMeasures(const Box& box, const HalfSpace& cut) {
  Measures m;
  Vec3 areaSum = Vec3::Zero();
  for (int k = 0; k < 3; ++k) {
    const Vec3 u = box.axes.col((k + 1) % 3) * box.halfSize[(k + 1) % 3];
    const Vec3 v = box.axes.col((k + 2) % 3) * box.halfSize[(k + 2) % 3];
    for (const double side : {-1.0, 1.0}) {
      const Vec3 c = box.center + side * box.halfSize[k] * box.axes.col(k);
      // Counter-clockwise seen from outside: u x v is +axis k.
      std::vector<Vec3> face = {c - u - v, c + u - v, c + u + v, c - u + v};
      if (side < 0.0) std::reverse(face.begin(), face.end());
      std::vector<Vec3> clipped;  // Sutherland-Hodgman against normal.x <= offset
      for (std::size_t i = 0; i < face.size(); ++i) {
        const Vec3& a = face[i];
        const Vec3& b = face[(i + 1) % face.size()];
        const double da = cut.normal.dot(a) - cut.offset, db = cut.normal.dot(b) - cut.offset;
        if (da <= 0.0) clipped.push_back(a);
        if ((da < 0.0) != (db < 0.0) && da != db) clipped.push_back(a + da / (da - db) * (b - a));
      }
      if (clipped.size() < 3) continue;
      Vec3 areaVector = Vec3::Zero();
      for (std::size_t i = 0; i < clipped.size(); ++i) {
        areaVector += 0.5 * clipped[i].cross(clipped[(i + 1) % clipped.size()]);
      }
      m.area += areaVector.norm();
      m.volume += areaVector.dot(clipped[0]) / 3.0;
      areaSum += areaVector;
    }
  }
  // The cap lies on normal.x = offset with outward normal `normal`.
  m.area += areaSum.norm();
  m.volume += cut.offset * areaSum.norm() / 3.0;
  return m;
}

/// A solid with its exact volume and area.
struct MeasuredCase {
  std::string name;
  CsgTree tree;
  double volume = 0.0;
  double area = 0.0;
};

/// Test-name-friendly printing for parameterised tests.
void PrintTo(const MeasuredCase& c, std::ostream* out) { *out << c.name; }

std::vector<MeasuredCase> primitiveCases() {
  std::vector<MeasuredCase> cases;
  const auto add = [&](const std::string& name, const Primitive& p) {
    cases.push_back({name, CsgTree::leaf(p), p.volume(), p.surfaceArea()});
  };
  add("RotatedBox", Box{Vec3(0.3, -0.2, 0.1), rotation(0.7, Vec3(1, 2, 3)), Vec3(1.0, 0.6, 0.4)});
  add("Cylinder", Cylinder{Vec3(0.1, 0.2, -0.3), Vec3(0.3, 0.2, 1).normalized(), 0.7, 1.6});
  add("ConeFrustum", Cone{Vec3(0, 0, 0), Vec3(1, -0.4, 0.5).normalized(), 0.9, 0.4, 1.5});
  add("Sphere", Sphere{Vec3(0.2, 0.1, 0), 1.1});
  add("Torus", Torus{Vec3(0, 0, 0.2), Vec3(0.2, 1, 0.4).normalized(), 1.0, 0.3});
  const Box box{Vec3(0.1, 0.0, -0.2), rotation(0.3, Vec3(0, 1, 1)), Vec3(0.8, 0.7, 0.6)};
  const HalfSpace cut{Vec3(1, 1, 1).normalized(), 0.2};
  const Measures m = clippedBoxMeasures(box, cut);
  cases.push_back({"HalfSpaceCutBox", CsgTree::intersect({CsgTree::leaf(box), CsgTree::leaf(cut)}),
                   m.volume, m.area});
  return cases;
}

/// A 4 x 3 x 0.5 plate with four through holes of radius 0.3 (genus 4).
CsgTree plateWithHoles() {
  std::vector<CsgTree> operands = {
      CsgTree::leaf(Box{Vec3::Zero(), Mat3::Identity(), Vec3(2.0, 1.5, 0.25)}, "plate")};
  for (const double x : {-1.4, 1.4}) {
    for (const double y : {-1.0, 1.0}) {
      operands.push_back(CsgTree::leaf(Cylinder{Vec3(x, y, 0.0), Vec3::UnitZ(), 0.3, 1.0}, "hole"));
    }
  }
  return CsgTree::subtract(operands);
}

/// (Cylinder ∪ rotated box) minus a sphere: convex and concave edges, curved
/// and flat faces meeting at various angles.
CsgTree bracket() {
  const CsgTree body = CsgTree::unite(
      {CsgTree::leaf(Cylinder{Vec3::Zero(), Vec3::UnitZ(), 1.0, 2.0}),
       CsgTree::leaf(Box{Vec3(0.8, 0, 0), rotation(0.4, Vec3(1, 1, 0)), Vec3(1.0, 0.5, 0.4)})});
  return CsgTree::subtract({body, CsgTree::leaf(Sphere{Vec3(0, 0, 1.0), 0.6})});
}

/// A fresh temporary directory, removed with its content at the end of the test.
class TempDir {
 public:
  TempDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    // A parameterised test's name ("Name/0") would make a nested directory,
    // whose parent the destructor would leave behind.
    std::string name = info->name();
    std::replace(name.begin(), name.end(), '/', '_');
    path_ = fs::temp_directory_path() /
            ("csgvox_test_mesh_export_" + std::to_string(::getpid()) + "_" + name);
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

void writeText(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

/// Expects `fn` to throw E with a message that contains `part`.
template <class E, class Fn>
void expectThrowWith(Fn&& fn, const std::string& part) {
  try {
    fn();
    ADD_FAILURE() << "expected an exception mentioning '" << part << "'";
  } catch (const E& e) {
    EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
  }
}

// ---------------------------------------------------------------------------
// meshTree on primitives

class MeshPrimitive : public ::testing::TestWithParam<MeasuredCase> {};

TEST_P(MeshPrimitive, IsClosedAndMeasuresLikeTheSolid) {
  const MeasuredCase& c = GetParam();
  const TriangleMesh mesh = meshTree(c.tree);
  ASSERT_FALSE(mesh.triangles.empty());
  EXPECT_TRUE(mesh.isClosed());
  EXPECT_GT(mesh.volume(), 0.0) << "the mesh must be oriented outwards";
  EXPECT_LT(relativeError(mesh.volume(), c.volume), 0.01)
      << "volume " << mesh.volume() << " vs " << c.volume;
  EXPECT_LT(relativeError(mesh.area(), c.area), 0.01) << "area " << mesh.area() << " vs " << c.area;
}

TEST_P(MeshPrimitive, VerticesLieOnTheSurface) {
  const MeasuredCase& c = GetParam();
  MeshOptions options;
  options.resolution = 48;
  const TriangleMesh mesh = meshTree(c.tree, options);
  const double voxel = c.tree.bounds().size().maxCoeff() / options.resolution;
  double worst = 0.0;
  for (const Vec3& v : mesh.vertices) worst = std::max(worst, std::abs(c.tree.value(v)));
  EXPECT_LT(worst, 0.5 * voxel);
  const Aabb grown = c.tree.bounds().grown(voxel);
  EXPECT_TRUE(grown.contains(mesh.bounds().min) && grown.contains(mesh.bounds().max));
}

INSTANTIATE_TEST_SUITE_P(Shapes, MeshPrimitive, ::testing::ValuesIn(primitiveCases()),
                         [](const auto& info) { return info.param.name; });

TEST(MeshTree, SharpEdgesKeepTheAreaAtLowResolution) {
  const MeasuredCase box = primitiveCases().front();
  MeshOptions options;
  options.resolution = 32;
  const TriangleMesh sharp = meshTree(box.tree, options);
  options.sharpenEdges = false;
  const TriangleMesh rounded = meshTree(box.tree, options);
  EXPECT_TRUE(sharp.isClosed());
  EXPECT_TRUE(rounded.isClosed());
  EXPECT_LT(relativeError(sharp.area(), box.area), 0.002);
  // Without sharpening every edge is chamfered by about a voxel.
  EXPECT_GT(relativeError(rounded.area(), box.area), 0.02);
  EXPECT_EQ(sharp.triangles.size(), rounded.triangles.size());
}

TEST(MeshTree, TopologyMatchesTheSolid) {
  EXPECT_EQ(eulerCharacteristic(meshTree(CsgTree::leaf(Sphere{Vec3::Zero(), 1.0}))), 2);
  EXPECT_EQ(
      eulerCharacteristic(meshTree(CsgTree::leaf(Torus{Vec3::Zero(), Vec3::UnitZ(), 1.0, 0.3}))),
      0);
  EXPECT_EQ(eulerCharacteristic(meshTree(plateWithHoles())), 2 - 2 * 4);
}

// ---------------------------------------------------------------------------
// meshTree on CSG trees

TEST(MeshTree, PlateWithHolesMatchesMonteCarloAndAnalyticMeasures) {
  const CsgTree tree = plateWithHoles();
  const TriangleMesh mesh = meshTree(tree);
  EXPECT_TRUE(mesh.isClosed());
  const double holes = 4.0 * kPi * 0.3 * 0.3;
  const double exactVolume = 4.0 * 3.0 * 0.5 - holes * 0.5;
  const double exactArea =
      2.0 * (12.0 - holes) + 2.0 * (4.0 + 3.0) * 0.5 + 4.0 * 2.0 * kPi * 0.3 * 0.5;
  const double mcVolume = monteCarloVolume(tree, 1'000'000, 7);
  ASSERT_LT(relativeError(mcVolume, exactVolume), 0.005) << "Monte-Carlo estimate itself";
  EXPECT_LT(relativeError(mesh.volume(), mcVolume), 0.01);
  EXPECT_LT(relativeError(mesh.volume(), exactVolume), 0.01);
  EXPECT_LT(relativeError(mesh.area(), exactArea), 0.01) << mesh.area() << " vs " << exactArea;
}

TEST(MeshTree, BracketMatchesMonteCarloVolumeAndConverges) {
  const CsgTree tree = bracket();
  const TriangleMesh mesh = meshTree(tree);
  EXPECT_TRUE(mesh.isClosed());
  EXPECT_EQ(eulerCharacteristic(mesh), 2);
  EXPECT_LT(relativeError(mesh.volume(), monteCarloVolume(tree, 1'000'000, 11)), 0.01);
  // No closed form for the area: compare with a mesh twice as fine.
  MeshOptions fine;
  fine.resolution = 2 * MeshOptions{}.resolution;
  EXPECT_LT(relativeError(mesh.area(), meshTree(tree, fine).area()), 0.01);
}

TEST(MeshTree, AdaptiveMeshIsClosedWithFewerTriangles) {
  const CsgTree tree = bracket();
  MeshOptions options;
  options.adaptivity = 0.5;
  const TriangleMesh adaptive = meshTree(tree, options);
  const TriangleMesh uniform = meshTree(tree);
  EXPECT_TRUE(adaptive.isClosed());
  EXPECT_LT(adaptive.triangles.size(), uniform.triangles.size() / 4);
  EXPECT_LT(relativeError(adaptive.volume(), uniform.volume()), 0.01);
}

TEST(MeshTree, PartFarFromTheOriginKeepsItsPrecision) {
  const Vec3 far(25000.0, -40000.0, 12000.0);
  const Primitive box = Box{far, rotation(0.5, Vec3(1, 0, 1)), Vec3(1.0, 0.5, 0.25)};
  MeshOptions options;
  options.resolution = 64;
  const TriangleMesh mesh = meshTree(CsgTree::leaf(box), options);
  EXPECT_TRUE(mesh.isClosed());
  EXPECT_LT(relativeError(mesh.volume(), box.volume()), 0.002);
  EXPECT_LT(relativeError(mesh.area(), box.surfaceArea()), 0.002);
}

TEST(MeshTree, EmptyBoundedSolidGivesAnEmptyMesh) {
  const CsgTree tree = CsgTree::subtract(
      {CsgTree::leaf(Sphere{Vec3::Zero(), 1.0}), CsgTree::leaf(Sphere{Vec3::Zero(), 2.0})});
  const TriangleMesh mesh = meshTree(tree);
  EXPECT_TRUE(mesh.triangles.empty());
}

TEST(MeshTree, RejectsBadTreesAndOptions) {
  const CsgTree sphere = CsgTree::leaf(Sphere{Vec3::Zero(), 1.0});
  EXPECT_THROW(meshTree(CsgTree()), std::invalid_argument);
  EXPECT_THROW(meshTree(CsgTree::leaf(HalfSpace{})), std::invalid_argument);
  EXPECT_THROW(meshTree(CsgTree::complement(sphere)), std::invalid_argument);
  const CsgTree disjoint =
      CsgTree::intersect({sphere, CsgTree::leaf(Sphere{Vec3(5, 0, 0), 1.0})});  // empty bounds
  EXPECT_THROW(meshTree(disjoint), std::invalid_argument);
  EXPECT_THROW(meshTree(CsgTree::leaf(Sphere{Vec3::Zero(), -1.0})), std::invalid_argument);
  for (const int resolution : {-1, 0, 7, 2049}) {
    MeshOptions options;
    options.resolution = resolution;
    EXPECT_THROW(meshTree(sphere, options), std::invalid_argument) << resolution;
  }
  MeshOptions options;
  options.adaptivity = 1.5;
  EXPECT_THROW(meshTree(sphere, options), std::invalid_argument);
}

TEST(MeshTree, RefusesToExceedTheMemoryLimit) {
  const CsgTree sphere = CsgTree::leaf(Sphere{Vec3::Zero(), 1.0});
  MeshOptions options;
  options.resolution = 256;
  options.memoryLimitMiB = 1.0;
  expectThrowWith<std::invalid_argument>([&] { meshTree(sphere, options); }, "memoryLimitMiB");
  // Eight thin fins at the largest resolution would need about 20 GiB: they
  // are refused up front at the default limit rather than exhausting memory.
  std::vector<CsgTree> fins;
  for (int k = 0; k < 8; ++k) {
    fins.push_back(
        CsgTree::leaf(Box{Vec3(0, 0, -0.9 + 0.25 * k), Mat3::Identity(), Vec3(1, 1, 0.02)}));
  }
  options = MeshOptions{};
  options.resolution = 2048;
  expectThrowWith<std::invalid_argument>([&] { meshTree(CsgTree::unite(fins), options); }, "MiB");
}

TEST(MeshTree, RejectsPrimitivesThatCannotBeMeshedNamingThem) {
  // Too large for single-precision vertices (was: an STL with 0 triangles or
  // with -inf coordinates), too small for OpenVDB's transform (was OpenVDB's
  // "ArithmeticError: Non-zero scale values required").
  const CsgTree base = CsgTree::leaf(Box{Vec3::Zero(), Mat3::Identity(), Vec3(1, 1, 1)}, "base");
  for (const double radius : {1e300, 1e40}) {
    expectThrowWith<std::invalid_argument>(
        [&] {
          meshTree(CsgTree::unite({base, CsgTree::leaf(Sphere{Vec3::Zero(), radius}, "ball")}));
        },
        "sphere 'ball' (leaf 2");
    expectThrowWith<std::invalid_argument>(
        [&] {
          meshTree(CsgTree::leaf(Sphere{Vec3::Zero(), radius}));
        },
        "too large");
  }
  expectThrowWith<std::invalid_argument>(
      [&] {
        meshTree(CsgTree::leaf(Sphere{Vec3::Zero(), 1e-30}));
      },
      "sphere (leaf 1 in depth-first order) is too small for the mesh resolution");
  // A part far out of range is refused too, not only a large one.
  expectThrowWith<std::invalid_argument>(
      [&] {
        meshTree(CsgTree::leaf(Sphere{Vec3(1e31, 0, 0), 1}));
      },
      "too large");
  // Small but representable parts still mesh.
  const Primitive small = Sphere{Vec3(1, 2, 3), 0.01};
  MeshOptions options;
  options.resolution = 64;
  const TriangleMesh mesh = meshTree(CsgTree::leaf(small), options);
  EXPECT_LT(relativeError(mesh.volume(), small.volume()), 0.01);
}

// n^3 spheres of radius r on a unit grid, with names.
CsgTree sphereLattice(int n, double r) {
  std::vector<CsgTree> spheres;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      for (int k = 0; k < n; ++k) spheres.push_back(CsgTree::leaf(Sphere{Vec3(i, j, k), r}));
    }
  }
  return CsgTree::unite(spheres);
}

TEST(MeshTree, UnionOfTenThousandSpheresMeshesLikeTheSpheres) {
  // 22^3 = 10648 disjoint spheres. The mesher evaluates only the spheres near
  // each block of voxels (this took about two minutes when every voxel
  // evaluated every sphere).
  const int n = 22;
  const double r = 0.35;
  const CsgTree tree = sphereLattice(n, r);
  const MeshOptions options;  // 160: about 2.5 voxels per radius
  std::vector<std::string> stages;
  double last = -1.0;
  bool monotone = true;
  const TriangleMesh mesh =
      meshTree(tree, options, RunControl(0.0, [&](double fraction, std::string_view stage) {
                 if (stages.empty() || stages.back() != stage) {
                   stages.emplace_back(stage);
                   last = -1.0;
                 }
                 monotone = monotone && fraction >= last && fraction <= 1.0;
                 last = fraction;
                 return true;
               }));
  EXPECT_TRUE(mesh.isClosed());
  const double sphereVolume = 4.0 / 3.0 * kPi * r * r * r;
  // Spheres 2.5 voxels in radius: within a few percent.
  EXPECT_LT(relativeError(mesh.volume(), n * n * n * sphereVolume), 0.05);
  EXPECT_EQ(stages, (std::vector<std::string>{"cull", "sample", "polygonise", "sharpen"}));
  EXPECT_TRUE(monotone);
  // Every vertex lies on the surface of one of the spheres.
  double worst = 0.0;
  for (const Vec3& v : mesh.vertices) {
    const Vec3 c = v.array().round();
    worst = std::max(worst, std::abs((v - c).norm() - r));
  }
  EXPECT_LT(worst, 0.1 * r);  // a voxel is 0.4 r
}

TEST(MeshTree, PrunedMeshingGivesTheSameMeshAsTheWholeTree) {
  // The same solid with 400 far-off leaves that cannot reach the surface
  // subtracted: each is dropped where it cannot matter, and the mesh is the
  // same, vertex for vertex.
  const CsgTree part = sphereLattice(3, 0.4);
  std::vector<CsgTree> operands = {part};
  for (int i = 0; i < 400; ++i) {
    operands.push_back(CsgTree::leaf(Sphere{Vec3(0.5, 0.5, 0.5) + 0.001 * Vec3(i, 0, 0), 0.01}));
  }
  const CsgTree withTools = CsgTree::subtract(operands);
  MeshOptions options;
  options.resolution = 96;
  const TriangleMesh a = meshTree(part, options);
  const TriangleMesh b = meshTree(withTools, options);
  ASSERT_EQ(a.vertices.size(), b.vertices.size());
  ASSERT_EQ(a.triangles.size(), b.triangles.size());
  EXPECT_TRUE(a.vertices == b.vertices);
  EXPECT_TRUE(a.triangles == b.triangles);
}

TEST(MeshTree, ProgressCanStopTheMeshing) {
  const CsgTree tree = sphereLattice(4, 0.3);
  int calls = 0;
  expectThrowWith<std::runtime_error>(
      [&] {
        meshTree(tree, {}, RunControl(0.0, [&](double, std::string_view stage) {
                   ++calls;
                   return stage != "sample";
                 }));
      },
      "cancelled");
  EXPECT_GT(calls, 0);
}

// ---------------------------------------------------------------------------
// TriangleMesh measures

TriangleMesh unitTetrahedron() {
  TriangleMesh m;
  m.vertices = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)};
  m.triangles = {{{0, 2, 1}}, {{0, 1, 3}}, {{0, 3, 2}}, {{1, 2, 3}}};
  return m;
}

TEST(TriangleMesh, MeasuresOfATetrahedron) {
  TriangleMesh m = unitTetrahedron();
  EXPECT_NEAR(m.volume(), 1.0 / 6.0, 1e-15);
  EXPECT_NEAR(m.area(), 1.5 + std::sqrt(3.0) / 2.0, 1e-15);
  EXPECT_TRUE(m.isClosed());
  test::expectNear(m.bounds().min, Vec3::Zero(), 0.0);
  test::expectNear(m.bounds().max, Vec3::Ones(), 0.0);
  std::swap(m.triangles[0][0], m.triangles[0][1]);  // one face flipped
  EXPECT_FALSE(m.isClosed());
  m = unitTetrahedron();
  m.triangles.pop_back();  // a hole
  EXPECT_FALSE(m.isClosed());
  m = unitTetrahedron();
  m.triangles.push_back({{0, 0, 1}});  // degenerate
  EXPECT_FALSE(m.isClosed());
  EXPECT_TRUE(TriangleMesh{}.isClosed());
  EXPECT_TRUE(TriangleMesh{}.bounds().isEmpty());
}

// ---------------------------------------------------------------------------
// Mesh files

class MeshFileRoundTrip : public ::testing::TestWithParam<std::string> {};

TEST_P(MeshFileRoundTrip, ReadsBackTheSameClosedMesh) {
  const std::string ext = GetParam();
  MeshOptions options;
  options.resolution = 24;
  const TriangleMesh mesh = meshTree(bracket(), options);
  ASSERT_TRUE(mesh.isClosed());
  TempDir dir;
  const fs::path path = dir.path() / ("bracket." + ext);
  writeMesh(path, mesh);
  const TriangleMesh back = readMesh(path);
  EXPECT_TRUE(back.isClosed());
  EXPECT_EQ(back.triangles.size(), mesh.triangles.size());
  EXPECT_EQ(back.vertices.size(), mesh.vertices.size());
  EXPECT_LT(relativeError(back.volume(), mesh.volume()), 1e-5);
  EXPECT_LT(relativeError(back.area(), mesh.area()), 1e-5);
  if (ext == "stl") return;  // STL stores triangles only: vertex order changes
  EXPECT_EQ(back.triangles, mesh.triangles);
  const double tolerance = ext == "obj" ? 0.0 : 1e-6;  // OBJ text is exact, PLY is float
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    ASSERT_TRUE(test::vecNear(back.vertices[i], mesh.vertices[i], tolerance)) << "vertex " << i;
  }
}

INSTANTIATE_TEST_SUITE_P(Formats, MeshFileRoundTrip, ::testing::Values("ply", "stl", "obj"));

TEST(MeshFiles, StreamWritersProduceTheExpectedLayout) {
  const TriangleMesh tet = unitTetrahedron();
  std::ostringstream stl(std::ios::binary);
  writeMeshStl(stl, tet);
  EXPECT_EQ(stl.str().size(), 84u + 50u * tet.triangles.size());
  EXPECT_NE(stl.str().rfind("solid", 0), 0u) << "a binary STL must not start with 'solid'";
  std::ostringstream ply(std::ios::binary);
  writeMeshPly(ply, tet);
  EXPECT_EQ(ply.str().rfind("ply\nformat binary_little_endian 1.0\n", 0), 0u);
  std::ostringstream obj;
  writeMeshObj(obj, tet);
  EXPECT_NE(obj.str().find("\nv 0 0 1\n"), std::string::npos);
  EXPECT_NE(obj.str().find("\nf 2 3 4\n"), std::string::npos);
  TriangleMesh bad = tet;
  bad.triangles.push_back({{0, 1, 9}});
  std::ostringstream sink;
  EXPECT_THROW(writeMeshObj(sink, bad), std::invalid_argument);
}

TEST(MeshFiles, ReadsAsciiStlAndPolygonOff) {
  TempDir dir;
  // ASCII STL as OpenSCAD writes it: shared corners are repeated per facet.
  std::string stl = "solid OpenSCAD_Model\n";
  const TriangleMesh tet = unitTetrahedron();
  for (const auto& t : tet.triangles) {
    stl += "  facet normal 0 0 0\n    outer loop\n";
    for (const std::uint32_t i : t) {
      const Vec3& v = tet.vertices[i];
      stl += "      vertex " + std::to_string(v.x()) + " " + std::to_string(v.y()) + " " +
             std::to_string(v.z()) + "\n";
    }
    stl += "    endloop\n  endfacet\n";
  }
  stl += "endsolid OpenSCAD_Model\n";
  writeText(dir.path() / "tet.stl", stl);
  const TriangleMesh fromStl = readMesh(dir.path() / "tet.stl");
  EXPECT_EQ(fromStl.vertices.size(), 4u);
  EXPECT_TRUE(fromStl.isClosed());
  EXPECT_NEAR(fromStl.volume(), 1.0 / 6.0, 1e-12);

  // A unit cube of quads: split into 12 triangles.
  writeText(dir.path() / "cube.OFF",
            "OFF\n8 6 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 0 1\n1 0 1\n1 1 1\n0 1 1\n"
            "4 0 3 2 1\n4 4 5 6 7\n4 0 1 5 4\n4 1 2 6 5\n4 2 3 7 6\n4 3 0 4 7\n");
  const TriangleMesh cube = readMesh(dir.path() / "cube.OFF");
  EXPECT_EQ(cube.triangles.size(), 12u);
  EXPECT_TRUE(cube.isClosed());
  EXPECT_NEAR(cube.volume(), 1.0, 1e-12);
  EXPECT_NEAR(cube.area(), 6.0, 1e-12);
}

TEST(MeshFiles, BadPathsAndContentThrowNamingTheFile) {
  TempDir dir;
  const TriangleMesh tet = unitTetrahedron();
  const fs::path missing = dir.path() / "missing.stl";
  expectThrowWith<IoError>([&] { readMesh(missing); }, missing.string());
  expectThrowWith<IoError>([&] { readMesh(dir.path()); }, dir.path().string());
  writeText(dir.path() / "mesh.xyz", "0 0 0\n");
  expectThrowWith<IoError>([&] { readMesh(dir.path() / "mesh.xyz"); }, "mesh.xyz");

  const std::vector<std::pair<std::string, std::string>> corrupt = {
      {"garbage.obj", "this is not a mesh\n"},
      {"empty.stl", ""},
      {"truncated.stl", std::string(80, 'x') + std::string("\x05\x00\x00\x00", 4) + "abc"},
      {"badindex.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n"},
      {"nan.obj", "v 0 0 nan\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"},
      {"short.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n"},
      {"header.ply", "ply\nformat ascii 1.0\nelement vertex 3\nend_header\n1 2\n"},
  };
  for (const auto& [name, content] : corrupt) {
    writeText(dir.path() / name, content);
    expectThrowWith<ParseError>([&] { readMesh(dir.path() / name); }, name);
  }

  expectThrowWith<IoError>([&] { writeMesh(dir.path() / "no_dir" / "m.stl", tet); }, "m.stl");
  expectThrowWith<IoError>([&] { writeMesh(dir.path() / "m.xyz", tet); }, "m.xyz");
  expectThrowWith<IoError>([&] { writeMesh(dir.path(), tet); }, dir.path().string());
  EXPECT_FALSE(fs::exists(dir.path() / "m.xyz"));
}

// ---------------------------------------------------------------------------
// MeshSolid

TEST(MeshSolid, AgreesWithTheTreeItWasMeshedFrom) {
  const CsgTree tree = bracket();
  const TriangleMesh mesh = meshTree(tree);
  const double voxel = tree.bounds().size().maxCoeff() / 160.0;
  const MeshSolid solid(mesh, voxel);
  EXPECT_EQ(solid.voxelSize(), voxel);
  const Aabb box = tree.bounds().grown(0.05 * tree.bounds().diagonal());
  Rng rng(5);
  constexpr int kSamples = 200'000;
  int agree = 0;
  for (int i = 0; i < kSamples; ++i) {
    const Vec3 p = test::randomPoint(rng, box);
    agree += solid.contains(p) == tree.contains(p);
  }
  EXPECT_GE(agree, 0.995 * kSamples);
  EXPECT_FALSE(solid.contains(Vec3(100, 0, 0)));
  EXPECT_TRUE(solid.contains(Vec3(0, 0, -0.5)));
}

TEST(MeshSolid, VolumeFromContainsMatchesTheMesh) {
  const TriangleMesh mesh = meshTree(plateWithHoles());
  const MeshSolid solid(mesh, 0.02);
  const Aabb box = mesh.bounds();
  Rng rng(3);
  constexpr int kSamples = 200'000;
  int inside = 0;
  for (int i = 0; i < kSamples; ++i) inside += solid.contains(test::randomPoint(rng, box));
  EXPECT_LT(relativeError(box.size().prod() * inside / kSamples, mesh.volume()), 0.01);
}

TEST(MeshSolid, RejectsOpenMeshesAndBadVoxelSizes) {
  TriangleMesh open = unitTetrahedron();
  open.triangles.pop_back();
  expectThrowWith<std::invalid_argument>([&] { MeshSolid(open, 0.1); }, "not closed");
  EXPECT_THROW(MeshSolid(TriangleMesh{}, 0.1), std::invalid_argument);
  EXPECT_THROW(MeshSolid(unitTetrahedron(), 0.0), std::invalid_argument);
  EXPECT_THROW(MeshSolid(unitTetrahedron(), -1.0), std::invalid_argument);
  EXPECT_THROW(MeshSolid(unitTetrahedron(), 1e-6), std::invalid_argument);  // too many voxels
  const MeshSolid coarse(unitTetrahedron(), 0.02);
  EXPECT_TRUE(coarse.contains(Vec3(0.1, 0.1, 0.1)));
  EXPECT_FALSE(coarse.contains(Vec3(0.5, 0.5, 0.5)));
}

}  // namespace
}  // namespace csgvox
