#include "io/freecad_macro.h"

#include <cmath>
#include <map>
#include <ostream>
#include <stdexcept>

#include "core/export_cutters.h"
#include "core/export_extent.h"
#include "io/file_util.h"
#include "io/tree_names.h"

namespace csgvox {
namespace {

// A Python string literal.
std::string quoted(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

struct MacroWriter {
  std::ostream& out;
  const DesignedTree& d;
  double big = 1.0;
  Vec3 center = Vec3::Zero();  // of the half-space blocks, frame coordinates
  std::map<std::pair<const Node*, bool>, std::string> features{};
  int operations = 0;

  // An expression bound to the sheet.
  std::string e(const Expression& x) const {
    if (x.empty()) return "0";
    return x.textWith([&](int p) { return "Parameters." + d.parameters[std::size_t(p)].name; });
  }
  std::string p(const Expression& x) const { return "(" + e(x) + ")"; }

  // One Part feature: its type, name, fixed rotation (axis, degrees) and
  // bound properties.
  void feature(const std::string& type, const std::string& name, const Vec3& axis, double angle,
               const std::vector<std::pair<std::string, std::string>>& bound) {
    out << name << " = doc.addObject(" << quoted(type) << ", " << quoted(name) << ")\n";
    if (angle != 0.0) {
      out << name << ".Placement = App.Placement(App.Vector(0, 0, 0), App.Rotation(App.Vector("
          << formatNumber(axis.x()) << ", " << formatNumber(axis.y()) << ", "
          << formatNumber(axis.z()) << "), " << formatNumber(angle) << "))\n";
    }
    for (const auto& [prop, text] : bound) {
      out << "bind(" << name << ", " << quoted(prop) << ", " << quoted(text) << ")\n";
    }
  }

  // The feature of leaf `index` (pattern copy `member`), grown when it cuts.
  void leaf(int index, int member, bool cuts, const std::string& name) {
    const DesignedLeaf& l = d.leaves[std::size_t(index)];
    const std::string g = cuts ? "Parameters.overcut" : "0";
    // The offset of the copy: a row's or lattice's steps, or a circle's place.
    std::string dx = "0", dy = "0", dz = "0";
    bool onCircle = false;
    std::string cx, cy;
    if (l.pattern >= 0) {
      const DesignedPattern& pat = d.patterns[std::size_t(l.pattern)];
      const std::string n = "Parameters." + d.parameters[std::size_t(pat.count)].name;
      if (pat.kind == PatternKind::Circular) {
        const std::string angle = p(pat.phase) + " + " + std::to_string(member) + " * 360 / " + n;
        cx = p(pat.centerX) + " + " + p(pat.radius) + " * cos(" + angle + ")";
        cy = p(pat.centerY) + " + " + p(pat.radius) + " * sin(" + angle + ")";
        onCircle = true;
      } else {
        const int count = int(std::lround(d.parameters[std::size_t(pat.count)].value));
        const int i = member % count, j = member / count;
        std::string* off[3] = {&dx, &dy, &dz};
        for (int k = 0; k < 3; ++k) {
          *off[k] = std::to_string(i) + " * " + p(pat.step[std::size_t(k)]) + " + " +
                    std::to_string(j) + " * " + p(pat.step2[std::size_t(k)]);
        }
      }
    }
    const std::string off[3] = {dx, dy, dz};
    const auto at = [&](int k) {
      if (onCircle && k < 2) return k == 0 ? cx : cy;
      return p(l.at[std::size_t(k)]) + " + " + off[k];
    };
    const auto base = [&](int k, const std::string& v) {
      return std::make_pair(std::string(".Placement.Base.") + "xyz"[k], v);
    };
    const auto width = [&](int k) {
      return p(l.hi[std::size_t(k)]) + " - " + p(l.lo[std::size_t(k)]) + " + 2 * " + g;
    };
    const auto low = [&](int k) { return p(l.lo[std::size_t(k)]) + " - " + g + " + " + off[k]; };
    switch (l.form) {
      case LeafForm::AlignedBox:
        feature("Part::Box", name, Vec3::UnitZ(), 0.0,
                {{"Length", width(0)},
                 {"Width", width(1)},
                 {"Height", width(2)},
                 base(0, low(0)),
                 base(1, low(1)),
                 base(2, low(2))});
        return;
      case LeafForm::TurnedBox: {
        const std::string t = p(l.angle);
        const std::string u = "(-" + p(l.radius) + " / 2 - " + g + ")";
        const std::string v = "(-" + p(l.radius2) + " / 2 - " + g + ")";
        feature("Part::Box", name, Vec3::UnitZ(), 0.0,
                {{"Length", p(l.radius) + " + 2 * " + g},
                 {"Width", p(l.radius2) + " + 2 * " + g},
                 {"Height", width(2)},
                 {".Placement.Rotation.Angle", t},
                 base(0, at(0) + " + cos(" + t + ") * " + u + " - sin(" + t + ") * " + v),
                 base(1, at(1) + " + sin(" + t + ") * " + u + " + cos(" + t + ") * " + v),
                 base(2, low(2))});
        return;
      }
      case LeafForm::Axial: {
        const int a = l.axis;
        const Vec3 axis = a == 0 ? Vec3::UnitY() : Vec3::UnitX();
        const double angle = a == 0 ? 90.0 : a == 1 ? -90.0 : 0.0;
        std::vector<std::pair<std::string, std::string>> props;
        for (int k = 0; k < 3; ++k) {
          if (k != a || l.type == PrimitiveType::Torus) props.push_back(base(k, at(k)));
        }
        if (l.type == PrimitiveType::Torus) {
          props.push_back({"Radius1", e(l.radius)});
          props.push_back({"Radius2", p(l.radius2) + " + " + g});
          feature("Part::Torus", name, axis, angle, props);
          return;
        }
        props.push_back(base(a, low(a)));
        props.push_back({"Height", width(a)});
        if (l.type == PrimitiveType::Cylinder) {
          props.push_back({"Radius", p(l.radius) + " + " + g});
          feature("Part::Cylinder", name, axis, angle, props);
        } else {
          props.push_back({"Radius1", p(l.radius) + " + " + g});
          props.push_back({"Radius2", p(l.radius2) + " + " + g});
          feature("Part::Cone", name, axis, angle, props);
        }
        return;
      }
      case LeafForm::Sphere:
        feature(
            "Part::Sphere", name, Vec3::UnitZ(), 0.0,
            {{"Radius", p(l.radius) + " + " + g}, base(0, at(0)), base(1, at(1)), base(2, at(2))});
        return;
      case LeafForm::AlignedHalfSpace: {
        const int a = l.axis;
        std::vector<std::pair<std::string, std::string>> props = {{"Length", "Parameters.big"},
                                                                  {"Width", "Parameters.big"},
                                                                  {"Height", "Parameters.big"}};
        for (int k = 0; k < 3; ++k) {
          if (k == a) {
            props.push_back(
                base(k, l.flipped ? p(l.lo[std::size_t(a)]) + " - " + g
                                  : p(l.hi[std::size_t(a)]) + " + " + g + " - Parameters.big"));
          } else {
            props.push_back(base(k, formatNumber(center[k]) + " - Parameters.big / 2"));
          }
        }
        feature("Part::Box", name, Vec3::UnitZ(), 0.0, props);
        return;
      }
      default:
        break;
    }
    // Oblique: placed as it is now (its dimensions bound where they are parameters).
    const Primitive prim = grownPrimitive(d.localPrimitive(index), cuts ? overcut : 0.0);
    fixedFeature(prim, name);
  }

  double overcut = 0.0;

  void fixedFeature(const Primitive& prim, const std::string& name) {
    const auto placement = [&](const Mat3& r, const Vec3& origin) {
      out << name << ".Placement = App.Placement(App.Matrix(";
      for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) out << formatNumber(r(i, j)) << ", ";
        out << formatNumber(origin[i]) << ", ";
      }
      out << "0, 0, 0, 1))\n";
    };
    if (const auto* b = prim.as<Box>()) {
      out << name << " = doc.addObject(\"Part::Box\", " << quoted(name) << ")\n"
          << name << ".Length = " << formatNumber(2 * b->halfSize.x()) << "\n"
          << name << ".Width = " << formatNumber(2 * b->halfSize.y()) << "\n"
          << name << ".Height = " << formatNumber(2 * b->halfSize.z()) << "\n";
      placement(b->axes, b->center - b->axes * b->halfSize);
    } else if (const auto* c = prim.as<Cylinder>()) {
      const Mat3 r = frameFromAxis(c->axis);
      out << name << " = doc.addObject(\"Part::Cylinder\", " << quoted(name) << ")\n"
          << name << ".Radius = " << formatNumber(c->radius) << "\n"
          << name << ".Height = " << formatNumber(c->height) << "\n";
      placement(r, c->center - 0.5 * c->height * c->axis);
    } else if (const auto* c = prim.as<Cone>()) {
      const Mat3 r = frameFromAxis(c->axis);
      out << name << " = doc.addObject(\"Part::Cone\", " << quoted(name) << ")\n"
          << name << ".Radius1 = " << formatNumber(c->radiusBottom) << "\n"
          << name << ".Radius2 = " << formatNumber(c->radiusTop) << "\n"
          << name << ".Height = " << formatNumber(c->height) << "\n";
      placement(r, c->center - 0.5 * c->height * c->axis);
    } else if (const auto* t = prim.as<Torus>()) {
      out << name << " = doc.addObject(\"Part::Torus\", " << quoted(name) << ")\n"
          << name << ".Radius1 = " << formatNumber(t->majorRadius) << "\n"
          << name << ".Radius2 = " << formatNumber(t->minorRadius) << "\n";
      placement(frameFromAxis(t->axis), t->center);
    } else if (const auto* s = prim.as<Sphere>()) {
      out << name << " = doc.addObject(\"Part::Sphere\", " << quoted(name) << ")\n"
          << name << ".Radius = " << formatNumber(s->radius) << "\n";
      placement(Mat3::Identity(), s->center);
    } else if (const auto* h = prim.as<HalfSpace>()) {
      // A block below the plane: its top face in the plane, centred on the
      // point of the plane nearest the part's centre.
      const Mat3 r = frameFromAxis(h->normal);
      const Vec3 onPlane = center - (h->normal.dot(center) - h->offset) * h->normal;
      out << name << " = doc.addObject(\"Part::Box\", " << quoted(name) << ")\n"
          << name << ".Length = " << formatNumber(big) << "\n"
          << name << ".Width = " << formatNumber(big) << "\n"
          << name << ".Height = " << formatNumber(big) << "\n";
      placement(r, onPlane - r * Vec3(0.5 * big, 0.5 * big, big));
    }
  }

  std::string node(const Node& n, bool removes) {
    if (n.kind == NodeKind::Primitive) {
      const auto key = std::make_pair(&n, removes);
      if (const auto it = features.find(key); it != features.end()) return it->second;
      const int index = d.leafIndex(&n);
      const DesignedLeaf& l = d.leaves[std::size_t(index)];
      std::string name = l.name;
      if (removes && l.adds) name += "_cut";
      leaf(index, l.member, removes, name);
      return features[key] = name;
    }
    std::vector<std::string> children;
    for (std::size_t i = 0; i < n.children.size(); ++i) {
      children.push_back(node(*n.children[i], removes != subtractsOperand(n, i)));
    }
    const std::string name = std::string(nodeKindName(n.kind)) + "_" + std::to_string(++operations);
    const auto list = [&](std::size_t from) {
      std::string s = "[";
      for (std::size_t i = from; i < children.size(); ++i)
        s += (i > from ? ", " : "") + children[i];
      return s + "]";
    };
    switch (n.kind) {
      case NodeKind::Union:
        out << name << " = doc.addObject(\"Part::MultiFuse\", " << quoted(name) << ")\n"
            << name << ".Shapes = " << list(0) << "\n";
        break;
      case NodeKind::Intersection:
        out << name << " = doc.addObject(\"Part::MultiCommon\", " << quoted(name) << ")\n"
            << name << ".Shapes = " << list(0) << "\n";
        break;
      case NodeKind::Difference: {
        std::string tool = children.size() > 1 ? children[1] : "";
        if (children.size() > 2) {
          tool = name + "_tools";
          out << tool << " = doc.addObject(\"Part::MultiFuse\", " << quoted(tool) << ")\n"
              << tool << ".Shapes = " << list(1) << "\n";
        }
        out << name << " = doc.addObject(\"Part::Cut\", " << quoted(name) << ")\n"
            << name << ".Base = " << children[0] << "\n"
            << name << ".Tool = " << tool << "\n";
        break;
      }
      default: {  // complement: everything around the part, less the operand
        const std::string all = name + "_everything";
        out << all << " = doc.addObject(\"Part::Box\", " << quoted(all) << ")\n";
        out << all << ".Length = " << all << ".Width = " << all << ".Height = " << formatNumber(big)
            << "\n"
            << all << ".Placement.Base = App.Vector(" << formatNumber(center.x() - big / 2) << ", "
            << formatNumber(center.y() - big / 2) << ", " << formatNumber(center.z() - big / 2)
            << ")\n";
        out << name << " = doc.addObject(\"Part::Cut\", " << quoted(name) << ")\n"
            << name << ".Base = " << all << "\n"
            << name << ".Tool = " << children[0] << "\n";
      }
    }
    return name;
  }
};

}  // namespace

void writeFreecadMacro(std::ostream& out, const DesignedTree& d,
                       const FreecadMacroOptions& options) {
  if (d.fitted.empty()) throw std::invalid_argument("writeFreecadMacro: empty tree");
  const CsgTree local = d.localTree();
  const Aabb part = exportExtent(local);
  const Aabb reach = standInExtent(local);
  MacroWriter w{out, d};
  w.big = options.halfSpaceScale * std::max(reach.diagonal(), 1e-9);
  w.center = reach.center();
  w.overcut = options.overcut * part.diagonal();
  out << "# tree.FCMacro written by csgvox: the part as designed, as a parametric FreeCAD\n"
         "# document. Run it in FreeCAD (Macro > Macros... > Execute) or with freecadcmd: it\n"
         "# builds a document \"csgvox\" whose Part features take their dimensions from the\n"
         "# spreadsheet Parameters (the parameters of tree.scad). Edit a cell and recompute:\n"
         "# every feature using it follows. The solid is the object \"part\".\n"
         "import FreeCAD as App\n"
         "import Part\n\n"
         "doc = App.newDocument(\"csgvox\")\n"
         "sheet = doc.addObject(\"Spreadsheet::Sheet\", \"Parameters\")\n"
         "sheet.set(\"A1\", \"parameter\")\n"
         "sheet.set(\"B1\", \"value\")\n"
         "sheet.set(\"C1\", \"note\")\n"
         "row = 1\n\n\n"
         "def parameter(name, value, note):\n"
         "    global row\n"
         "    row += 1\n"
         "    sheet.set(\"A%d\" % row, name)\n"
         "    sheet.set(\"B%d\" % row, repr(value))\n"
         "    sheet.setAlias(\"B%d\" % row, name)\n"
         "    sheet.set(\"C%d\" % row, note)\n\n\n"
         "def bind(obj, prop, expression):\n"
         "    obj.setExpression(prop, expression)\n\n\n";
  for (const DesignParameter& p : d.parameters) {
    std::string note = p.snapped ? "designed" : "as fitted";
    if (!p.usedBy.empty()) note += "; " + p.usedBy;
    out << "parameter(" << quoted(p.name) << ", " << formatNumber(p.value) << ", " << quoted(note)
        << ")\n";
  }
  out << "parameter(\"overcut\", " << formatNumber(w.overcut)
      << ", \"cutters grow by this on every side, so no film is left\")\n"
      << "parameter(\"big\", " << formatNumber(w.big)
      << ", \"edge of the blocks standing in for half-spaces\")\n"
      << "doc.recompute()\n\n";
  const std::string root = w.node(*d.fitted.root(), false);
  const Vec3 euler = d.frame.eulerDegrees();
  out << "\n# The part, placed by its frame (frame coordinates to the scan's).\n"
      << "part = doc.addObject(\"Part::Compound\", \"part\")\n"
      << "part.Links = [" << root << "]\n"
      << "part.Placement = App.Placement(App.Vector(" << formatNumber(d.frame.origin.x()) << ", "
      << formatNumber(d.frame.origin.y()) << ", " << formatNumber(d.frame.origin.z())
      << "), App.Rotation(" << formatNumber(euler.z()) << ", " << formatNumber(euler.y()) << ", "
      << formatNumber(euler.x()) << "))\n"
      << "doc.recompute()\n";
}

void writeFreecadMacro(const std::filesystem::path& path, const DesignedTree& design,
                       const FreecadMacroOptions& options) {
  writeFileAtomically(path, [&](std::ostream& out) { writeFreecadMacro(out, design, options); });
}

}  // namespace csgvox
