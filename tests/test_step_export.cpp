// tree.step: every bundled part written as STEP and read back with
// OpenCASCADE's own reader is one valid closed solid with the tree's volume
// and bounds; half-spaces and complements clip as they should; a tree with
// no solid is refused with a message.

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <algorithm>
#include <set>
#include <thread>

#include "cad/step_export.h"
#include "cli_helpers.h"
#include "core/export_extent.h"
#include "io/errors.h"
#include "io/tree_json.h"
#include "io/tree_names.h"
#include "part_list.h"
#include "solid_sampling.h"
#include "temp_dir_test.h"
#include "test_helpers.h"

namespace csgvox {
namespace {

class StepExport : public test::TempDirTest {
 protected:
  void SetUp() override {
    if (!stepExportAvailable()) GTEST_SKIP() << "built without OpenCASCADE (CSGVOX_WITH_OCCT=OFF)";
    TempDirTest::SetUp();
  }
};

TEST_F(StepExport, EveryBundledPartIsOneValidSolidWithTheTreesVolumeAndBounds) {
  for (const std::string& part : test::partNames()) {
    SCOPED_TRACE(part);
    const CsgTree tree = readTreeJson(test::dataDir() / part / "tree.json");
    const fs::path path = dir_ / (part + ".step");
    const auto t0 = std::chrono::steady_clock::now();
    const BrepSummary written = writeStep(path, tree);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const BrepSummary read = readStepSummary(path);
    EXPECT_EQ(read.solids, 1u);
    EXPECT_TRUE(read.valid);
    EXPECT_TRUE(read.closed);

    const Aabb extent = exportExtent(tree);
    const test::SolidSample sample =
        test::sampleSolid(tree, extent.grown(0.01 * extent.diagonal()), 100);
    const double volumeError = read.volume / sample.volume - 1.0;
    EXPECT_LT(std::abs(volumeError), 0.005) << read.volume << " vs sampled " << sample.volume;
    EXPECT_NEAR(read.volume, written.volume, 1e-6 * written.volume);
    // The sampled inside points lie within a cell of the solid's bounds.
    for (int i = 0; i < 3; ++i) {
      EXPECT_LE(read.bounds.min[i], sample.inside.min[i] + 1e-6);
      EXPECT_GE(read.bounds.min[i], sample.inside.min[i] - 1.01 * sample.cell[i]);
      EXPECT_GE(read.bounds.max[i], sample.inside.max[i] - 1e-6);
      EXPECT_LE(read.bounds.max[i], sample.inside.max[i] + 1.01 * sample.cell[i]);
    }
    // Every face lies on a primitive and carries its name in the file; a
    // primitive may leave no face of its own (a fillet ring whose faces lie
    // on its neighbours'), at most one per part here.
    EXPECT_EQ(written.namedFaces, written.faces);
    const std::string text = slurp(path);
    EXPECT_NE(text.find("AUTOMOTIVE_DESIGN"), std::string::npos);  // AP214
    std::set<std::string> leafNameSet, faceNames;
    for (const auto& entry : leafNames(tree)) leafNameSet.insert(entry.second);
    std::size_t namedInFile = 0;
    for (std::size_t at = text.find("ADVANCED_FACE('"); at != std::string::npos;
         at = text.find("ADVANCED_FACE('", at + 1)) {
      const std::size_t begin = at + 15;
      const std::string name = text.substr(begin, text.find('\'', begin) - begin);
      EXPECT_TRUE(leafNameSet.count(name)) << "face named '" << name << "'";
      faceNames.insert(name);
      ++namedInFile;
    }
    EXPECT_EQ(namedInFile, read.faces);
    EXPECT_GE(faceNames.size() + 1, leafNameSet.size());
    std::printf("[ step ] %-18s %3zu faces, volume %+.3f %% of sampled, written in %.3f s\n",
                part.c_str(), read.faces, 100 * volumeError, seconds);
  }
}

TEST_F(StepExport, HalfSpacesAndComplementsClipThePartExactly) {
  // A 2 x 2 x 2 cube cut by the plane z <= 0.5 and with a hole of radius
  // 0.5 as an intersection with a complement: volume 2*2*1.5 - pi*0.25*1.5.
  const CsgTree box = CsgTree::leaf(Box{Vec3::Zero(), Mat3::Identity(), Vec3::Ones()}, "block");
  const CsgTree cut = CsgTree::leaf(HalfSpace{Vec3::UnitZ(), 0.5}, "top");
  const CsgTree hole = CsgTree::leaf(Cylinder{Vec3::Zero(), Vec3::UnitZ(), 0.5, 3.0}, "bore");
  const CsgTree tree = CsgTree::intersect({box, cut, CsgTree::complement(hole)});
  const fs::path path = dir_ / "clipped.step";
  writeStep(path, tree);
  const BrepSummary s = readStepSummary(path);
  EXPECT_EQ(s.solids, 1u);
  EXPECT_TRUE(s.valid);
  EXPECT_NEAR(s.volume, 6.0 - std::numbers::pi * 0.25 * 1.5, 1e-6);
  EXPECT_NEAR(s.bounds.max.z(), 0.5, 1e-6);
  EXPECT_NEAR(s.bounds.min.z(), -1.0, 1e-6);
}

TEST_F(StepExport, RotatedPrimitivesKeepTheirExactVolume) {
  test::Rng rng(3);
  for (PrimitiveType type : test::allPrimitiveTypes()) {
    if (type == PrimitiveType::HalfSpace) continue;
    const Primitive p = test::randomPrimitive(type, rng);
    const fs::path path = dir_ / "one.step";
    writeStep(path, CsgTree::leaf(p));
    const BrepSummary s = readStepSummary(path);
    EXPECT_EQ(s.solids, 1u) << primitiveTypeName(type);
    EXPECT_TRUE(s.valid) << primitiveTypeName(type);
    EXPECT_NEAR(s.volume, p.volume(), 1e-6 * p.volume()) << primitiveTypeName(type);
  }
}

TEST_F(StepExport, AnEmptySolidIsRefusedAndNoFileIsLeft) {
  const CsgTree a = CsgTree::leaf(Sphere{Vec3::Zero(), 1.0}, "left");
  const CsgTree b = CsgTree::leaf(Sphere{Vec3(5, 0, 0), 1.0}, "right");
  const fs::path path = dir_ / "empty.step";
  try {
    writeStep(path, CsgTree::intersect({a, b}));
    FAIL() << "an empty solid was written";
  } catch (const CadError& e) {
    EXPECT_NE(std::string(e.what()).find("empty"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(path));
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_), fs::directory_iterator()), 0);
}

// A cancel request stops the export inside OpenCASCADE's booleans within
// 0.5 s, and no file is left; one made before the export starts stops it
// at once.
TEST_F(StepExport, ACancelStopsTheExportAndLeavesNoFile) {
  const CsgTree tree = readTreeJson(test::dataDir() / "knob" / "tree.json");
  const fs::path path = dir_ / "knob.step";
  StepOptions before;
  before.control.cancel();
  EXPECT_THROW(writeStep(path, tree, before), CancelledError);
  EXPECT_FALSE(fs::exists(path));

  // The knob's export takes more than a second: the request comes in its midst.
  StepOptions during;
  std::chrono::steady_clock::time_point asked;
  std::thread canceller([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    asked = std::chrono::steady_clock::now();
    during.control.cancel();
  });
  EXPECT_THROW(writeStep(path, tree, during), CancelledError);
  const auto ended = std::chrono::steady_clock::now();
  canceller.join();
  EXPECT_LT(std::chrono::duration<double>(ended - asked).count(), 0.5 * CSGVOX_TEST_SLOWDOWN);
  EXPECT_FALSE(fs::exists(path));
  EXPECT_EQ(std::count_if(fs::directory_iterator(dir_), fs::directory_iterator(),
                          [](const fs::directory_entry& e) {
                            return e.path().filename().string().find(".tmp-") != std::string::npos;
                          }),
            0);
}

TEST_F(StepExport, ReadingANonStepFileIsAParseError) {
  const fs::path path = write("bad.step", "not a step file\n");
  EXPECT_THROW(readStepSummary(path), ParseError);
  EXPECT_THROW(readStepSummary(dir_ / "missing.step"), IoError);
}

}  // namespace
}  // namespace csgvox

namespace csgvox {
namespace {

// Trees the main job reconstructed from data/bearing_housing/scan.ply, on
// which OpenCASCADE 7.6's booleans return a valid but wrong solid: a box
// minus a torus tangent to its bottom face, intersected with a cylinder,
// comes out empty (occt-wrong-intersection, an earlier build's tree); the
// sphere cut from the union of the plate, the fillet ring and the boss
// leaves the inside of the ring in place, +7 % (occt-wrong-sphere-cut, this
// build's). Both are now written as one solid of the tree's volume (fuzzy
// booleans, or the caps snapped onto the torus's planes).
void expectOneSolidOfTheTreesVolume(const CsgTree& tree, const fs::path& path) {
  writeStep(path, tree);
  const BrepSummary s = readStepSummary(path);
  EXPECT_EQ(s.solids, 1u);
  EXPECT_TRUE(s.valid);
  EXPECT_TRUE(s.closed);
  const Aabb extent = exportExtent(tree);
  const double sampled =
      test::sampleSolid(tree, extent.grown(0.01 * extent.diagonal()), 100).volume;
  EXPECT_LT(std::abs(s.volume / sampled - 1.0), 0.005) << s.volume << " vs sampled " << sampled;
}

TEST_F(StepExport, TreesOpenCascadeGetsWrongAsTheyAreComeOutAsOneSolidOfTheirVolume) {
  for (const char* name : {"occt-wrong-intersection.json", "occt-wrong-sphere-cut.json"}) {
    SCOPED_TRACE(name);
    const CsgTree tree = readTreeJson(test::dataDir() / "regressions" / name);
    expectOneSolidOfTheTreesVolume(tree, dir_ / "right.step");
  }
}

TEST_F(StepExport, WithoutTheRetriesAWrongBooleanResultIsRefusedNamingTheNode) {
  const CsgTree tree =
      readTreeJson(test::dataDir() / "regressions" / "occt-wrong-intersection.json");
  const fs::path path = dir_ / "wrong.step";
  StepOptions options;
  options.snapTolerance = 0.0;
  options.retryFuzzy = 0.0;
  try {
    writeStep(path, tree, options);
    FAIL() << "a solid with the wrong volume was written";
  } catch (const CadError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("the intersection at node root/0/2 (difference of 2, cylinder7)"),
              std::string::npos)
        << what;
  }
  EXPECT_FALSE(fs::exists(path));
}

// The tree the main job reconstructs from
// data/regressions/inversecsg-143-60k.ply at resolution 110 (62
// primitives): OpenCASCADE's booleans leave a solid 3.6 % too large
// however it is retried, and merging the faces of those wrong solids ran
// for more than ten minutes. It is refused, naming the node, after the
// booleans alone (about 6 s); the ctest timeout is the bound.
TEST_F(StepExport, ATreeOpenCascadeCannotBuildIsRefusedWithoutMergingItsWrongSolids) {
  const CsgTree tree = readTreeJson(test::dataDir() / "regressions" / "occt-wrong-solid-143.json");
  const fs::path path = dir_ / "wrong.step";
  try {
    writeStep(path, tree);
    FAIL() << "a solid with the wrong volume was written";
  } catch (const CadError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("OpenCASCADE computed a wrong solid for the difference at node root/0/0"),
              std::string::npos)
        << what;
  }
  EXPECT_FALSE(fs::exists(path));
}

// Trees the main job reconstructed from the bundled scans (clean
// stepped_shaft and funnel, noisy flange) whose pieces the fit left
// 0.04-0.14 mm apart (below 0.1 % of the diagonal): as they are, they are
// 2 or 3 solids; written, one.
TEST_F(StepExport, ReconstructedTreesWithSliversBetweenPiecesComeOutAsOneSolid) {
  for (const char* name : {"step-slivers-stepped-shaft.json", "step-slivers-flange-noisy.json",
                           "step-slivers-funnel.json"}) {
    SCOPED_TRACE(name);
    const CsgTree tree = readTreeJson(test::dataDir() / "regressions" / name);
    StepOptions asTheyAre;
    asTheyAre.snapTolerance = 0.0;
    asTheyAre.retryFuzzy = 0.0;
    EXPECT_GE(writeStep(dir_ / "pieces.step", tree, asTheyAre).solids, 2u);
    expectOneSolidOfTheTreesVolume(tree, dir_ / "one.step");
  }
}

// A cylinder standing on a plate 0.01 above or below its top face (the
// diagonal is about 17, the snapping tolerance 0.02): one solid, the
// cylinder's cap on the plate's face; 0.5 above, two solids as the tree
// says.
TEST_F(StepExport, APieceAFewHundredthsOffItsNeighbourJoinsIt) {
  const CsgTree plate =
      CsgTree::leaf(Box{Vec3(5, 5, 2.5), Mat3::Identity(), Vec3(5, 5, 2.5)}, "plate");
  for (const double gap : {0.01, -0.01, 0.5}) {
    SCOPED_TRACE(gap);
    const double bottom = 5.0 + gap;
    const CsgTree boss = CsgTree::leaf(
        Cylinder{Vec3(5, 5, 0.5 * (bottom + 10.0)), Vec3::UnitZ(), 3.0, 10.0 - bottom}, "boss");
    const fs::path path = dir_ / "boss.step";
    writeStep(path, CsgTree::unite({plate, boss}));
    const BrepSummary s = readStepSummary(path);
    EXPECT_TRUE(s.valid);
    if (gap == 0.5) {
      EXPECT_EQ(s.solids, 2u);
      EXPECT_NEAR(s.volume, 500.0 + std::numbers::pi * 9.0 * 4.5, 1e-6);
    } else {
      EXPECT_EQ(s.solids, 1u);
      EXPECT_NEAR(s.volume, 500.0 + std::numbers::pi * 9.0 * 5.0, 1e-6);
      EXPECT_NEAR(s.bounds.max.z(), 10.0, 1e-6);
    }
  }
}

}  // namespace
}  // namespace csgvox
