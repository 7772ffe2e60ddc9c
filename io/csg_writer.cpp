#include "io/csg_writer.h"

#include <ostream>
#include <string>

#include "core/export_cutters.h"
#include "core/export_extent.h"
#include "io/file_util.h"
#include "io/tree_names.h"

namespace csgvox {
namespace {

// The exact rotation nearest a frame the tree keeps orthonormal to ~1e-6:
// FreeCAD turns a multmatrix into a placement only when it is a rotation.
Mat3 exactRotation(const Mat3& frame) {
  return Eigen::Quaterniond(frame).normalized().toRotationMatrix();
}

std::string multmatrix(const Mat3& frame, const Vec3& t) {
  const Mat3 r = exactRotation(frame);
  std::string s = "multmatrix([";
  for (int i = 0; i < 3; ++i) {
    s += "[" + formatNumber(r(i, 0)) + ", " + formatNumber(r(i, 1)) + ", " + formatNumber(r(i, 2)) +
         ", " + formatNumber(t[i]) + "], ";
  }
  return s + "[0, 0, 0, 1]])";
}

const char* kExact = "$fn = 0, $fa = 12, $fs = 2";

struct Writer {
  std::ostream& out;
  const std::unordered_map<const Node*, std::string>& names;
  Aabb reach;  // what the stand-ins of unbounded sets cover (standInExtent)
  double bigEdge = 0.0;
  double overcut = 0.0;  // how much a primitive that removes material is grown

  void placed(const std::string& pad, const Mat3& frame, const Vec3& t, const std::string& body,
              const std::string& comment) const {
    out << pad << multmatrix(frame, t) << " {\n"
        << pad << "  " << body << (comment.empty() ? "" : "  // " + comment) << "\n"
        << pad << "}\n";
  }

  void cube(const std::string& pad, const StandInCube& c, const std::string& comment) const {
    const std::string e = formatNumber(c.edge);
    placed(pad, c.frame, c.center, "cube(size = [" + e + ", " + e + ", " + e + "], center = true);",
           comment);
  }

  void leaf(const Node& n, const std::string& pad, bool removes) const {
    const std::string& name = names.at(&n);
    const Primitive p =
        removes && overcut > 0.0 ? grownPrimitive(n.primitive, overcut) : n.primitive;
    if (const auto* h = p.as<HalfSpace>()) {
      cube(pad, halfSpaceCube(*h, reach, bigEdge),
           name + ": halfspace " + formatVector(h->normal) + ".x <= " + formatNumber(h->offset));
    } else if (const auto* b0 = p.as<Box>()) {
      const Box b = canonicalBox(*b0);
      placed(pad, b.axes, b.center,
             "cube(size = " + formatVector(2.0 * b.halfSize) + ", center = true);", name);
    } else if (const auto* c = p.as<Cylinder>()) {
      const std::string r = formatNumber(c->radius);
      placed(pad, frameFromAxis(c->axis), c->center,
             std::string("cylinder(") + kExact + ", h = " + formatNumber(c->height) +
                 ", r1 = " + r + ", r2 = " + r + ", center = true);",
             name);
    } else if (const auto* c = p.as<Cone>()) {
      placed(pad, frameFromAxis(c->axis), c->center,
             std::string("cylinder(") + kExact + ", h = " + formatNumber(c->height) +
                 ", r1 = " + formatNumber(c->radiusBottom) +
                 ", r2 = " + formatNumber(c->radiusTop) + ", center = true);",
             name);
    } else if (const auto* s = p.as<Sphere>()) {
      placed(pad, Mat3::Identity(), s->center,
             std::string("sphere(") + kExact + ", r = " + formatNumber(s->radius) + ");", name);
    } else if (const auto* t = p.as<Torus>()) {
      out << pad << multmatrix(frameFromAxis(t->axis), t->center) << " {  // " << name << "\n"
          << pad << "  rotate_extrude(angle = 360, convexity = 2, " << kExact << ") {\n"
          << pad << "    " << multmatrix(Mat3::Identity(), Vec3(t->majorRadius, 0, 0)) << " {\n"
          << pad << "      circle(" << kExact << ", r = " << formatNumber(t->minorRadius) << ");\n"
          << pad << "    }\n"
          << pad << "  }\n"
          << pad << "}\n";
    }
  }

  // `removes`: the node's material is removed from the part (it lies
  // under an odd number of subtracted operands).
  void node(const Node& n, int indent, bool removes) const {
    const std::string pad(std::size_t(2 * indent), ' ');
    switch (n.kind) {
      case NodeKind::Primitive:
        leaf(n, pad, removes);
        return;
      case NodeKind::Complement:
        out << pad << "difference() {\n";
        cube(pad + "  ", surroundingCube(reach, bigEdge), "everything around the part");
        node(*n.children.front(), indent + 1, !removes);
        out << pad << "}\n";
        return;
      case NodeKind::Intersection:
        intersection(n, 0, indent, removes);
        return;
      default:
        if (n.children.size() == 1) {
          node(*n.children.front(), indent, removes);
          return;
        }
        out << pad << nodeKindName(n.kind) << "() {\n";
        for (std::size_t i = 0; i < n.children.size(); ++i) {
          node(*n.children[i], indent + 1, removes != subtractsOperand(n, i));
        }
        out << pad << "}\n";
    }
  }

  // The intersection of children first.. as nested pairs: FreeCAD's
  // importer (0.20) fails on an intersection of one or of more than two.
  void intersection(const Node& n, std::size_t first, int indent, bool removes) const {
    if (first + 1 == n.children.size()) {
      node(*n.children[first], indent, removes);
      return;
    }
    const std::string pad(std::size_t(2 * indent), ' ');
    out << pad << "intersection() {\n";
    node(*n.children[first], indent + 1, removes);
    intersection(n, first + 1, indent + 1, removes);
    out << pad << "}\n";
  }
};

}  // namespace

void writeCsg(std::ostream& out, const CsgTree& tree, const CsgOptions& options) {
  const Aabb extent = exportExtent(tree);
  const auto names = leafNames(tree);
  const Aabb reach = standInExtent(tree);
  const Writer w{out, names, reach, options.halfSpaceScale * std::max(reach.diagonal(), 1e-9),
                 options.overcut * extent.diagonal()};
  out << "// CSG tree written by csgvox in OpenSCAD's CSG format; units are the scan's.\n"
      << "// FreeCAD opens it as a feature tree (File > Open, importCSG).\n";
  if (w.overcut > 0.0 && !leafRoles(tree).removing.empty()) {
    out << "// Primitives that cut are written " << formatNumber(w.overcut)
        << " larger on every side, so that a hole\n"
           "// ending on the face it goes through cuts that face.\n";
  }
  w.node(*tree.root(), 0, false);
}

void writeCsg(const std::filesystem::path& path, const CsgTree& tree, const CsgOptions& options) {
  writeFileAtomically(path, [&](std::ostream& out) { writeCsg(out, tree, options); });
}

}  // namespace csgvox
