#include "io/scad_export.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <ostream>
#include <set>
#include <stdexcept>
#include <string>
#include <variant>

#include "core/export_cutters.h"
#include "core/export_extent.h"
#include "io/file_util.h"
#include "io/tree_names.h"

namespace csgvox {
namespace {

constexpr double kDeg = 180.0 / std::numbers::pi;

std::string vec(const Vec3& v) { return formatVector(v); }

std::string translate(const Vec3& c) {
  if (c.isZero(0.0)) return "";
  return "translate(" + vec(c) + ") ";
}

// Rotation taking +z to `axis`, as OpenSCAD's rotate(a, v).
std::string rotateZTo(const Vec3& axis) {
  const Vec3 z = Vec3::UnitZ();
  const double c = std::clamp(z.dot(axis), -1.0, 1.0);
  if (c >= 1.0 - 1e-15) return "";
  if (c <= -1.0 + 1e-15) return "rotate(a = 180, v = [1, 0, 0]) ";
  const Vec3 v = z.cross(axis).normalized();
  return "rotate(a = " + formatNumber(std::acos(c) * kDeg) + ", v = " + vec(v) + ") ";
}

// OpenSCAD's rotate([a, b, c]) is Rz(c) * Ry(b) * Rx(a).
std::string rotateEuler(const Mat3& r) {
  if (r.isIdentity(1e-15)) return "";
  double a, b, c;
  const double sb = std::clamp(-r(2, 0), -1.0, 1.0);
  b = std::asin(sb);
  if (std::abs(sb) < 1.0 - 1e-12) {
    a = std::atan2(r(2, 1), r(2, 2));
    c = std::atan2(r(1, 0), r(0, 0));
  } else {
    c = 0.0;
    a = std::atan2(-r(1, 2), r(1, 1));
  }
  return "rotate(" + vec(Vec3(a, b, c) * kDeg) + ") ";
}



struct Writer {
  std::ostream& out;
  const std::unordered_map<const Node*, std::string>& names;
  // The grown module of each leaf that both adds and removes material.
  const std::unordered_map<const Node*, std::string>& cutNames;
  Aabb reach;          // what the stand-ins of unbounded sets cover (standInExtent)
  double bigSize = 0;  // edge of the cubes standing in for unbounded sets
  const ScadOptions& options;
  double tolerance = 0.0;  // chord tolerance, scan units

  // $fn of a circle of radius r (`coarser`: multiple of the tolerance).
  std::string fn(double r, double coarser = 1.0, int lo = 0) const {
    return scadSegments(r, coarser * tolerance, options, lo);
  }

  std::string cube(const StandInCube& c) const {
    return translate(c.center) + rotateEuler(c.frame) + "cube(" + vec(Vec3::Constant(c.edge)) +
           ", center = true);";
  }

  std::string body(const Primitive& p) const {
    if (const auto* h = p.as<HalfSpace>()) {
      // A slab of the half-space covering the part: its top face is the plane.
      return cube(halfSpaceCube(*h, reach, bigSize)) + "  // halfspace " + vec(h->normal) +
             ".x <= " + formatNumber(h->offset);
    }
    if (const auto* b0 = p.as<Box>()) {
      const Box b = canonicalBox(*b0);
      return translate(b.center) + rotateEuler(b.axes) + "cube(" + vec(2.0 * b.halfSize) +
             ", center = true);";
    }
    if (const auto* c = p.as<Cylinder>()) {
      return translate(c->center) + rotateZTo(c->axis) + "cylinder(h = " + formatNumber(c->height) +
             ", r = " + formatNumber(c->radius) + ", center = true, " + fn(c->radius) + ");";
    }
    if (const auto* c = p.as<Cone>()) {
      return translate(c->center) + rotateZTo(c->axis) + "cylinder(h = " + formatNumber(c->height) +
             ", r1 = " + formatNumber(c->radiusBottom) + ", r2 = " + formatNumber(c->radiusTop) +
             ", center = true, " + fn(std::max(c->radiusBottom, c->radiusTop)) + ");";
    }
    if (const auto* s = p.as<Sphere>()) {
      return translate(s->center) + "sphere(r = " + formatNumber(s->radius) + ", " +
             fn(s->radius, options.surfaceCoarsening) + ");";
    }
    if (const auto* t = p.as<Torus>()) {
      // Its tube swept round the axis: both circles' segments multiply.
      return translate(t->center) + rotateZTo(t->axis) + "rotate_extrude(" +
             fn(t->majorRadius + t->minorRadius, options.surfaceCoarsening) + ") translate([" +
             formatNumber(t->majorRadius) + ", 0]) circle(r = " + formatNumber(t->minorRadius) +
             ", " + fn(t->minorRadius, options.surfaceCoarsening, options.minTubeSegments) + ");";
    }
    return "";
  }

  void node(const Node& n, int indent, bool removes) const {
    const std::string pad(std::size_t(2 * indent), ' ');
    switch (n.kind) {
      case NodeKind::Primitive:
        out << pad << (removes && cutNames.count(&n) ? cutNames.at(&n) : names.at(&n)) << "();\n";
        return;
      case NodeKind::Complement:
        out << pad << "difference() {\n"
            << pad << "  " << cube(surroundingCube(reach, bigSize))
            << "  // everything around the part\n";
        node(*n.children.front(), indent + 1, removes != subtractsOperand(n, 0));
        out << pad << "}\n";
        return;
      default:
        out << pad << nodeKindName(n.kind) << "() {\n";
        for (std::size_t i = 0; i < n.children.size(); ++i) {
          node(*n.children[i], indent + 1, removes != subtractsOperand(n, i));
        }
        out << pad << "}\n";
    }
  }
};

}  // namespace

// Sides of a polygon inscribed in a circle of radius r whose chords stay
// within `tolerance` (sagitta r·(1 − cos(π/n))), rounded up to the next of 8,
// 12, 16, 24, 32, 48, 64, 96, ... (multiples of four, so the circle's
// extremes along its frame's axes are vertices; and coaxial surfaces of close
// radii, a thin wall's two sides, get the same count, so their vertices line
// up and the wall keeps its thickness), clamped to [lo, hi].
std::string scadSegments(double r, double tolerance, const ScadOptions& options, int minimum) {
  int n = options.facets;
  if (n <= 0) {
    const int lo = std::max(minimum, options.minSegments), hi = options.maxSegments;
    double exact = double(hi);
    if (tolerance >= r) {
      exact = double(lo);
    } else if (tolerance > 0.0) {
      exact = std::numbers::pi / std::acos(1.0 - tolerance / r);
    }
    n = 8;
    for (int k = 0; n < exact && n < hi; ++k) n = (k % 2 == 0) ? n * 3 / 2 : n * 4 / 3;
    n = std::clamp(n, lo, hi);
  }
  return "$fn = segments(" + std::to_string(n) + ")";
}

void writeScad(std::ostream& out, const CsgTree& tree, const ScadOptions& options) {
  const Aabb part = exportExtent(tree);
  const auto names = leafNames(tree);
  const LeafRoles roles = leafRoles(tree);
  const auto& adds = roles.adding;
  const auto& removes = roles.removing;
  const double overcut = options.overcut * part.diagonal();
  std::unordered_map<const Node*, std::string> cutNames;
  std::set<std::string> taken;
  for (const auto& [leaf, name] : names) taken.insert(name);
  for (const Node* leaf : tree.leaves()) {  // in the tree's order, so names are stable
    if (!(overcut > 0.0) || !adds.count(leaf) || !removes.count(leaf)) continue;
    if (cutNames.count(leaf)) continue;  // a leaf the tree shares
    std::string name = names.at(leaf) + "_cut";
    for (int k = 1; taken.count(name); ++k) name = names.at(leaf) + "_cut_" + std::to_string(k);
    taken.insert(name);
    cutNames[leaf] = name;
  }
  const Aabb reach = standInExtent(tree);
  const double tolerance = options.chordTolerance * part.diagonal();
  const double edge = options.halfSpaceScale * std::max(reach.diagonal(), 1e-9);
  Writer w{out, names, cutNames, reach, edge, options, tolerance};
  out << "// CSG tree written by csgvox. Units are those of the scan.\n"
      << "// Each primitive is a module below; the solid is the expression at the end.\n";
  if (overcut > 0.0 && !removes.empty()) {
    out << "// Primitives that cut are written " << formatNumber(overcut)
        << " larger on every side, so that a hole\n"
           "// ending on the face it goes through leaves no film of that face.\n";
  }
  char within[96];
  std::snprintf(within, sizeof within, "%.3g of the true surface (%.3g on spheres and tori)",
                tolerance, options.surfaceCoarsening * tolerance);
  out << "// Curved primitives are polygons of segments(n) sides, n chosen from their size so\n"
         "// that facets lie within "
      << within
      << ".\n"
         "// For a finer render raise detail: 2 doubles every count (facets 4x closer),\n"
         "// and makes rendering (F6) several times slower.\n"
      << "detail = 1;\n"
      << "function segments(n) = max(3, round(n * detail));\n\n";
  for (const Node* leaf : tree.distinctLeaves()) {
    const std::string& name = names.at(leaf);
    const bool cuts = overcut > 0.0 && removes.count(leaf) > 0;
    if (adds.count(leaf) || !cuts) {
      out << "module " << name << "() " << w.body(leaf->primitive) << "\n";
    }
    if (cuts) {
      out << "module " << (cutNames.count(leaf) ? cutNames.at(leaf) : name) << "() "
          << w.body(grownPrimitive(leaf->primitive, overcut)) << "\n";
    }
  }
  out << "\n";
  w.node(*tree.root(), 0, false);
}

void writeScad(const std::filesystem::path& path, const CsgTree& tree, const ScadOptions& options) {
  writeFileAtomically(path, [&](std::ostream& out) { writeScad(out, tree, options); });
}

}  // namespace csgvox
