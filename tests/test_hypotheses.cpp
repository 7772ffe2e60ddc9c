// Tests of generateHypotheses (primitives/hypotheses.h): Wu's cuboid
// enumeration and filters on small hand-made scans, the quadric, additional,
// indirect and separator candidates, and every bundled part against its
// ground truth (clean and noisy, axis-aligned and rotated).

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <map>
#include <numbers>
#include <optional>
#include <span>
#include <string>

#include "candidate_matching.h"
#include "io/tree_json.h"
#include "part_list.h"
#include "primitives/hypotheses.h"
#include "test_helpers.h"

namespace csgvox {
namespace {

using test::GroundTruth;
using test::makeGroundTruth;

constexpr double kNoise = 0.005;  // fraction of D

// Ground truth of a bundled part, computed once per (part, noise).
const GroundTruth& partTruth(const std::string& part, double noise) {
  static std::map<std::pair<std::string, double>, GroundTruth> cache;
  const auto key = std::make_pair(part, noise);
  auto it = cache.find(key);
  if (it == cache.end()) {
    const CsgTree tree = readTreeJson(test::dataDir() / part / "tree.json");
    it = cache.emplace(key, makeGroundTruth(tree, 20000, noise, 7)).first;
  }
  return it->second;
}

// Candidates of one origin.
std::vector<const Candidate*> ofOrigin(const HypothesisSet& set, CandidateOrigin origin) {
  std::vector<const Candidate*> out;
  for (const Candidate& c : set.candidates) {
    if (c.origin == origin) out.push_back(&c);
  }
  return out;
}

// The surfaces of `gt` with the given indices.
std::vector<Surface> pick(const GroundTruth& gt, std::initializer_list<std::size_t> which) {
  std::vector<Surface> out;
  for (std::size_t i : which) out.push_back(gt.surfaces[i]);
  return out;
}

// Index of the ground-truth surface of `leaf`'s piece `piece`, or -1.
int surfaceOf(const GroundTruth& gt, int leaf, int piece) {
  for (std::size_t s = 0; s < gt.surfaces.size(); ++s) {
    if (gt.surfaceLeaf[s] == leaf && gt.surfacePiece[s] == piece) return static_cast<int>(s);
  }
  return -1;
}

// A box candidate spanning [lo, hi] in world axes (within tol), if any.
const Candidate* findBox(const HypothesisSet& set, const Vec3& lo, const Vec3& hi, double tol) {
  for (const Candidate& c : set.candidates) {
    const Node& n = *c.tree.root();
    if (n.kind != NodeKind::Primitive || n.primitive.type() != PrimitiveType::Box) continue;
    const Box& b = *n.primitive.as<Box>();
    // Compare the corners' ranges along the world axes.
    Vec3 bmin = Vec3::Constant(1e300), bmax = Vec3::Constant(-1e300);
    for (int k = 0; k < 8; ++k) {
      const Vec3 s((k & 1) ? 1 : -1, (k & 2) ? 1 : -1, (k & 4) ? 1 : -1);
      const Vec3 corner = b.center + b.axes * s.cwiseProduct(b.halfSize);
      bmin = bmin.cwiseMin(corner), bmax = bmax.cwiseMax(corner);
    }
    if ((bmin - lo).cwiseAbs().maxCoeff() <= tol && (bmax - hi).cwiseAbs().maxCoeff() <= tol) {
      return &c;
    }
  }
  return nullptr;
}

TEST(Hypotheses, EmptySurfaceListGivesAnEmptySet) {
  const GroundTruth& gt = partTruth("plate_holes", 0.0);
  const HypothesisSet set = generateHypotheses(gt.scan, {});
  EXPECT_TRUE(set.candidates.empty());
  EXPECT_EQ(set.stats.returned.total(), 0u);
  EXPECT_TRUE(generateHypotheses(PointCloud{}, {}).candidates.empty());
}

TEST(Hypotheses, InlierOutsideTheScanThrows) {
  const GroundTruth& gt = partTruth("plate_holes", 0.0);
  std::vector<Surface> surfaces = pick(gt, {0});
  surfaces[0].inliers.push_back(static_cast<std::uint32_t>(gt.scan.size()));
  EXPECT_THROW(generateHypotheses(gt.scan, surfaces), std::invalid_argument);
}

// A single 4 x 3 x 2 box with its six face patches. Eq. 3: 2^6 + 6 = 70
// (with the empty selection); 57 selections of two or more patches, all
// facing outwards, all give the whole box; 6 single patches give 12 boxes.
// Filter 3 keeps the six-patch box and rejects the 56 other multi-patch
// selections (their patch sets are subsets); each single patch keeps its two
// boxes (behind it, as deep as its longest side, and in front of it), none
// of which is the whole box.
TEST(Hypotheses, SingleBoxEq3CountAndExactSurvivors) {
  const CsgTree tree = CsgTree::leaf(Box{Vec3::Zero(), Mat3::Identity(), Vec3(2, 1.5, 1)});
  const GroundTruth gt = makeGroundTruth(tree, 20000, 0.0, 3);
  ASSERT_EQ(gt.surfaces.size(), 6u);
  const HypothesisSet set = generateHypotheses(gt.scan, gt.surfaces);
  const CuboidStats& st = set.stats.cuboids;
  EXPECT_EQ(st.planes, 6u);
  EXPECT_EQ(st.directionSets, 3u);
  EXPECT_EQ(st.triangleGroups, 1u);
  EXPECT_EQ(st.edgeGroups + st.singleGroups, 0u);
  EXPECT_EQ(st.eq3Count, 70u);
  EXPECT_EQ(st.considered, 69u);
  EXPECT_EQ(st.rejectedOrientation, 0u);
  EXPECT_EQ(st.rejectedDegenerate, 0u);
  EXPECT_EQ(st.rejectedFit, 0u);
  EXPECT_EQ(st.rejectedRedundant, 56u);
  EXPECT_EQ(st.kept, 13u);
  EXPECT_EQ(st.keptTool, 6u);
  EXPECT_FALSE(st.patchesCapped || st.enumerationCapped);
  ASSERT_EQ(ofOrigin(set, CandidateOrigin::Cuboid).size(), 13u);
  EXPECT_EQ(set.candidates.size(), 13u);  // no quadric, and every plane is in the box

  const double tol = 0.01;
  const Candidate* whole = findBox(set, Vec3(-2, -1.5, -1), Vec3(2, 1.5, 1), tol);
  ASSERT_NE(whole, nullptr);
  EXPECT_EQ(whole->surfaces, (std::vector<int>{0, 1, 2, 3, 4, 5}));
  EXPECT_FALSE(whole->tool);
  // Single patches: the +x face (3 x 2, longest side 3) gives [-1, 2] behind
  // and [2, 5] in front; the +z face (4 x 3) gives [-3, 1] and [1, 5].
  const Vec3 lo(-2, -1.5, -1), hi(2, 1.5, 1);
  for (int axis = 0; axis < 3; ++axis) {
    double longest = 0.0;
    for (int k = 0; k < 3; ++k) {
      if (k != axis) longest = std::max(longest, hi[k] - lo[k]);
    }
    for (double side : {1.0, -1.0}) {
      const double face = side > 0 ? hi[axis] : lo[axis];
      Vec3 a = lo, b = hi;  // behind the face
      (side > 0 ? a : b)[axis] = face - side * longest;
      const Candidate* behind = findBox(set, a.cwiseMin(b), a.cwiseMax(b), tol);
      Vec3 c = lo, d = hi;  // in front of it
      c[axis] = face, d[axis] = face + side * longest;
      const Candidate* front = findBox(set, c.cwiseMin(d), c.cwiseMax(d), tol);
      ASSERT_NE(behind, nullptr) << "axis " << axis << " side " << side;
      ASSERT_NE(front, nullptr) << "axis " << axis << " side " << side;
      EXPECT_EQ(behind->surfaces.size(), 1u);
      EXPECT_FALSE(behind->tool);
      EXPECT_TRUE(front->tool);
    }
  }
}

// The same box turned arbitrarily gives the same counts (nothing depends on
// the world axes).
TEST(Hypotheses, SingleBoxCountsDoNotDependOnOrientation) {
  test::Rng rng(11);
  const Mat3 r = test::randomRotation(rng);
  const CsgTree tree = CsgTree::leaf(Box{Vec3(1, 2, 3), r, Vec3(2, 1.5, 1)});
  const GroundTruth gt = makeGroundTruth(tree, 20000, 0.0, 3);
  const HypothesisSet set = generateHypotheses(gt.scan, gt.surfaces);
  EXPECT_EQ(set.stats.cuboids.eq3Count, 70u);
  EXPECT_EQ(set.stats.cuboids.rejectedRedundant, 56u);
  EXPECT_EQ(set.stats.cuboids.kept, 13u);
  const test::LeafMatch m = test::matchLeaf(gt, 0, set.candidates);
  EXPECT_TRUE(m.matched) << m.detail;
}

// Wu Fig. 5(1): the two faces of a concave corner (an L's inner faces) face
// each other, so they cannot be two faces of a solid box.
TEST(Hypotheses, OrientationFilterRejectsAConcaveCorner) {
  const CsgTree tree = CsgTree::unite({
      CsgTree::leaf(Box{Vec3(2, 0, 0.5), Mat3::Identity(), Vec3(2, 1, 0.5)}),  // foot [0,4] x [0,1]
      CsgTree::leaf(Box{Vec3(0.5, 0, 2), Mat3::Identity(), Vec3(0.5, 0.8, 2)})  // leg [0,1] x [0,4]
  });
  const GroundTruth gt = makeGroundTruth(tree, 20000, 0.0, 5);
  const int footTop = surfaceOf(gt, 0, 4);  // z = 1, normal +z
  const int legSide = surfaceOf(gt, 1, 0);  // x = 1, normal +x
  ASSERT_GE(footTop, 0);
  ASSERT_GE(legSide, 0);
  const std::vector<Surface> corner = pick(gt, {std::size_t(footTop), std::size_t(legSide)});

  HypothesisOptions wu;
  wu.toolCuboids = false;
  const HypothesisSet solid = generateHypotheses(gt.scan, corner, wu);
  EXPECT_EQ(solid.stats.cuboids.considered, 5u);  // the pair + 2 boxes per single patch
  EXPECT_EQ(solid.stats.cuboids.rejectedOrientation, 1u);
  for (const Candidate& c : solid.candidates) EXPECT_LE(c.surfaces.size(), 1u);

  // With tool cuboids the pair gives the box of the notch instead: material outside.
  const HypothesisSet tools = generateHypotheses(gt.scan, corner);
  EXPECT_EQ(tools.stats.cuboids.rejectedOrientation, 0u);
  const Candidate* notch = findBox(tools, Vec3(1, -1, 1), Vec3(4, 1, 4), 0.02);
  ASSERT_NE(notch, nullptr);
  EXPECT_TRUE(notch->tool);
  EXPECT_EQ(notch->surfaces.size(), 2u);
}

// Wu Fig. 5(2): a plate's bottom and the side of a post standing on it pass
// filter 1, but the box they bound leaves most of the bottom patch outside.
TEST(Hypotheses, FitFilterRejectsAnUnexplainedPatch) {
  const CsgTree tree = CsgTree::unite({
      CsgTree::leaf(Box{Vec3(0, 0, 0.5), Mat3::Identity(), Vec3(4, 1, 0.5)}),       // plate
      CsgTree::leaf(Box{Vec3(0, 0, 1.75), Mat3::Identity(), Vec3(0.5, 0.5, 1.25)})  // post
  });
  const GroundTruth gt = makeGroundTruth(tree, 20000, 0.0, 5);
  const int bottom = surfaceOf(gt, 0, 5);    // z = 0, normal -z
  const int postSide = surfaceOf(gt, 1, 0);  // x = 0.5, normal +x
  ASSERT_GE(bottom, 0);
  ASSERT_GE(postSide, 0);
  const HypothesisSet set =
      generateHypotheses(gt.scan, pick(gt, {std::size_t(bottom), std::size_t(postSide)}));
  EXPECT_EQ(set.stats.cuboids.rejectedOrientation, 0u);
  EXPECT_EQ(set.stats.cuboids.rejectedFit, 1u);
  for (const Candidate& c : set.candidates) EXPECT_LE(c.surfaces.size(), 1u);
}

// Wu Fig. 5(3): a box from two opposite faces is the box from all six; only
// the one with more patches is kept.
TEST(Hypotheses, RedundancyFilterKeepsOneOfTheSameBoxes) {
  const CsgTree tree = CsgTree::leaf(Box{Vec3::Zero(), Mat3::Identity(), Vec3(2, 1.5, 1)});
  const GroundTruth gt = makeGroundTruth(tree, 20000, 0.0, 3);
  // Two opposite faces alone: their box is the whole box.
  const HypothesisSet two = generateHypotheses(gt.scan, pick(gt, {0, 1}));
  ASSERT_NE(findBox(two, Vec3(-2, -1.5, -1), Vec3(2, 1.5, 1), 0.01), nullptr);
  EXPECT_EQ(two.stats.cuboids.rejectedRedundant, 0u);
  // With all six, the two-patch selection is redundant.
  const HypothesisSet six = generateHypotheses(gt.scan, gt.surfaces);
  const Candidate* whole = findBox(six, Vec3(-2, -1.5, -1), Vec3(2, 1.5, 1), 0.01);
  ASSERT_NE(whole, nullptr);
  EXPECT_EQ(whole->surfaces.size(), 6u);
  int wholeBoxes = 0;
  for (const Candidate& c : six.candidates) {
    wholeBoxes += c.origin == CandidateOrigin::Cuboid && c.surfaces.size() >= 2;
  }
  EXPECT_EQ(wholeBoxes, 1);
}

// Checks that every end of every cuboid candidate within 3 sigma of a fitted
// plane across it lies on that plane; returns the number of such ends and
// adds the number of ends off every plane by more than a tenth of sigma.
int checkEndsOnPlanes(const HypothesisSet& set, std::span<const Surface> planes, double sigma,
                      int& offPlane) {
  int onPlane = 0;
  for (const Candidate& c : set.candidates) {
    if (c.origin != CandidateOrigin::Cuboid) continue;
    const Box& b = *c.tree.root()->primitive.as<Box>();
    for (int k = 0; k < 3; ++k) {
      const Vec3 axis = b.axes.col(k);
      for (const int side : {-1, 1}) {
        const double end = b.center.dot(axis) + side * b.halfSize[k];
        double nearest = std::numeric_limits<double>::infinity();
        for (const Surface& s : planes) {
          const PlaneSurface& pl = *s.as<PlaneSurface>();
          const double cosine = pl.normal.normalized().dot(axis);
          if (std::abs(cosine) < 0.999) continue;
          nearest = std::min(nearest, std::abs(end - pl.offset / pl.normal.norm() / cosine));
        }
        offPlane += nearest > 0.1 * sigma;
        if (nearest > 3.0 * sigma) continue;  // a single patch's height, or a free end
        EXPECT_LT(nearest, 1e-9) << "end " << end << " of a box along " << axis.transpose();
        ++onPlane;
      }
    }
  }
  return onPlane;
}

// Noise pushes a patch's extreme inliers past its edges. A box end that no
// chosen patch bounds comes from those extremes; where a fitted plane across
// that axis lies within the end's uncertainty, the end is moved onto it.
TEST(Hypotheses, FreeBoxEndsSnapOntoTheFittedPlanes) {
  const CsgTree tree = CsgTree::leaf(Box{Vec3::Zero(), Mat3::Identity(), Vec3(2, 1.5, 1)});
  const GroundTruth gt = makeGroundTruth(tree, 20000, kNoise, 3);
  // The four faces across x and z; none across y, so the y ends stay free.
  std::vector<Surface> faces;
  for (const Surface& s : gt.surfaces) {
    if (std::abs(s.as<PlaneSurface>()->normal.normalized().y()) < 0.5) faces.push_back(s);
  }
  ASSERT_EQ(faces.size(), 4u);
  int offPlane = 0;
  EXPECT_GE(
      checkEndsOnPlanes(generateHypotheses(gt.scan, faces), faces, kNoise * gt.diagonal, offPlane),
      8);
  // The noise is there: the free ends (across y) are off the true faces.
  EXPECT_GE(offPlane, 2);
}

// The same across groups: a block turned 45 degrees about y on an upright
// one. The upright block's group takes the y planes, so the turned block's
// boxes have no y patch to choose; their y ends snap onto its own y faces.
TEST(Hypotheses, FreeBoxEndsSnapOntoPlanesOfOtherGroups) {
  const Mat3 turned = Eigen::AngleAxisd(0.25 * std::numbers::pi, Vec3::UnitY()).toRotationMatrix();
  const CsgTree tree = CsgTree::unite({
      CsgTree::leaf(Box{Vec3(0, 0, 0), Mat3::Identity(), Vec3(3, 1, 2)}),
      CsgTree::leaf(Box{Vec3(0, 1.5, 0), turned, Vec3(1, 0.5, 1)}),
  });
  const GroundTruth gt = makeGroundTruth(tree, 30000, kNoise, 5);
  const HypothesisSet set = generateHypotheses(gt.scan, gt.surfaces);
  int offPlane = 0;
  // At least the six faces of the turned block's own box are checked (120 ends in all).
  EXPECT_GE(checkEndsOnPlanes(set, gt.surfaces, kNoise * gt.diagonal, offPlane), 6);
  // The turned block's own box, y ends included, is among the candidates.
  int turnedBoxes = 0;
  for (const Candidate& c : set.candidates) {
    const Node& n = *c.tree.root();
    if (c.origin != CandidateOrigin::Cuboid || n.primitive.type() != PrimitiveType::Box) continue;
    const Box& b = *n.primitive.as<Box>();
    Vec3 half = b.halfSize;
    std::sort(half.data(), half.data() + 3);
    const double alongY = (b.axes.transpose() * Vec3::UnitY()).cwiseAbs().dot(b.halfSize);
    if ((b.center - Vec3(0, 1.5, 0)).norm() > 0.01 || (half - Vec3(0.5, 1, 1)).norm() > 0.01 ||
        std::abs(alongY - 0.5) > 1e-9) {
      continue;
    }
    ++turnedBoxes;
  }
  EXPECT_GE(turnedBoxes, 1);
}

// A noisy cone frustum standing on a plate, with a flat top: its bounded
// cone ends on the plate's top plane and on its cap's plane, not at its
// noisy extreme inliers, with the radii the cone has there.
TEST(Hypotheses, ConeEndsSnapOntoTheirCapPlanes) {
  const CsgTree tree = CsgTree::unite({
      CsgTree::leaf(Box{Vec3(0, 0, 0.5), Mat3::Identity(), Vec3(3, 3, 0.5)}),  // top at z = 1
      CsgTree::leaf(Cone{Vec3(0, 0, 2), Vec3::UnitZ(), 1.5, 0.75, 2.0}),       // z = 1 to 3
  });
  const GroundTruth gt = makeGroundTruth(tree, 30000, kNoise, 9);
  const HypothesisSet set = generateHypotheses(gt.scan, gt.surfaces);
  const Cone* cone = nullptr;
  for (const Candidate* c : ofOrigin(set, CandidateOrigin::Quadric)) {
    if (const Cone* k = c->tree.root()->primitive.as<Cone>()) cone = k;
  }
  ASSERT_NE(cone, nullptr);
  const double up = cone->axis.z() > 0.0 ? 1.0 : -1.0;
  const double zLo = cone->center.z() - up * 0.5 * cone->height;
  const double zHi = cone->center.z() + up * 0.5 * cone->height;
  EXPECT_NEAR(std::min(zLo, zHi), 1.0, 1e-9);
  EXPECT_NEAR(std::max(zLo, zHi), 3.0, 1e-9);
  // The exact surfaces give the exact cone: radius 1.5 at z = 1, 0.75 at z = 3.
  EXPECT_NEAR(up > 0.0 ? cone->radiusBottom : cone->radiusTop, 1.5, 1e-9);
  EXPECT_NEAR(up > 0.0 ? cone->radiusTop : cone->radiusBottom, 0.75, 1e-9);
}

TEST(Hypotheses, CylinderEndsLeaveTheSparseNoiseTailsOfTheirNeighbours) {
  // A shank (radius 0.3, z = -5 to 4.5) under a head (radius 0.45, z = 4.5
  // to 5). On a noisy scan of a thin shank the shank's band reaches the
  // head's side: one in eight of the head's side points (about 15 % of the
  // shank's density along the axis) joins the shank's inliers. The shank
  // ends at the head, on the plane z = 4.5, not at the head's top.
  const CsgTree tree = CsgTree::unite({
      CsgTree::leaf(Cylinder{Vec3(0, 0, -0.25), Vec3::UnitZ(), 0.3, 9.5}),
      CsgTree::leaf(Cylinder{Vec3(0, 0, 4.75), Vec3::UnitZ(), 0.45, 0.5}),
  });
  GroundTruth gt = makeGroundTruth(tree, 30000, 0.0, 9);
  const int shank = surfaceOf(gt, 0, 0), head = surfaceOf(gt, 1, 0);
  ASSERT_GE(shank, 0);
  ASSERT_GE(head, 0);
  const auto shankTop = [&](const std::vector<Surface>& surfaces) {
    const HypothesisSet set = generateHypotheses(gt.scan, surfaces);
    double top = -1e300;
    for (const Candidate* c : ofOrigin(set, CandidateOrigin::Quadric)) {
      const Cylinder* k = c->tree.root()->primitive.as<Cylinder>();
      if (k && std::abs(k->radius - 0.3) < 1e-9) {
        top = std::max(top, k->center.z() + 0.5 * k->height * std::abs(k->axis.z()));
      }
    }
    return top;
  };
  EXPECT_NEAR(shankTop(gt.surfaces), 4.5, 1e-9);
  std::vector<Surface> surfaces = gt.surfaces;
  auto& from = surfaces[std::size_t(head)].inliers;
  auto& to = surfaces[std::size_t(shank)].inliers;
  ASSERT_GT(from.size(), 1000u);
  std::vector<std::uint32_t> kept;
  for (std::size_t k = 0; k < from.size(); ++k) (k % 8 == 0 ? to : kept).push_back(from[k]);
  from = kept;
  EXPECT_NEAR(shankTop(surfaces), 4.5, 1e-9);
}

// A boss of radius 3 on a base, ringed by `grooves` grooves (radius 2.5) 0.5
// wide between bands 0.5 tall from z = 0.25, scanned with `noise`, and the
// detection's view: the bands' sides as one cylinder surface, with residual
// `rms` when given (else the lowest band's own).
struct RingedBoss {
  GroundTruth gt;
  std::vector<Surface> surfaces;
};
RingedBoss ringedBoss(int grooves, double noise = 0.0, std::optional<double> rms = {}) {
  std::vector<CsgTree> parts{
      CsgTree::leaf(Box{Vec3(0, 0, -0.5), Mat3::Identity(), Vec3(5, 5, 0.75)}),  // top z = 0.25
      CsgTree::leaf(Cylinder{Vec3(0, 0, 0.25 + 0.5 * grooves + 0.25), Vec3::UnitZ(), 2.5,
                             1.0 * grooves + 0.5}),  // the core, z 0.25 to the top band's top
  };
  for (int b = 0; b <= grooves; ++b) {
    parts.push_back(CsgTree::leaf(Cylinder{Vec3(0, 0, 0.5 + 1.0 * b), Vec3::UnitZ(), 3.0, 0.5}));
  }
  RingedBoss out{makeGroundTruth(CsgTree::unite(parts), 40000, noise, 5), {}};
  std::vector<int> sides;
  for (int b = 0; b <= grooves; ++b) sides.push_back(surfaceOf(out.gt, 2 + b, 0));
  if (std::find(sides.begin(), sides.end(), -1) != sides.end()) {
    ADD_FAILURE() << "a band's side is not among the visible surfaces";
    return out;
  }
  for (std::size_t s = 0; s < out.gt.surfaces.size(); ++s) {
    if (std::find(sides.begin() + 1, sides.end(), int(s)) != sides.end()) continue;
    out.surfaces.push_back(out.gt.surfaces[s]);
    if (int(s) != sides.front()) continue;
    for (auto it = sides.begin() + 1; it != sides.end(); ++it) {
      const auto& more = out.gt.surfaces[std::size_t(*it)].inliers;
      out.surfaces.back().inliers.insert(out.surfaces.back().inliers.end(), more.begin(),
                                         more.end());
    }
    if (rms) out.surfaces.back().rms = *rms;
  }
  return out;
}

// The z ranges of the radius-3 cylinders among the candidates, in order.
std::vector<std::pair<double, double>> radius3Spans(const HypothesisSet& set) {
  std::vector<std::pair<double, double>> spans;
  for (const Candidate* c : ofOrigin(set, CandidateOrigin::Quadric)) {
    const Cylinder* k = c->tree.root()->primitive.as<Cylinder>();
    if (k == nullptr || std::abs(k->radius - 3.0) > 0.05) continue;
    const double half = 0.5 * k->height * std::abs(k->axis.z());
    spans.emplace_back(k->center.z() - half, k->center.z() + half);
  }
  std::sort(spans.begin(), spans.end());
  return spans;
}

// A boss with a groove (z 0.75 to 1.25) on a base plate: the detection
// takes the boss's side below and above the groove as one cylinder, which
// bounded by its inliers fills the groove. Each band it leaves is a
// candidate too, its ends on the groove's walls; the whole cylinder stays.
// With noise the bands' edges spread into the gap (at 0.5 % of D, σ = 0.07,
// three deviations from each side close all but 0.08 of the 0.5 gap, under
// twice the duplicate tolerance); at 0.25 % the gap stays open.
TEST(Hypotheses, AGroovedCylinderAlsoGivesOneCylinderPerBand) {
  for (const double noise : {0.0, 0.5 * kNoise}) {
    SCOPED_TRACE(noise);
    const RingedBoss boss = ringedBoss(1, noise);
    const HypothesisSet set = generateHypotheses(boss.gt.scan, boss.surfaces);
    const auto spans = radius3Spans(set);
    ASSERT_EQ(spans.size(), 3u);
    EXPECT_EQ(set.stats.axialBands, 2u);
    // Lower band, whole, upper band: every end on its fitted plane.
    const double tol = noise > 0.0 ? 0.02 : 1e-9;
    EXPECT_NEAR(spans[0].first, 0.25, tol);
    EXPECT_NEAR(spans[0].second, 0.75, tol);
    EXPECT_NEAR(spans[1].first, 0.25, tol);
    EXPECT_NEAR(spans[1].second, 1.75, tol);
    EXPECT_NEAR(spans[2].first, 1.25, tol);
    EXPECT_NEAR(spans[2].second, 1.75, tol);

    HypothesisOptions off;
    off.axialBands = false;
    EXPECT_EQ(radius3Spans(generateHypotheses(boss.gt.scan, boss.surfaces, off)).size(), 1u);
  }
}

// A gap between bands must be wider than six deviations of the patch's noise
// (as the detection measured it): the 0.5 grooves split a surface of RMS
// 0.07 (6 sigma = 0.42) and not one of RMS 0.1 (0.6), the points being the
// same. And a patch of more than four bands (ribs, a thread) stays whole: 3
// grooves give 4 bands, 4 grooves none.
TEST(Hypotheses, BandsNeedGapsWiderThanTheNoiseAndAreFew) {
  // Radius-3 cylinders among the candidates: the whole patch and its bands
  // (the core's side, seen in the grooves, is split too, at radius 2.5).
  const auto radius3 = [](const RingedBoss& boss) {
    return radius3Spans(generateHypotheses(boss.gt.scan, boss.surfaces)).size();
  };
  EXPECT_EQ(radius3(ringedBoss(1, 0.0, 0.07)), 1u + 2u);
  EXPECT_EQ(radius3(ringedBoss(1, 0.0, 0.1)), 1u);
  EXPECT_EQ(radius3(ringedBoss(3, 0.0, 0.0)), 1u + 4u);
  EXPECT_EQ(radius3(ringedBoss(4, 0.0, 0.0)), 1u);
}

// A shaft with a cross hole: the hole interrupts the side over part of the
// circumference only, so the side's inliers leave no empty band and the
// shaft stays one cylinder. A hole through two walls, taken as one surface,
// stays one too: subtracted whole it cuts only the air between the walls.
TEST(Hypotheses, ACrossHoleOrAHoleThroughTwoWallsSplitsNoBand) {
  const CsgTree shaft = CsgTree::subtract({
      CsgTree::leaf(Cylinder{Vec3(0, 0, 0), Vec3::UnitZ(), 1.0, 8.0}),
      CsgTree::leaf(Cylinder{Vec3(0, 0, 0), Vec3::UnitX(), 0.6, 4.0}),
  });
  const GroundTruth gt = makeGroundTruth(shaft, 30000, 0.0, 5);
  EXPECT_EQ(generateHypotheses(gt.scan, gt.surfaces).stats.axialBands, 0u);

  // Two walls (x = -4 to -3.5 and 3.5 to 4) on a base, a hole of radius 0.5
  // along x through both.
  const CsgTree walls = CsgTree::subtract({
      CsgTree::unite({
          CsgTree::leaf(Box{Vec3(0, 0, 0.25), Mat3::Identity(), Vec3(4, 2, 0.25)}),
          CsgTree::leaf(Box{Vec3(-3.75, 0, 2), Mat3::Identity(), Vec3(0.25, 2, 2)}),
          CsgTree::leaf(Box{Vec3(3.75, 0, 2), Mat3::Identity(), Vec3(0.25, 2, 2)}),
      }),
      CsgTree::leaf(Cylinder{Vec3(0, 0, 2.5), Vec3::UnitX(), 0.5, 9.0}),
  });
  const GroundTruth wallsGt = makeGroundTruth(walls, 30000, 0.0, 5);
  // The hole's two pieces (one per wall) as one surface.
  std::vector<Surface> surfaces;
  int hole = -1;
  for (std::size_t s = 0; s < wallsGt.surfaces.size(); ++s) {
    const auto* c = wallsGt.surfaces[s].as<CylinderSurface>();
    if (c == nullptr) {
      surfaces.push_back(wallsGt.surfaces[s]);
    } else if (hole < 0) {
      hole = int(surfaces.size());
      surfaces.push_back(wallsGt.surfaces[s]);
    } else {
      auto& in = surfaces[std::size_t(hole)].inliers;
      in.insert(in.end(), wallsGt.surfaces[s].inliers.begin(), wallsGt.surfaces[s].inliers.end());
    }
  }
  ASSERT_GE(hole, 0);
  ASSERT_FALSE(surfaces[std::size_t(hole)].convex);
  EXPECT_EQ(generateHypotheses(wallsGt.scan, surfaces).stats.axialBands, 0u);
}

// A block [0,10] x [0,10] x [0,20] with one edge rounded (radius 3, axis
// x = y = 7): a quarter cylinder between the planes x = 10 and y = 10.
GroundTruth roundedBlock() {
  const CsgTree tree = CsgTree::unite({
      CsgTree::leaf(Box{Vec3(5, 3.5, 10), Mat3::Identity(), Vec3(5, 3.5, 10)}),  // [0,10] x [0,7]
      CsgTree::leaf(Box{Vec3(3.5, 5, 10), Mat3::Identity(), Vec3(3.5, 5, 10)}),  // [0,7] x [0,10]
      CsgTree::leaf(Cylinder{Vec3(7, 7, 10), Vec3::UnitZ(), 3.0, 20.0}),
  });
  return makeGroundTruth(tree, 20000, 0.0, 9);
}

// Wu Fig. 6(2): a block with one rounded edge (a quarter cylinder) gets the
// maximal box of the quarter, with its corner on the axis.
TEST(Hypotheses, QuarterCylinderGetsTheMaximalBox) {
  const GroundTruth gt = roundedBlock();
  const HypothesisSet set = generateHypotheses(gt.scan, gt.surfaces);
  EXPECT_EQ(set.stats.quarterCylinders, 1u);
  const auto additional = ofOrigin(set, CandidateOrigin::Additional);
  ASSERT_EQ(additional.size(), 1u);
  const Box& b = *additional[0]->tree.root()->primitive.as<Box>();
  test::expectNear(b.center, Vec3(8.5, 8.5, 10), 0.02);
  Vec3 sizes = b.halfSize;
  std::sort(sizes.data(), sizes.data() + 3);
  test::expectNear(sizes, Vec3(1.5, 1.5, 10), 0.02);
  // The rounded block is the maximal box's complement of the quadric: the
  // indirect candidate box − cylinder is the sliver to cut off the corner.
  const auto indirect = ofOrigin(set, CandidateOrigin::Indirect);
  ASSERT_EQ(indirect.size(), 2u);
  const Vec3 sliver(9.8, 9.8, 10), inCylinder(8.5, 8.5, 10);
  const CsgTree& difference = indirect[0]->tree.root()->kind == NodeKind::Difference
                                  ? indirect[0]->tree
                                  : indirect[1]->tree;
  EXPECT_TRUE(difference.contains(sliver));
  EXPECT_FALSE(difference.contains(inCylinder));
}

// The quarter's inliers run a little onto a plane it meets tangentially (as
// RANSAC's do: there plane and cylinder agree within the noise). Their span,
// 101 degrees, would turn the box by 5.7 degrees and move its centre by 0.2;
// the box turns back onto the tangent planes' normals and is exact.
TEST(Hypotheses, QuarterBoxLiesAlongTheTangentPlanes) {
  const GroundTruth gt = roundedBlock();
  std::vector<Surface> surfaces = gt.surfaces;
  auto quarter = std::find_if(surfaces.begin(), surfaces.end(),
                              [](const Surface& s) { return s.as<CylinderSurface>() != nullptr; });
  ASSERT_NE(quarter, surfaces.end());
  std::size_t added = 0;
  for (std::size_t i = 0; i < gt.clean.size(); ++i) {
    const Vec3& p = gt.clean[i];
    if (std::abs(p.x() - 10.0) < 1e-9 && p.y() > 6.4 && p.y() < 7.0) {
      quarter->inliers.push_back(std::uint32_t(i));
      ++added;
    }
  }
  ASSERT_GT(added, 20u);

  auto quarterBox = [&](const HypothesisOptions& options) {
    const HypothesisSet set = generateHypotheses(gt.scan, surfaces, options);
    EXPECT_EQ(set.stats.quarterCylinders, 1u);
    const auto additional = ofOrigin(set, CandidateOrigin::Additional);
    EXPECT_EQ(additional.size(), 1u);
    return additional.empty() ? Box{} : *additional[0]->tree.root()->primitive.as<Box>();
  };
  const Box b = quarterBox(HypothesisOptions{});
  test::expectNear(b.center, Vec3(8.5, 8.5, 10), 0.005);
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(b.axes.col(k).cwiseAbs().maxCoeff(), 1.0, 1e-9) << "axis " << k;
  }
  Vec3 sizes = b.halfSize;
  std::sort(sizes.data(), sizes.data() + 3);
  test::expectNear(sizes, Vec3(1.5, 1.5, 10), 0.005);

  // Without the planes the box follows the points' span.
  HypothesisOptions noSnap;
  noSnap.snapToPlanes = false;
  EXPECT_GT((quarterBox(noSnap).center - Vec3(8.5, 8.5, 10)).norm(), 0.1);
}

// Wu §4.1: every additional box comes with box − quadric and box ∩ quadric
// built from exactly that box and quadric. The obround slot of rotated_block
// has two half-cylinder ends, whose minimal boxes are half as wide as their
// own bounding boxes, so they are kept.
TEST(Hypotheses, IndirectCandidatesPairEachAdditionalBoxWithItsQuadric) {
  const GroundTruth& gt = partTruth("rotated_block", 0.0);
  const HypothesisSet set = generateHypotheses(gt.scan, gt.surfaces);
  const auto additional = ofOrigin(set, CandidateOrigin::Additional);
  const auto indirect = ofOrigin(set, CandidateOrigin::Indirect);
  ASSERT_GE(additional.size(), 2u);
  EXPECT_EQ(indirect.size(), 2 * additional.size());
  for (const Candidate* a : additional) {
    const Primitive& box = a->tree.root()->primitive;
    int differences = 0, intersections = 0;
    for (const Candidate* c : indirect) {
      const Node& n = *c->tree.root();
      ASSERT_EQ(n.children.size(), 2u);
      if (!(n.children[0]->primitive == box)) continue;
      EXPECT_EQ(c->surfaces, a->surfaces);
      EXPECT_NE(n.children[1]->primitive.type(), PrimitiveType::Box);
      differences += n.kind == NodeKind::Difference;
      intersections += n.kind == NodeKind::Intersection;
    }
    EXPECT_EQ(differences, 1);
    EXPECT_EQ(intersections, 1);
  }
}

// Geometric equality of two single-primitive candidates, by their signed
// distances at points around them (a half-space and its complement alike).
bool sameShape(const Primitive& a, const Primitive& b, const Aabb& box, double tol) {
  test::Rng rng(3);
  const bool planes = a.type() == PrimitiveType::HalfSpace;
  for (int i = 0; i < 300; ++i) {
    const Vec3 p = test::randomPoint(rng, box);
    const double fa = a.value(p), fb = b.value(p);
    if (std::abs(planes ? std::abs(fa) - std::abs(fb) : fa - fb) > tol) return false;
  }
  return true;
}

// Every surface given twice: duplicates are removed, so the candidates are
// the same as with each surface once; and no two returned primitives of a
// part are the same within the duplicate tolerance (their distance fields
// differ by more than 0.2 % of D somewhere around the part).
TEST(Hypotheses, DuplicatesAreRemoved) {
  const GroundTruth& gt = partTruth("bearing_housing", 0.0);
  HypothesisOptions options;
  options.maxCandidates = 0;
  const HypothesisSet once = generateHypotheses(gt.scan, gt.surfaces, options);
  std::vector<Surface> twice = gt.surfaces;
  twice.insert(twice.end(), gt.surfaces.begin(), gt.surfaces.end());
  const HypothesisSet doubled = generateHypotheses(gt.scan, twice, options);
  EXPECT_GT(doubled.stats.duplicatesRemoved, 0u);
  // Redundancy removes repeated patches' boxes before duplicate removal;
  // quadric-side candidates are all doubled, then removed.
  for (CandidateOrigin o :
       {CandidateOrigin::Quadric, CandidateOrigin::Additional, CandidateOrigin::Indirect,
        CandidateOrigin::Separator, CandidateOrigin::Plane}) {
    EXPECT_EQ(doubled.stats.returned[o], once.stats.returned[o]) << candidateOriginName(o);
  }
  for (const std::string& part : test::partNames()) {
    const GroundTruth& g = partTruth(part, 0.0);
    const HypothesisSet set = generateHypotheses(g.scan, g.surfaces);
    const auto leaves = [&] {
      std::vector<const Candidate*> v;
      for (const Candidate& c : set.candidates) {
        if (c.tree.root()->kind == NodeKind::Primitive) v.push_back(&c);
      }
      return v;
    }();
    for (std::size_t i = 0; i < leaves.size(); ++i) {
      for (std::size_t j = i + 1; j < leaves.size(); ++j) {
        const Primitive& a = leaves[i]->tree.root()->primitive;
        const Primitive& b = leaves[j]->tree.root()->primitive;
        if (a.type() != b.type()) continue;
        EXPECT_FALSE(sameShape(a, b, g.tree.bounds().grown(0.1 * g.diagonal), 0.002 * g.diagonal))
            << part << ": candidates " << i << " and " << j << " are the same "
            << primitiveTypeName(a.type());
      }
    }
  }
}

// Runs the generator on every part; checks that every observable leaf has a
// matching candidate and that the counts stay bounded; prints a table.
void checkAllParts(double noise) {
  std::printf("\n%-18s %6s %6s | %6s %6s %6s %6s %6s %6s | %5s %4s | %7s %8s\n", "part", "planes",
              "curved", "cuboid", "quadr", "plane", "addit", "indir", "separ", "total", "cap",
              "matched", "ms");
  for (const std::string& part : test::partNames()) {
    const GroundTruth& gt = partTruth(part, noise);
    const auto t0 = std::chrono::steady_clock::now();
    const HypothesisSet set = generateHypotheses(gt.scan, gt.surfaces);
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    std::size_t planes = 0;
    for (const Surface& s : gt.surfaces) planes += s.type() == SurfaceType::Plane;
    const OriginCounts& n = set.stats.returned;
    int observable = 0, matched = 0;
    std::string failures;
    for (std::size_t leaf = 0; leaf < gt.leaves.size(); ++leaf) {
      const test::LeafMatch m = test::matchLeaf(gt, leaf, set.candidates);
      if (!m.observable) {
        failures += "    (" + gt.leaves[leaf]->name + " is not visible)\n";
        continue;
      }
      ++observable;
      matched += m.matched;
      EXPECT_TRUE(m.matched) << part << (noise > 0 ? " (noisy)" : "") << ": "
                             << gt.leaves[leaf]->name << " has no matching candidate: " << m.detail;
      if (!m.matched) failures += "    " + gt.leaves[leaf]->name + ": " + m.detail + "\n";
    }
    EXPECT_LE(set.candidates.size(), 600u) << part;
    EXPECT_FALSE(set.stats.cuboids.enumerationCapped) << part;
    std::printf("%-18s %6zu %6zu | %6zu %6zu %6zu %6zu %6zu %6zu | %5zu %4s | %3d/%-3d %8.1f\n",
                part.c_str(), planes, gt.surfaces.size() - planes, n[CandidateOrigin::Cuboid],
                n[CandidateOrigin::Quadric], n[CandidateOrigin::Plane],
                n[CandidateOrigin::Additional], n[CandidateOrigin::Indirect],
                n[CandidateOrigin::Separator], set.candidates.size(),
                set.stats.capped ? "yes" : "no", matched, observable, ms);
    const CuboidStats& cs = set.stats.cuboids;
    std::printf(
        "    cuboids: groups %zu/%zu/%zu (triangle/edge/single), Eq.3 %zu, considered %zu, "
        "rejected orientation %zu, degenerate %zu, fit %zu, redundant %zu; kept %zu "
        "(%zu tool)%s; duplicates removed %zu, own boxes dropped %zu, extended cylinders %zu\n",
        cs.triangleGroups, cs.edgeGroups, cs.singleGroups, cs.eq3Count, cs.considered,
        cs.rejectedOrientation, cs.rejectedDegenerate, cs.rejectedFit, cs.rejectedRedundant,
        cs.kept, cs.keptTool, cs.patchesCapped ? ", patches capped" : "",
        set.stats.duplicatesRemoved, set.stats.ownBoundsDropped, set.stats.extendedCylinders);
    if (!failures.empty()) std::printf("%s", failures.c_str());
  }
  std::fflush(stdout);
}

TEST(Hypotheses, EveryPartMatchesItsGroundTruth) { checkAllParts(0.0); }

TEST(Hypotheses, EveryNoisyPartMatchesItsGroundTruth) { checkAllParts(kNoise); }

// The off-axis parts match every observable primitive, like the axis-aligned ones.
TEST(Hypotheses, RotatedPartsMatchAsWellAsAxisAlignedOnes) {
  for (const char* part : {"rotated_block", "pipe_tee", "knob"}) {
    for (double noise : {0.0, kNoise}) {
      const GroundTruth& gt = partTruth(part, noise);
      const HypothesisSet set = generateHypotheses(gt.scan, gt.surfaces);
      for (std::size_t leaf = 0; leaf < gt.leaves.size(); ++leaf) {
        const test::LeafMatch m = test::matchLeaf(gt, leaf, set.candidates);
        if (m.observable) {
          EXPECT_TRUE(m.matched) << part << " " << gt.leaves[leaf]->name << ": " << m.detail;
        }
      }
    }
  }
}

// Rotated and shifted input gives the same candidates, rotated and shifted.
Surface moved(const Surface& s, const Mat3& r, const Vec3& t) {
  Surface m = s;
  if (const auto* p = s.as<PlaneSurface>()) {
    const Vec3 n = r * p->normal;
    m.shape = PlaneSurface{n, p->offset + n.dot(t)};
  } else if (const auto* c = s.as<CylinderSurface>()) {
    m.shape = CylinderSurface{r * c->axisPoint + t, r * c->axisDir, c->radius};
  } else if (const auto* c = s.as<ConeSurface>()) {
    m.shape = ConeSurface{r * c->apex + t, r * c->axisDir, c->halfAngle};
  } else if (const auto* c = s.as<SphereSurface>()) {
    m.shape = SphereSurface{r * c->center + t, c->radius};
  } else if (const auto* c = s.as<TorusSurface>()) {
    m.shape = TorusSurface{r * c->center + t, r * c->axisDir, c->majorRadius, c->minorRadius};
  }
  return m;
}

TEST(Hypotheses, CandidatesTurnWithTheScan) {
  test::Rng rng(21);
  for (const char* part : {"wedge_block", "l_bracket", "flange"}) {
    const GroundTruth& gt = partTruth(part, 0.0);
    const Mat3 r = test::randomRotation(rng);
    const Vec3 t(13, -7, 5);
    PointCloud scan = gt.scan;
    for (Vec3& p : scan.points) p = r * p + t;
    for (Vec3& n : scan.normals) n = r * n;
    std::vector<Surface> surfaces;
    for (const Surface& s : gt.surfaces) surfaces.push_back(moved(s, r, t));
    const HypothesisSet a = generateHypotheses(gt.scan, gt.surfaces);
    const HypothesisSet b = generateHypotheses(scan, surfaces);
    for (std::size_t o = 0; o < kCandidateOriginCount; ++o) {
      EXPECT_EQ(a.stats.returned.count[o], b.stats.returned.count[o])
          << part << " " << candidateOriginName(CandidateOrigin(o));
    }
    EXPECT_EQ(a.stats.cuboids.considered, b.stats.cuboids.considered) << part;
    EXPECT_EQ(a.stats.cuboids.kept, b.stats.cuboids.kept) << part;
    // Each turned candidate has a counterpart among the original ones.
    const Aabb box = gt.tree.bounds().grown(0.05 * gt.diagonal);
    const double tol = 1e-3 * gt.diagonal;
    for (const Candidate& cb : b.candidates) {
      bool found = false;
      for (const Candidate& ca : a.candidates) {
        if (ca.origin != cb.origin || ca.surfaces != cb.surfaces) continue;
        test::Rng prng(5);
        bool same = true;
        for (int i = 0; i < 200 && same; ++i) {
          const Vec3 p = test::randomPoint(prng, box);
          same = std::abs(ca.tree.value(p) - cb.tree.value(r * p + t)) <= tol;
        }
        found = found || same;
      }
      EXPECT_TRUE(found) << part << ": a " << candidateOriginName(cb.origin)
                         << " candidate has no counterpart";
    }
  }
}

// Fayolle §5.2: the flange's fillet ring is hidden (the torus removes all of
// its faces), but the separator cylinder of the fillet torus rebuilds it:
// same axis and radius, and it ends where the ring does (z = 18).
TEST(Hypotheses, TorusSeparatorRebuildsAHiddenFilletRing) {
  const GroundTruth& gt = partTruth("flange", 0.0);
  const HypothesisSet set = generateHypotheses(gt.scan, gt.surfaces);
  int ring = -1;
  for (std::size_t leaf = 0; leaf < gt.leaves.size(); ++leaf) {
    if (gt.leaves[leaf]->name == "fillet_ring") ring = static_cast<int>(leaf);
  }
  ASSERT_GE(ring, 0);
  EXPECT_TRUE(gt.visible[static_cast<std::size_t>(ring)].empty());
  const Cylinder& want = *gt.leaves[static_cast<std::size_t>(ring)]->primitive.as<Cylinder>();
  bool found = false;
  for (const Candidate* c : ofOrigin(set, CandidateOrigin::Separator)) {
    const Cylinder* cyl = c->tree.root()->primitive.as<Cylinder>();
    if (cyl == nullptr) continue;
    const double top = (cyl->center + 0.5 * cyl->height * cyl->axis).z();
    const double bottom = (cyl->center - 0.5 * cyl->height * cyl->axis).z();
    found = found || (std::abs(cyl->axis.dot(want.axis)) > 0.9999 &&
                      std::abs(cyl->radius - want.radius) < 1e-6 &&
                      std::abs(std::max(top, bottom) - 18.0) < 0.01 * gt.diagonal &&
                      (cyl->center - want.center).head<2>().norm() < 1e-6);
  }
  EXPECT_TRUE(found);
}

// Half-spaces: the wedge's slope and bevel (single-set groups, only in
// one-patch boxes) become half-spaces; the faces of the block do not.
TEST(Hypotheses, PlanesOutsideCuboidsBecomeHalfSpaces) {
  const GroundTruth& gt = partTruth("wedge_block", 0.0);
  const HypothesisSet set = generateHypotheses(gt.scan, gt.surfaces);
  const auto planes = ofOrigin(set, CandidateOrigin::Plane);
  ASSERT_EQ(planes.size(), 2u);
  for (const Candidate* c : planes) {
    ASSERT_EQ(c->surfaces.size(), 1u);
    EXPECT_NE(gt.surfaceLeaf[static_cast<std::size_t>(c->surfaces[0])], 0);  // not the block
    // Oriented outwards: the scan points lie on it, the part on its inner side.
    const HalfSpace& h = *c->tree.root()->primitive.as<HalfSpace>();
    EXPECT_TRUE(gt.tree.contains(gt.tree.bounds().center()));
    EXPECT_GT(Primitive(h).value(gt.tree.bounds().center()), 0.0);
  }
}

TEST(Hypotheses, SameInputSameCandidates) {
  const GroundTruth& gt = partTruth("knob", kNoise);
  const HypothesisSet a = generateHypotheses(gt.scan, gt.surfaces);
  const HypothesisSet b = generateHypotheses(gt.scan, gt.surfaces);
  ASSERT_EQ(a.candidates.size(), b.candidates.size());
  for (std::size_t i = 0; i < a.candidates.size(); ++i) {
    EXPECT_TRUE(a.candidates[i].tree.structurallyEqual(b.candidates[i].tree));
    EXPECT_EQ(a.candidates[i].surfaces, b.candidates[i].surfaces);
  }
}

// The cap removes the worst-supported cuboids first (the only kind that
// grows combinatorially), keeps every other candidate while it can, and says so.
TEST(Hypotheses, CapDropsTheWorstSupportedCuboidsFirst) {
  const GroundTruth& gt = partTruth("housing_complex", 0.0);
  HypothesisOptions options;
  options.maxCandidates = 0;
  const HypothesisSet all = generateHypotheses(gt.scan, gt.surfaces, options);
  EXPECT_FALSE(all.stats.capped);
  options.maxCandidates = 40;
  const HypothesisSet set = generateHypotheses(gt.scan, gt.surfaces, options);
  EXPECT_TRUE(set.stats.capped);
  ASSERT_EQ(set.candidates.size(), 40u);
  const std::size_t others = all.candidates.size() - all.stats.returned[CandidateOrigin::Cuboid];
  ASSERT_LT(others, 40u);
  for (std::size_t o = 0; o < kCandidateOriginCount; ++o) {
    if (CandidateOrigin(o) == CandidateOrigin::Cuboid) continue;
    EXPECT_EQ(set.stats.returned.count[o], all.stats.returned.count[o]);
  }
  const auto cuboids = ofOrigin(set, CandidateOrigin::Cuboid);
  ASSERT_EQ(cuboids.size(), 40u - others);
  double weakest = 1e300;
  for (const Candidate* c : cuboids) weakest = std::min(weakest, c->support);
  std::size_t stronger = 0;
  for (const Candidate* c : ofOrigin(all, CandidateOrigin::Cuboid))
    stronger += c->support > weakest;
  EXPECT_LE(stronger, cuboids.size());
}

// A bounded enumeration: a tiny per-direction cap is reported.
TEST(Hypotheses, PatchCapIsReported) {
  const GroundTruth& gt = partTruth("housing_complex", 0.0);
  HypothesisOptions options;
  options.maxPatchesPerDirection = 2;
  const HypothesisSet set = generateHypotheses(gt.scan, gt.surfaces, options);
  EXPECT_TRUE(set.stats.cuboids.patchesCapped);
  EXPECT_LT(set.stats.cuboids.considered, set.stats.cuboids.eq3Count);
  options.maxCuboidHypotheses = 50;
  EXPECT_TRUE(generateHypotheses(gt.scan, gt.surfaces, options).stats.cuboids.enumerationCapped);
}

}  // namespace
}  // namespace csgvox
