#include "core/export_extent.h"

#include <algorithm>
#include <array>
#include <stdexcept>

namespace csgvox {

Box canonicalBox(const Box& box) {
  static const std::array<std::array<int, 3>, 6> perms = {
      {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}}};
  Box best = box;
  double bestTrace = -1e300;
  for (const auto& perm : perms) {
    for (int signs = 0; signs < 8; ++signs) {
      Box b = box;
      for (int i = 0; i < 3; ++i) {
        b.axes.col(i) = box.axes.col(perm[i]) * ((signs >> i) & 1 ? -1.0 : 1.0);
        b.halfSize[i] = box.halfSize[perm[i]];
      }
      if (b.axes.determinant() <= 0.0) continue;
      if (b.axes.trace() > bestTrace + 1e-12) {
        bestTrace = b.axes.trace();
        best = b;
      }
    }
  }
  return best;
}

Aabb exportExtent(const CsgTree& tree) {
  if (tree.empty()) throw std::invalid_argument("cannot export an empty tree");
  Aabb part;
  for (const Node* leaf : tree.leaves()) {
    if (leaf->primitive.isBounded()) part.extend(leaf->primitive.bounds());
  }
  const Aabb solid = tree.bounds();
  if (solid.isBounded()) part = part.isBounded() ? part.intersected(solid) : solid;
  if (!part.isBounded() || part.isEmpty()) {
    throw std::invalid_argument("the tree has no bounded primitive to size its half-spaces by");
  }
  return part;
}

Aabb standInExtent(const CsgTree& tree) {
  Aabb reach = exportExtent(tree);
  for (const Node* leaf : tree.leaves()) {
    if (leaf->primitive.isBounded()) reach.extend(leaf->primitive.bounds());
  }
  const Aabb solid = tree.bounds();
  if (solid.isBounded()) reach.extend(solid);
  return reach;
}

StandInCube halfSpaceCube(const HalfSpace& h, const Aabb& extent, double edge) {
  const Vec3 c = extent.center();
  // A point of the extent lies within half its diagonal of c: the cube must
  // reach that far beside the plane's nearest point and below the plane by
  // the plane's height above c as well.
  const double above = h.offset - h.normal.dot(c);
  edge = std::max(edge, std::max(0.0, above) + extent.diagonal());
  const Vec3 onPlane = c + above * h.normal;
  return {frameFromAxis(h.normal), onPlane - 0.5 * edge * h.normal, edge};
}

StandInCube surroundingCube(const Aabb& extent, double edge) {
  return {Mat3::Identity(), extent.center(), edge};
}

}  // namespace csgvox
