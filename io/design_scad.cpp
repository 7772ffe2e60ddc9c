#include "io/design_scad.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <ostream>
#include <regex>
#include <set>
#include <sstream>
#include <stdexcept>

#include "core/export_cutters.h"
#include "core/export_extent.h"
#include "io/file_util.h"
#include "io/tree_names.h"

namespace csgvox {
namespace {

constexpr const char* kBodyMarker = "// ---- primitives";

std::string sig(double v, int digits = 6) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*g", digits, v);
  return buf;
}

// The comment of a parameter: where its value comes from.
std::string comment(const DesignParameter& p, UnitSystem units) {
  if (p.kind == ParameterKind::Count) return p.usedBy;
  std::string s;
  if (units == UnitSystem::Inch && p.snapped && p.kind == ParameterKind::Length) {
    const std::string in = inchText(p.value);
    if (!in.empty()) s += in + ", ";
  }
  if (p.snapped && p.value == p.fitted) {
    s += "fitted exactly";
  } else {
    s += std::string(p.snapped ? "fitted " : "as fitted: ") + sig(p.fitted, 9);
  }
  if (std::isfinite(p.uncertainty)) {
    s += " ± " + sig(p.uncertainty, 2);
  } else {
    s += " (no point holds it)";
  }
  if (!p.usedBy.empty()) s += ", " + p.usedBy;
  return s;
}

struct DesignWriter {
  std::ostream& out;
  const DesignedTree& d;
  const ScadOptions& options;
  double tolerance = 0.0;

  std::string e(const Expression& x) const { return x.text(d.parameters); }
  // "a + g", "a - g" with the growth.
  std::string grown(const Expression& x, const char* sign) const {
    return e(x) + " " + sign + " g";
  }
  std::string width(const Expression& lo, const Expression& hi) const {
    return e(hi) + " - " + (lo.terms.size() > 1 ? "(" + e(lo) + ")" : e(lo)) + " + 2 * g";
  }
  std::string fn(double r, double coarser = 1.0, int lo = 0) const {
    return scadSegments(r, coarser * tolerance, options, lo);
  }

  std::string body(int index) const {
    const DesignedLeaf& l = d.leaves[std::size_t(index)];
    const Primitive p = d.localPrimitive(index);
    const bool onCircle =
        l.pattern >= 0 && d.patterns[std::size_t(l.pattern)].kind == PatternKind::Circular;
    const auto at = [&](int k) {
      return onCircle && k < 2 ? std::string("0") : e(l.at[std::size_t(k)]);
    };
    switch (l.form) {
      case LeafForm::AlignedBox:
        return "translate([" + grown(l.lo[0], "-") + ", " + grown(l.lo[1], "-") + ", " +
               grown(l.lo[2], "-") + "]) cube([" + width(l.lo[0], l.hi[0]) + ", " +
               width(l.lo[1], l.hi[1]) + ", " + width(l.lo[2], l.hi[2]) + "]);";
      case LeafForm::TurnedBox:
        return "translate([" + e(l.at[0]) + ", " + e(l.at[1]) + ", " + grown(l.lo[2], "-") +
               "]) rotate([0, 0, " + e(l.angle) + "]) translate([-" + e(l.radius) + " / 2 - g, -" +
               e(l.radius2) + " / 2 - g, 0]) cube([" + e(l.radius) + " + 2 * g, " + e(l.radius2) +
               " + 2 * g, " + width(l.lo[2], l.hi[2]) + "]);";
      case LeafForm::Axial: {
        const int a = l.axis;
        const char* turn = a == 0 ? "along_x() " : a == 1 ? "along_y() " : "";
        std::string pos[3];
        for (int k = 0; k < 3; ++k) pos[k] = at(k);
        if (l.type == PrimitiveType::Torus) {
          const Torus& t = *p.as<Torus>();
          return "translate([" + pos[0] + ", " + pos[1] + ", " + pos[2] + "]) " + turn +
                 "rotate_extrude(" + fn(t.majorRadius + t.minorRadius, options.surfaceCoarsening) +
                 ") translate([" + e(l.radius) + ", 0]) circle(r = " + grown(l.radius2, "+") +
                 ", " + fn(t.minorRadius, options.surfaceCoarsening, options.minTubeSegments) +
                 ");";
        }
        pos[a] = grown(l.lo[std::size_t(a)], "-");
        const std::string place =
            "translate([" + pos[0] + ", " + pos[1] + ", " + pos[2] + "]) " + turn;
        const std::string h = "h = " + width(l.lo[std::size_t(a)], l.hi[std::size_t(a)]);
        if (l.type == PrimitiveType::Cylinder) {
          return place + "cylinder(" + h + ", r = " + grown(l.radius, "+") + ", " +
                 fn(p.as<Cylinder>()->radius) + ");";
        }
        const Cone& c = *p.as<Cone>();
        // Caps out by g along the slope, every face out by g (as grownPrimitive).
        const std::string slope = "(" + e(l.radius2) + " - " + e(l.radius) + ") / (" +
                                  e(l.hi[std::size_t(a)]) + " - " + e(l.lo[std::size_t(a)]) + ")";
        return place + "cylinder(" + h + ", r1 = max(0, " + e(l.radius) + " - " + slope +
               " * g) + g, r2 = max(0, " + e(l.radius2) + " + " + slope + " * g) + g, " +
               fn(std::max(c.radiusBottom, c.radiusTop)) + ");";
      }
      case LeafForm::Sphere:
        return "translate([" + at(0) + ", " + at(1) + ", " + at(2) +
               "]) sphere(r = " + grown(l.radius, "+") + ", " +
               fn(p.as<Sphere>()->radius, options.surfaceCoarsening) + ");";
      case LeafForm::AlignedHalfSpace:
        return l.flipped ? "block_above(" + std::to_string(l.axis) + ", " +
                               grown(l.lo[std::size_t(l.axis)], "-") + ");"
                         : "block_below(" + std::to_string(l.axis) + ", " +
                               grown(l.hi[std::size_t(l.axis)], "+") + ");";
      case LeafForm::TiltedHalfSpace:
        return "plane_below(" + e(l.angle) + ", " + e(l.angle2) + ", " + grown(l.radius, "+") +
               ");";
      case LeafForm::Free:
        break;
    }
    return freeBody(l);
  }

  // An oblique primitive, as fitted (frame coordinates): its numbers stay.
  std::string freeBody(const DesignedLeaf& l) const {
    const Primitive& p = l.local;
    const auto place = [&](const Mat3& r, const Vec3& c) {
      std::string s = "multmatrix([";
      for (int i = 0; i < 3; ++i) {
        s += "[" + formatNumber(r(i, 0)) + ", " + formatNumber(r(i, 1)) + ", " +
             formatNumber(r(i, 2)) + ", " + formatNumber(c[i]) + "], ";
      }
      return s + "[0, 0, 0, 1]]) ";
    };
    if (const auto* b = p.as<Box>()) {
      return place(b->axes, b->center) + "cube([" + formatNumber(2 * b->halfSize.x()) +
             " + 2 * g, " + formatNumber(2 * b->halfSize.y()) + " + 2 * g, " +
             formatNumber(2 * b->halfSize.z()) + " + 2 * g], center = true);";
    }
    if (const auto* c = p.as<Cylinder>()) {
      return place(frameFromAxis(c->axis), c->center) + "cylinder(h = " + formatNumber(c->height) +
             " + 2 * g, r = " + formatNumber(c->radius) + " + g, center = true, " + fn(c->radius) +
             ");";
    }
    if (const auto* c = p.as<Cone>()) {
      return place(frameFromAxis(c->axis), c->center) + "cylinder(h = " + formatNumber(c->height) +
             " + 2 * g, r1 = " + formatNumber(c->radiusBottom) +
             " + g, r2 = " + formatNumber(c->radiusTop) + " + g, center = true, " +
             fn(std::max(c->radiusBottom, c->radiusTop)) + ");";
    }
    if (const auto* t = p.as<Torus>()) {
      return place(frameFromAxis(t->axis), t->center) + "rotate_extrude(" +
             fn(t->majorRadius + t->minorRadius, options.surfaceCoarsening) + ") translate([" +
             formatNumber(t->majorRadius) + ", 0]) circle(r = " + formatNumber(t->minorRadius) +
             " + g, " + fn(t->minorRadius, options.surfaceCoarsening, options.minTubeSegments) +
             ");";
    }
    const HalfSpace& h = *p.as<HalfSpace>();
    return place(frameFromAxis(h.normal), h.normal * h.offset) +
           "translate([-big / 2, -big / 2, g - big]) cube(big);";
  }

  std::string call(int index, bool removes) const {
    return d.leaves[std::size_t(index)].name + (removes ? "(overcut);" : "();");
  }

  std::string loop(const DesignedPattern& p, const std::string& member) const {
    const std::string n = d.parameters[std::size_t(p.count)].name;
    if (p.kind == PatternKind::Circular) {
      return "translate([" + e(p.centerX) + ", " + e(p.centerY) + ", 0]) for (i = [0 : " + n +
             " - 1]) rotate([0, 0, " + e(p.phase) + " + i * 360 / " + n + "]) translate([" +
             e(p.radius) + ", 0, 0]) " + member;
    }
    const auto vec = [&](const std::array<Expression, 3>& s) {
      return "[" + e(s[0]) + ", " + e(s[1]) + ", " + e(s[2]) + "]";
    };
    if (p.kind == PatternKind::Row) {
      return "for (i = [0 : " + n + " - 1]) translate(i * " + vec(p.step) + ") " + member;
    }
    const std::string n2 = d.parameters[std::size_t(p.count2)].name;
    return "for (i = [0 : " + n + " - 1], j = [0 : " + n2 + " - 1]) translate(i * " + vec(p.step) +
           " + j * " + vec(p.step2) + ") " + member;
  }

  void node(const Node& n, int indent, bool removes) const {
    const std::string pad(std::size_t(2 * indent), ' ');
    switch (n.kind) {
      case NodeKind::Primitive: {
        const int index = d.leafIndex(&n);
        const DesignedLeaf& l = d.leaves[std::size_t(index)];
        if (l.pattern < 0) {
          out << pad << call(index, removes) << "\n";
        } else if (l.member == 0) {
          const DesignedPattern& p = d.patterns[std::size_t(l.pattern)];
          out << pad << "// " << p.name << ": " << p.members.size() << " " << l.role << "s\n"
              << pad << loop(p, call(index, removes)) << "\n";
        }
        return;
      }
      case NodeKind::Complement:
        out << pad << "difference() {\n" << pad << "  everything();\n";
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

void writeDesignedScad(std::ostream& out, const DesignedTree& d, const ScadOptions& options) {
  if (d.fitted.empty()) throw std::invalid_argument("writeDesignedScad: empty tree");
  const CsgTree local = d.localTree();
  const Aabb part = exportExtent(local);
  const Aabb reach = standInExtent(local);
  const double overcut = options.overcut * part.diagonal();
  const double big = options.halfSpaceScale * std::max(reach.diagonal(), 1e-9);
  DesignWriter w{out, d, options, options.chordTolerance * part.diagonal()};

  out << "// CSG tree written by csgvox: the part as designed, units " << unitSystemName(d.units)
      << (d.units == UnitSystem::Inch ? " (values in millimetres, on an inch grid)" : "") << ".\n"
      << "// Each parameter below is the simplest value within the fit's uncertainty that\n"
      << "// keeps the tree on the scan (its fitted value in the comment); values the fit\n"
      << "// shares are one parameter. Change one and every use of it follows.\n\n";
  out << "// ---- parameters\n";
  for (const DesignParameter& p : d.parameters) {
    out << p.name << " = " << formatNumber(p.value) << ";  // " << comment(p, d.units) << "\n";
  }
  const Vec3 euler = d.frame.eulerDegrees();
  const bool unturned = d.frame.rotation == Mat3::Identity();  // no rotation to write
  if (!d.frame.isIdentity()) {
    out << "\n// The part's frame in the scan: its primitives are drawn in the frame, then "
           "placed.\n"
        << "frame_origin = " << formatVector(d.frame.origin) << ";\n";
    if (!unturned) {
      out << "frame_rotation = " << formatVector(euler) << ";  // degrees about x, y, z\n";
    }
  }
  out << "\n// ---- drawing\n"
      << "// Curved primitives are polygons of segments(n) sides; raise detail for a finer "
         "render.\n"
      << "detail = 1;\n"
      << "function segments(n) = max(3, round(n * detail));\n"
      << "overcut = " << formatNumber(overcut)
      << ";  // cutters grow by this on every side, so a hole ending on a face leaves no film\n"
      << "big = " << formatNumber(big) << ";  // edge of the blocks standing in for half-spaces\n"
      << "part_center = " << formatVector(reach.center()) << ";\n"
      << "module along_x() rotate([0, 90, 0]) children();\n"
      << "module along_y() rotate([-90, 0, 0]) children();\n"
      << "module block_below(axis, at) translate([for (k = [0 : 2]) k == axis ? at - big : "
         "part_center[k] - big / 2]) cube(big);\n"
      << "module block_above(axis, at) translate([for (k = [0 : 2]) k == axis ? at : "
         "part_center[k] - big / 2]) cube(big);\n"
      << "module everything() translate(part_center - [big, big, big] / 2) cube(big);\n"
      << "// The half-space normal·x <= at, its normal tilted from z, then turned about z "
         "(degrees).\n"
      << "module plane_below(tilt, turn, at) rotate([0, 0, turn]) rotate([0, tilt, 0]) "
         "translate([-big, -big, at - 2 * big]) cube(2 * big);\n\n";
  out << kBodyMarker << " (g: how much a cutter grows)\n";
  for (std::size_t i = 0; i < d.leaves.size(); ++i) {
    const DesignedLeaf& l = d.leaves[i];
    if (l.pattern >= 0 && l.member != 0) continue;
    out << "module " << l.name << "(g = 0) " << w.body(int(i));
    if (l.pattern >= 0) out << "  // one of " << d.patterns[std::size_t(l.pattern)].name;
    out << "\n";
  }
  out << "\n// ---- the part\n";
  int indent = 0;
  if (!d.frame.isIdentity()) {
    out << (unturned ? "translate(frame_origin) {\n"
                     : "translate(frame_origin) rotate(frame_rotation) {\n");
    indent = 1;
  }
  w.node(*d.fitted.root(), indent, false);
  if (indent) out << "}\n";
}

void writeDesignedScad(const std::filesystem::path& path, const DesignedTree& design,
                       const ScadOptions& options) {
  writeFileAtomically(path, [&](std::ostream& out) { writeDesignedScad(out, design, options); });
}

ScadLiteralCount countScadLiterals(const std::string& program) {
  ScadLiteralCount c;
  std::set<std::string> names;
  std::istringstream in(program);
  std::string line, body;
  bool inBody = false;
  const std::regex assignment(R"(^([A-Za-z_][A-Za-z0-9_]*) = )");
  while (std::getline(in, line)) {
    if (line.rfind(kBodyMarker, 0) == 0) {
      inBody = true;
      continue;
    }
    std::smatch m;
    if (!inBody && std::regex_search(line, m, assignment)) names.insert(m[1]);
    if (inBody) body += line.substr(0, line.find("//")) + "\n";
  }
  if (!inBody) {  // a program without a parameter block: all of it is body
    std::istringstream all(program);
    while (std::getline(all, line)) {
      if (line.rfind("detail", 0) == 0 || line.rfind("function", 0) == 0) continue;
      body += line.substr(0, line.find("//")) + "\n";
    }
  }
  body = std::regex_replace(body, std::regex(R"(segments\(\d+\))"), "segments()");
  const std::regex token(R"([A-Za-z_$][A-Za-z0-9_]*|\d+\.?\d*(?:[eE][-+]?\d+)?)");
  const std::set<std::string> structural = {"0", "1", "2", "360"};
  const std::set<std::string> drawing = {"overcut", "big", "part_center", "detail", "g", "i", "j"};
  for (auto it = std::sregex_iterator(body.begin(), body.end(), token);
       it != std::sregex_iterator(); ++it) {
    const std::string t = it->str();
    if (std::isdigit(static_cast<unsigned char>(t[0]))) {
      if (!structural.count(t)) ++c.numbers;
    } else if (names.count(t) && !drawing.count(t)) {
      ++c.numbers;
      ++c.parameters;
    }
  }
  return c;
}

}  // namespace csgvox
