// The designed dimensions of every bundled part, found again from its scans.
//
// A true tree's dimensions are its primitives' radii (a cone's at each cap,
// a torus's two) and lengths (a box's edges, a cylinder's or cone's
// height), the values on the hundredths a designer typed. A dimension is
// *observable* when the faces it spans lie on the solid's boundary: a
// through-hole's length, a cap hidden inside a union or a chamfer cone's
// caps outside the part are construction values no scan can show. One is
// *found* when the designed tree (the main job: reconstruct, then design
// from the scan's points) has it exactly as a parameter of its kind: a
// radius as a parameter named as a radius (`_r`, `_r0`, `_r1`, `_major_r`,
// `_minor_r`), a length as a size (`_width`, `_depth`, a pattern's step
// `_dx`...) or as the difference of two positions along one frame axis
// (`plate_z1 − plate_z0`). A chance equality of unrelated numbers (a bore's
// length and a bolt circle's phase, both 45) does not count.
//
// Clean scans: every observable dimension of every part, except the known
// gaps below. Noisy scans (σ = 0.5 % of D): at least 80 % of them over all
// parts.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>
#include <regex>
#include <string>
#include <vector>

#include "design/designed_tree.h"
#include "io/scan_reader.h"
#include "io/tree_json.h"
#include "part_list.h"
#include "pipeline/reconstruct.h"

namespace csgvox {
namespace {

namespace fs = std::filesystem;

// The bundled parts: data/<part>/ and data/thin/<part>/.
std::vector<fs::path> partDirs() {
  std::vector<fs::path> dirs;
  for (const fs::path& root : {test::dataDir(), test::dataDir() / "thin"}) {
    for (const auto& e : fs::directory_iterator(root)) {
      if (e.is_directory() && fs::exists(e.path() / "tree.json")) dirs.push_back(e.path());
    }
  }
  std::sort(dirs.begin(), dirs.end());
  return dirs;
}

bool onHundredths(double v) { return std::abs(v * 100 - std::round(v * 100)) < 1e-6; }

// Points on each face of a primitive: a face shows when some of them lie on
// the solid's boundary (its inside, or its rim where a cutter's face is
// flush with the part's and only its edge shows).
struct Face {
  std::vector<Vec3> points;
};

Mat3 frameOf(const Vec3& axis) {
  Vec3 u = std::abs(axis.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  u = (u - u.dot(axis) * axis).normalized();
  Mat3 f;
  f.col(0) = u;
  f.col(1) = axis.cross(u);
  f.col(2) = axis;
  return f;
}

constexpr int kSteps = 24;
double inner(int i) { return (i + 0.5) / kSteps; }  // (0, 1), away from the ends

Face disc(const Vec3& c, const Mat3& f, double r) {
  Face face;
  if (r <= 0.0) {
    face.points.push_back(c);  // an apex
    return face;
  }
  for (int i = 0; i <= kSteps; ++i) {  // i = kSteps: the rim
    for (int j = 0; j < 2 * kSteps; ++j) {
      const double a = std::numbers::pi * inner(j),
                   rr = i < kSteps ? r * (0.05 + 0.9 * inner(i)) : r;
      face.points.push_back(c + rr * (std::cos(a) * f.col(0) + std::sin(a) * f.col(1)));
    }
  }
  return face;
}

// A surface of revolution about f.col(2) through c: radius(t) at height
// h(t), t in (0, 1).
template <class R, class H>
Face revolved(const Vec3& c, const Mat3& f, R radius, H height) {
  Face face;
  for (int i = 0; i < kSteps; ++i) {
    for (int j = 0; j < 2 * kSteps; ++j) {
      const double t = inner(i), a = 2 * std::numbers::pi * (j + 0.5) / (2 * kSteps);
      face.points.push_back(c + height(t) * f.col(2) +
                            radius(t) * (std::cos(a) * f.col(0) + std::sin(a) * f.col(1)));
    }
  }
  return face;
}

struct Dimension {
  double value = 0.0;
  bool radius = false;
  std::vector<const Face*> faces;  // all must show
};

struct PartDimensions {
  std::vector<Face> faces;  // stable storage (reserved)
  std::vector<Dimension> all;
};

PartDimensions dimensionsOf(const CsgTree& truth) {
  PartDimensions d;
  d.faces.reserve(1000);
  const auto face = [&](Face f) {
    d.faces.push_back(std::move(f));
    return &d.faces.back();
  };
  for (const Node* leaf : truth.distinctLeaves()) {
    const Primitive& p = leaf->primitive;
    if (const auto* b = p.as<Box>()) {
      for (int k = 0; k < 3; ++k) {
        const int i = (k + 1) % 3, j = (k + 2) % 3;
        std::vector<const Face*> ends;
        for (double side : {-1.0, 1.0}) {
          Face f;
          // The face, then its four edges (a cutter's face flush with the
          // part's is open: only its edges show).
          const auto at = [&](double x, double y) {
            f.points.push_back(b->center + side * b->halfSize[k] * b->axes.col(k) +
                               x * b->halfSize[i] * b->axes.col(i) +
                               y * b->halfSize[j] * b->axes.col(j));
          };
          for (int s = 0; s < kSteps; ++s) {
            for (int t = 0; t < kSteps; ++t) at(2 * inner(s) - 1, 2 * inner(t) - 1);
          }
          for (int s = 0; s < kSteps; ++s) {
            for (double e : {-1.0, 1.0}) at(2 * inner(s) - 1, e), at(e, 2 * inner(s) - 1);
          }
          ends.push_back(face(std::move(f)));
        }
        d.all.push_back({2 * b->halfSize[k], false, ends});
      }
    } else if (const auto* c = p.as<Cylinder>()) {
      const Mat3 f = frameOf(c->axis);
      const double h = c->height;
      const Face* side = face(revolved(
          c->center, f, [&](double) { return c->radius; },
          [&](double t) { return (t - 0.5) * h; }));
      const Face* lo = face(disc(c->center - 0.5 * h * c->axis, f, c->radius));
      const Face* hi = face(disc(c->center + 0.5 * h * c->axis, f, c->radius));
      d.all.push_back({c->radius, true, {side}});
      d.all.push_back({h, false, {lo, hi}});
    } else if (const auto* c = p.as<Cone>()) {
      const Mat3 f = frameOf(c->axis);
      const double h = c->height;
      const Face* lo = face(disc(c->center - 0.5 * h * c->axis, f, c->radiusBottom));
      const Face* hi = face(disc(c->center + 0.5 * h * c->axis, f, c->radiusTop));
      d.all.push_back({c->radiusBottom, true, {lo}});
      d.all.push_back({c->radiusTop, true, {hi}});
      d.all.push_back({h, false, {lo, hi}});
    } else if (const auto* s = p.as<Sphere>()) {
      const Face* surface = face(revolved(
          s->center, Mat3::Identity(),
          [&](double t) { return s->radius * std::sin(std::numbers::pi * t); },
          [&](double t) { return -s->radius * std::cos(std::numbers::pi * t); }));
      d.all.push_back({s->radius, true, {surface}});
    } else if (const auto* t = p.as<Torus>()) {
      const Mat3 f = frameOf(t->axis);
      const Face* surface = face(revolved(
          t->center, f,
          [&](double u) {
            return t->majorRadius + t->minorRadius * std::cos(2 * std::numbers::pi * u);
          },
          [&](double u) { return t->minorRadius * std::sin(2 * std::numbers::pi * u); }));
      d.all.push_back({t->majorRadius, true, {surface}});
      d.all.push_back({t->minorRadius, true, {surface}});
    }
  }
  return d;
}

// Some of the face's points on the boundary of `truth`.
bool shows(const Face& f, const CsgTree& truth, double eps) {
  for (const Vec3& p : f.points) {
    if (std::abs(truth.value(p)) <= eps) return true;
  }
  return false;
}

// The distinct observable dimensions on the hundredths: value -> radius?
std::vector<std::pair<double, bool>> observable(const CsgTree& truth) {
  const PartDimensions d = dimensionsOf(truth);
  const double eps = 1e-7 * truth.bounds().diagonal();
  std::map<std::pair<bool, long>, double> out;
  for (const Dimension& dim : d.all) {
    if (!onHundredths(dim.value)) continue;
    const bool seen = std::all_of(dim.faces.begin(), dim.faces.end(),
                                  [&](const Face* f) { return shows(*f, truth, eps); });
    if (seen) out[{dim.radius, std::lround(dim.value * 100)}] = dim.value;
  }
  std::vector<std::pair<double, bool>> list;
  for (const auto& [key, v] : out) list.emplace_back(v, key.first);
  return list;
}

bool same(double a, double b) { return std::abs(a - b) <= 1e-9 * std::max(1.0, std::abs(b)); }

// Is the dimension a parameter of the designed tree, as its kind?
bool found(const DesignedTree& d, double value, bool radius) {
  static const std::regex radiusName("_(r|r0|r1|major_r|minor_r)$");
  static const std::regex sizeName("_(width|depth|d[xyz])$");
  static const std::regex positionName("_([xyz])[01]?$");
  std::map<char, std::vector<double>> positions;
  for (const DesignParameter& p : d.parameters) {
    if (p.kind != ParameterKind::Length) continue;
    std::smatch m;
    if (radius) {
      if (std::regex_search(p.name, radiusName) && same(p.value, value)) return true;
      continue;
    }
    if (std::regex_search(p.name, sizeName) && same(std::abs(p.value), value)) return true;
    if (std::regex_search(p.name, m, positionName)) positions[m[1].str()[0]].push_back(p.value);
  }
  for (const auto& [axis, values] : positions) {
    for (std::size_t i = 0; i < values.size(); ++i) {
      for (std::size_t j = i + 1; j < values.size(); ++j) {
        if (same(std::abs(values[i] - values[j]), value)) return true;
      }
    }
  }
  return false;
}

struct Count {
  int found = 0, of = 0;
  std::vector<std::string> missed;
};

// The main job's designed tree from one scan, and its count.
Count countDimensions(const fs::path& dir, const std::string& scanName) {
  const CsgTree truth = readTreeJson(dir / "tree.json");
  const Scan scan = readScan(dir / scanName);
  const Reconstruction rec = reconstruct(scan.cloud);
  Count c;
  if (!rec.ok()) {
    ADD_FAILURE() << dir / scanName << ": " << rec.message;
    return c;
  }
  const DesignedTree d = designTree(rec.tree, scan.cloud.points);
  for (const auto& [value, radius] : observable(truth)) {
    ++c.of;
    if (found(d, value, radius)) {
      ++c.found;
    } else {
      char text[64];
      std::snprintf(text, sizeof text, "%s %g", radius ? "radius" : "length", value);
      c.missed.push_back(text);
    }
  }
  return c;
}

// The observable dimensions of a few parts, by hand: a through-hole's length
// is not one, a blind hole's depth and a plate's thickness are.
TEST(DesignDimensions, ObservableDimensionsOfTheTrueTrees) {
  const auto has = [](const std::vector<std::pair<double, bool>>& list, double v, bool radius) {
    return std::find(list.begin(), list.end(), std::pair{v, radius}) != list.end();
  };
  const auto flange = observable(readTreeJson(test::dataDir() / "flange" / "tree.json"));
  EXPECT_TRUE(has(flange, 5.0, true)) << "the bolt holes' radius";
  EXPECT_TRUE(has(flange, 50.0, true)) << "the plate's radius";
  EXPECT_FALSE(has(flange, 41.0, false)) << "the bore runs through: its length is not seen";
  const auto pipe = observable(readTreeJson(test::dataDir() / "pipe_tee" / "tree.json"));
  EXPECT_FALSE(has(pipe, 114.0, false)) << "the run's bore passes both ends";
  EXPECT_TRUE(has(pipe, 110.0, false)) << "the run's length";
  const auto shaft = observable(readTreeJson(test::dataDir() / "stepped_shaft" / "tree.json"));
  EXPECT_FALSE(has(shaft, 41.0, true)) << "a chamfer cone's cap outside the shaft";
}

class DesignDimensions : public ::testing::TestWithParam<fs::path> {};

// Parts whose clean scan misses an observable dimension, with the measured
// reason (none now: the test fails when one is missed).
struct KnownGap {
  const char* part;
  const char* dimension;
  const char* reason;
};
const std::vector<KnownGap> kKnownGaps = {};

TEST_P(DesignDimensions, CleanScanGivesEveryObservableDimension) {
  const fs::path dir = GetParam();
  const Count c = countDimensions(dir, "scan.ply");
  std::printf("%s clean: %d of %d observable dimensions\n", dir.filename().c_str(), c.found, c.of);
  for (const std::string& m : c.missed) {
    const bool known = std::any_of(kKnownGaps.begin(), kKnownGaps.end(), [&](const KnownGap& g) {
      return dir.filename() == g.part && m == g.dimension;
    });
    EXPECT_TRUE(known) << dir.filename() << ": " << m << " not found";
  }
}

INSTANTIATE_TEST_SUITE_P(BundledParts, DesignDimensions, ::testing::ValuesIn(partDirs()),
                         [](const auto& info) { return info.param.filename().string(); });

TEST(DesignDimensions, NoisyScansGiveEightyPercent) {
  int found = 0, of = 0;
  for (const fs::path& dir : partDirs()) {
    const Count c = countDimensions(dir, "scan_noisy.ply");
    std::printf("%s noisy: %d of %d", dir.filename().c_str(), c.found, c.of);
    for (const std::string& m : c.missed) std::printf("; %s", m.c_str());
    std::printf("\n");
    found += c.found;
    of += c.of;
  }
  std::printf("noisy scans: %d of %d observable dimensions\n", found, of);
  ASSERT_GT(of, 0);
  EXPECT_GE(double(found), 0.8 * of);
}

}  // namespace
}  // namespace csgvox
