#include "io/text_export.h"

#include <ostream>
#include <sstream>

#include "io/file_util.h"
#include "io/tree_names.h"

namespace csgvox {
namespace {

std::string vec(const Vec3& v) { return formatVector(v); }

std::string expression(const Node& node,
                       const std::unordered_map<const Node*, std::string>& names) {
  if (node.kind == NodeKind::Primitive) return names.at(&node);
  std::string s(nodeKindName(node.kind));
  s += "(";
  for (std::size_t i = 0; i < node.children.size(); ++i) {
    if (i) s += ", ";
    s += expression(*node.children[i], names);
  }
  return s + ")";
}

std::string definition(const Primitive& p) {
  std::ostringstream s;
  s << primitiveTypeName(p.type()) << "(";
  if (const auto* h = p.as<HalfSpace>()) {
    s << "normal=" << vec(h->normal) << ", offset=" << formatNumber(h->offset);
  } else if (const auto* b = p.as<Box>()) {
    s << "center=" << vec(b->center) << ", half_size=" << vec(b->halfSize) << ", axes=";
    if (b->axes.isIdentity(0.0)) {
      s << "identity";
    } else {
      s << "[" << vec(b->axes.col(0)) << ", " << vec(b->axes.col(1)) << ", " << vec(b->axes.col(2))
        << "]";
    }
  } else if (const auto* c = p.as<Cylinder>()) {
    s << "center=" << vec(c->center) << ", axis=" << vec(c->axis)
      << ", radius=" << formatNumber(c->radius) << ", height=" << formatNumber(c->height);
  } else if (const auto* c = p.as<Cone>()) {
    s << "center=" << vec(c->center) << ", axis=" << vec(c->axis)
      << ", radius_bottom=" << formatNumber(c->radiusBottom)
      << ", radius_top=" << formatNumber(c->radiusTop) << ", height=" << formatNumber(c->height);
  } else if (const auto* sp = p.as<Sphere>()) {
    s << "center=" << vec(sp->center) << ", radius=" << formatNumber(sp->radius);
  } else if (const auto* t = p.as<Torus>()) {
    s << "center=" << vec(t->center) << ", axis=" << vec(t->axis)
      << ", major_radius=" << formatNumber(t->majorRadius)
      << ", minor_radius=" << formatNumber(t->minorRadius);
  }
  s << ")";
  return s.str();
}

}  // namespace

std::string treeExpression(const CsgTree& tree) {
  if (tree.empty()) return "empty";
  return expression(*tree.root(), leafNames(tree));
}

void writeTreeText(std::ostream& out, const CsgTree& tree) {
  const auto names = leafNames(tree);
  out << (tree.empty() ? std::string("empty") : expression(*tree.root(), names)) << "\n";
  for (const Node* leaf : tree.distinctLeaves()) {
    out << names.at(leaf) << " = " << definition(leaf->primitive) << "\n";
  }
}

void writeTreeText(const std::filesystem::path& path, const CsgTree& tree) {
  writeFileAtomically(path, [&](std::ostream& out) { writeTreeText(out, tree); });
}

void writeTreeText(std::ostream& out, const DesignedTree& design) {
  writeTreeText(out, design.tree());
  for (const DesignedPattern& p : design.patterns) {
    out << p.name << " = " << p.kindName() << "(";
    for (std::size_t i = 0; i < p.members.size(); ++i) {
      out << (i ? ", " : "") << design.leaves[std::size_t(p.members[i])].name;
    }
    const auto v = [&](const Expression& e) { return formatNumber(e.value(design.parameters)); };
    const auto vec = [&](const std::array<Expression, 3>& s) {
      return formatVector(design.frame.rotation *
                          Vec3(s[0].value(design.parameters), s[1].value(design.parameters),
                               s[2].value(design.parameters)));
    };
    out << "; count = " << formatNumber(design.parameters[std::size_t(p.count)].value);
    if (p.kind == PatternKind::Circular) {
      out << ", axis = " << formatVector(design.frame.rotation.col(2)) << ", center = "
          << formatVector(design.frame.toWorld(Vec3(p.centerX.value(design.parameters),
                                                    p.centerY.value(design.parameters), 0.0)))
          << ", radius = " << v(p.radius) << ", phase = " << v(p.phase);
    } else {
      out << ", step = " << vec(p.step);
      if (p.kind == PatternKind::Lattice) {
        out << ", count2 = " << formatNumber(design.parameters[std::size_t(p.count2)].value)
            << ", step2 = " << vec(p.step2);
      }
    }
    out << ")\n";
  }
}

void writeTreeText(const std::filesystem::path& path, const DesignedTree& design) {
  writeFileAtomically(path, [&](std::ostream& out) { writeTreeText(out, design); });
}

}  // namespace csgvox
