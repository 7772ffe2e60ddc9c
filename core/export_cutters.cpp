#include "core/export_cutters.h"

#include <algorithm>

namespace csgvox {
namespace {

void collectRoles(const Node& n, bool removes, LeafRoles& roles) {
  if (n.kind == NodeKind::Primitive) {
    (removes ? roles.removing : roles.adding).insert(&n);
    return;
  }
  for (std::size_t i = 0; i < n.children.size(); ++i) {
    collectRoles(*n.children[i], removes != subtractsOperand(n, i), roles);
  }
}

}  // namespace

Primitive grownPrimitive(const Primitive& p, double m) {
  PrimitiveShape s = p.shape();
  if (auto* h = std::get_if<HalfSpace>(&s)) {
    h->offset += m;
  } else if (auto* b = std::get_if<Box>(&s)) {
    b->halfSize.array() += m;
  } else if (auto* c = std::get_if<Cylinder>(&s)) {
    c->radius += m;
    c->height += 2.0 * m;
  } else if (auto* k = std::get_if<Cone>(&s)) {
    const double slope = (k->radiusTop - k->radiusBottom) / k->height;
    k->radiusBottom = std::max(0.0, k->radiusBottom - slope * m) + m;
    k->radiusTop = std::max(0.0, k->radiusTop + slope * m) + m;
    k->height += 2.0 * m;
  } else if (auto* sp = std::get_if<Sphere>(&s)) {
    sp->radius += m;
  } else if (auto* t = std::get_if<Torus>(&s)) {
    t->minorRadius += m;
  }
  return Primitive(s);
}

bool subtractsOperand(const Node& n, std::size_t i) {
  return n.kind == NodeKind::Complement || (n.kind == NodeKind::Difference && i > 0);
}

LeafRoles leafRoles(const CsgTree& tree) {
  LeafRoles roles;
  if (!tree.empty()) collectRoles(*tree.root(), false, roles);
  return roles;
}

}  // namespace csgvox
