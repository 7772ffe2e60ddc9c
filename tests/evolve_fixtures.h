#pragma once
/// Shared inputs of the evolve tests: oriented points on a box's faces and
/// the box's six face planes as a primitive library.

#include <cstddef>
#include <string>
#include <vector>

#include "core/csg_tree.h"
#include "evolve/primitive_library.h"

namespace csgvox::test {

/// Points on the faces of [-1, 1]³ (a k×k grid per face, away from the
/// edges) with outward normals.
struct OrientedPoints {
  std::vector<Vec3> points;
  std::vector<Vec3> normals;
};

inline OrientedPoints cubeFacePoints(int k) {
  OrientedPoints out;
  for (int axis = 0; axis < 3; ++axis) {
    for (const double side : {-1.0, 1.0}) {
      for (int a = 0; a < k; ++a) {
        for (int b = 0; b < k; ++b) {
          Vec3 p;
          p[axis] = side;
          p[(axis + 1) % 3] = -1.0 + (a + 0.5) * 2.0 / k;
          p[(axis + 2) % 3] = -1.0 + (b + 0.5) * 2.0 / k;
          Vec3 n = Vec3::Zero();
          n[axis] = side;
          out.points.push_back(p);
          out.normals.push_back(n);
        }
      }
    }
  }
  return out;
}

/// The six face half-spaces of [-1, 1]³, named plane0..plane5, plus `extra`.
inline PrimitiveLibrary cubePlanes(std::vector<Primitive> extra = {}) {
  std::vector<Primitive> primitives;
  std::vector<std::string> names;
  for (int axis = 0; axis < 3; ++axis) {
    for (const double side : {-1.0, 1.0}) {
      Vec3 n = Vec3::Zero();
      n[axis] = side;
      primitives.push_back(HalfSpace{n, 1.0});
      names.push_back("plane" + std::to_string(names.size()));
    }
  }
  for (Primitive& p : extra) {
    primitives.push_back(std::move(p));
    names.push_back("extra" + std::to_string(names.size()));
  }
  return PrimitiveLibrary(std::move(primitives), std::move(names));
}

/// The intersection of the library's first six leaves: the cube.
inline CsgTree cubeTree(const PrimitiveLibrary& library) {
  std::vector<CsgTree> faces;
  for (std::size_t i = 0; i < 6; ++i) faces.push_back(library.leafTree(i));
  return CsgTree::intersect(faces);
}

}  // namespace csgvox::test
