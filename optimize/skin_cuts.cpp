#include "optimize/skin_cuts.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

namespace csgvox {
namespace {

// Corners of a solid's bounds: exact support points for a box, conservative
// ones otherwise.
std::vector<Vec3> supportCorners(const CsgTree& solid) {
  std::vector<Vec3> corners;
  const Node& root = *solid.root();
  if (root.kind == NodeKind::Primitive) {
    if (const Box* b = root.primitive.as<Box>()) {
      for (int c = 0; c < 8; ++c) {
        const Vec3 s((c & 1) ? 1 : -1, (c & 2) ? 1 : -1, (c & 4) ? 1 : -1);
        corners.push_back(b->center + b->axes * s.cwiseProduct(b->halfSize));
      }
      return corners;
    }
  }
  const Aabb a = solid.bounds();
  if (!a.isBounded()) return corners;
  for (int c = 0; c < 8; ++c) {
    corners.emplace_back((c & 1) ? a.max.x() : a.min.x(), (c & 2) ? a.max.y() : a.min.y(),
                         (c & 4) ? a.max.z() : a.min.z());
  }
  return corners;
}

// The centre of a face and four points a quarter of the way to its rim,
// along u and v: far enough from the rim that a hole's cap has no scan
// point near them, spread enough that one gap in a scanned wall's sampling
// does not decide.
std::vector<Vec3> innerProbes(const Vec3& centre, const Vec3& u, const Vec3& v) {
  return {centre, centre + 0.25 * u, centre - 0.25 * u, centre + 0.25 * v, centre - 0.25 * v};
}

// How far past `from` along `dir` the solid ends, when it ends within
// `snap` (and holds `from`); -1 otherwise.
double exitWithin(const CsgTree& solid, const Vec3& from, const Vec3& dir, double snap) {
  if (solid.value(from) < 0.0) return -1.0;
  constexpr int kSteps = 16;
  for (int k = 1; k <= kSteps; ++k) {
    const double s = snap * k / kSteps;
    if (solid.value(from + s * dir) < 0.0) return s;
  }
  return -1.0;
}

// The centre of a disc (radius vectors u and v) and eight points at 0.95 of
// its radius.
std::vector<Vec3> discSamples(const Vec3& centre, const Vec3& u, const Vec3& v) {
  std::vector<Vec3> out{centre};
  for (int k = 0; k < 8; ++k) {
    const double a = k * std::numbers::pi / 4.0;
    out.push_back(centre + 0.95 * (std::cos(a) * u + std::sin(a) * v));
  }
  return out;
}

// A 3 x 3 grid over a rectangle (half extents u and v), reaching 0.95 of them.
std::vector<Vec3> rectangleSamples(const Vec3& centre, const Vec3& u, const Vec3& v) {
  std::vector<Vec3> out;
  for (int k = 0; k < 9; ++k) {
    out.push_back(centre + 0.95 * ((k % 3) - 1) * u + 0.95 * ((k / 3) - 1) * v);
  }
  return out;
}

// A subtracted box, cylinder or cone whose end face stops within `snap` of
// where the cut solid ends (along the face's normal) leaves a skin thinner
// than voxels can see: a hole that should go through a shaft stops short of
// its curved surface, and OpenSCAD then renders a closed cavity. Returns how
// far to move the face (centre `face`, outward `dir`, half extents u and v
// across it, `samples` on it): one `snap` past the farthest exit over the
// samples. -1 when the solid does not end within `snap` at every sample, or
// when the skin's outer face holds scan points (a real thin wall).
double pushThrough(const CsgTree& solid, const Vec3& face, const Vec3& dir, const Vec3& u,
                   const Vec3& v, const std::vector<Vec3>& samples, double snap,
                   const ScannedAt& scannedAt) {
  double reach = -1.0;
  for (const Vec3& p : samples) {
    const double e = exitWithin(solid, p, dir, snap);
    if (e < 0.0) return -1.0;
    reach = std::max(reach, e);
  }
  const std::vector<Vec3> probes = innerProbes(face, u, v);
  std::vector<Vec3> outer;
  for (const Vec3& p : probes) {
    const double e = exitWithin(solid, p, dir, snap);
    if (e >= 0.0) outer.push_back(p + e * dir);
  }
  if (2 * outer.size() > probes.size() && mostlyScanned(scannedAt, outer)) return -1.0;
  return reach + snap;
}

}  // namespace

bool mostlyScanned(const ScannedAt& scannedAt, std::span<const Vec3> probes) {
  if (!scannedAt || probes.empty()) return false;
  std::size_t hits = 0;
  for (const Vec3& p : probes) hits += scannedAt(p) ? 1 : 0;
  return 2 * hits > probes.size();
}

CsgTree throughCut(const CsgTree& tool, const CsgTree& root, double snap,
                   const ScannedAt& scannedAt) {
  if (snap <= 0.0 || tool.root()->kind != NodeKind::Primitive) return tool;
  const Box* b = tool.root()->primitive.as<Box>();
  const std::vector<Vec3> corners = supportCorners(root);
  if (!b || corners.empty()) return tool;
  Box grown = *b;
  bool changed = false;
  for (int axis = 0; axis < 3; ++axis) {
    for (double sign : {-1.0, 1.0}) {
      const Vec3 dir = sign * b->axes.col(axis);
      const double face = dir.dot(b->center) + b->halfSize[axis];
      double reach = -1e300;
      for (const Vec3& c : corners) reach = std::max(reach, dir.dot(c));
      if (face <= reach && reach - face <= snap) {
        const int u = (axis + 1) % 3, v = (axis + 2) % 3;
        const Vec3 outer = b->center + (b->halfSize[axis] + reach - face) * dir;
        if (mostlyScanned(scannedAt, innerProbes(outer, b->halfSize[u] * b->axes.col(u),
                                                 b->halfSize[v] * b->axes.col(v)))) {
          continue;
        }
        const double extra = reach - face + 2.0 * snap;
        grown.center += 0.5 * extra * dir;
        grown.halfSize[axis] += 0.5 * extra;
        changed = true;
      }
    }
  }
  return changed ? CsgTree::leaf(grown, tool.root()->name) : tool;
}

CsgTree throughSkin(const CsgTree& tool, const CsgTree& solid, double snap,
                    const ScannedAt& scannedAt) {
  if (snap <= 0.0 || tool.root()->kind != NodeKind::Primitive) return tool;
  const Primitive& prim = tool.root()->primitive;
  bool changed = false;
  if (const Cylinder* c = prim.as<Cylinder>()) {
    const Mat3 frame = frameFromAxis(c->axis);
    const Vec3 u = c->radius * frame.col(0), v = c->radius * frame.col(1);
    Cylinder grown = *c;
    for (const double sign : {-1.0, 1.0}) {
      const Vec3 dir = sign * c->axis;
      const Vec3 face = c->center + 0.5 * c->height * dir;
      const double extra =
          pushThrough(solid, face, dir, u, v, discSamples(face, u, v), snap, scannedAt);
      if (extra < 0.0) continue;
      grown.center += 0.5 * extra * dir;
      grown.height += extra;
      changed = true;
    }
    return changed ? CsgTree::leaf(grown, tool.root()->name) : tool;
  }
  if (const Cone* c = prim.as<Cone>()) {
    const Mat3 frame = frameFromAxis(c->axis);
    const double slope = (c->radiusTop - c->radiusBottom) / c->height;
    Cone grown = *c;
    for (const double sign : {-1.0, 1.0}) {
      const Vec3 dir = sign * c->axis;
      const Vec3 face = c->center + 0.5 * c->height * dir;
      const double radius = sign > 0.0 ? c->radiusTop : c->radiusBottom;
      const Vec3 u = radius * frame.col(0), v = radius * frame.col(1);
      const double extra =
          pushThrough(solid, face, dir, u, v, discSamples(face, u, v), snap, scannedAt);
      if (extra < 0.0) continue;
      // The frustum runs on along its own slope.
      if (sign > 0.0) {
        grown.radiusTop += slope * extra;
      } else {
        grown.radiusBottom = std::max(0.0, grown.radiusBottom - slope * extra);
      }
      grown.center += 0.5 * extra * dir;
      grown.height += extra;
      changed = true;
    }
    return changed ? CsgTree::leaf(grown, tool.root()->name) : tool;
  }
  if (const Box* b = prim.as<Box>()) {
    Box grown = *b;
    for (int axis = 0; axis < 3; ++axis) {
      const Vec3 u = b->halfSize[(axis + 1) % 3] * b->axes.col((axis + 1) % 3);
      const Vec3 v = b->halfSize[(axis + 2) % 3] * b->axes.col((axis + 2) % 3);
      for (const double sign : {-1.0, 1.0}) {
        const Vec3 dir = sign * b->axes.col(axis);
        const Vec3 face = b->center + b->halfSize[axis] * dir;
        const double extra =
            pushThrough(solid, face, dir, u, v, rectangleSamples(face, u, v), snap, scannedAt);
        if (extra < 0.0) continue;
        grown.center += 0.5 * extra * dir;
        grown.halfSize[axis] += 0.5 * extra;
        changed = true;
      }
    }
    return changed ? CsgTree::leaf(grown, tool.root()->name) : tool;
  }
  return tool;
}

}  // namespace csgvox
