#pragma once
/// The solid primitives of a csgvox CSG tree, each with an exact signed
/// distance. Convention (FRep): the value f is >= 0 inside the solid, 0 on its
/// surface and < 0 outside; |f| is the Euclidean distance to the surface.
/// The gradient of f therefore points inwards; the outward surface normal is
/// -grad f.

#include <cstddef>
#include <span>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "core/geometry.h"

namespace csgvox {

/// Kind of a primitive, in the order of the PrimitiveShape alternatives.
enum class PrimitiveType { HalfSpace, Box, Cylinder, Cone, Sphere, Torus };

/// The half-space {x : normal·x <= offset}; normal is unit and points outwards.
struct HalfSpace {
  Vec3 normal = Vec3::UnitZ();  ///< unit outward normal
  double offset = 0.0;          ///< plane offset: the boundary is normal·x = offset
};

/// An oriented box.
struct Box {
  Vec3 center = Vec3::Zero();           ///< centre of the box
  Mat3 axes = Mat3::Identity();         ///< columns: the box's unit axes (right-handed)
  Vec3 halfSize = Vec3::Constant(0.5);  ///< half extents along each axis (> 0)
};

/// A bounded (capped) cylinder.
struct Cylinder {
  Vec3 center = Vec3::Zero();  ///< midpoint of the axis segment
  Vec3 axis = Vec3::UnitZ();   ///< unit axis direction
  double radius = 1.0;         ///< > 0
  double height = 1.0;         ///< full length along the axis, > 0
};

/// A cone frustum (a cone when one radius is 0).
struct Cone {
  Vec3 center = Vec3::Zero();  ///< midpoint of the axis segment
  Vec3 axis = Vec3::UnitZ();   ///< unit axis, from the bottom cap to the top cap
  double radiusBottom = 1.0;   ///< radius at center - axis*height/2 (>= 0)
  double radiusTop = 0.5;      ///< radius at center + axis*height/2 (>= 0)
  double height = 1.0;         ///< > 0
};

/// A sphere.
struct Sphere {
  Vec3 center = Vec3::Zero();
  double radius = 1.0;  ///< > 0
};

/// A ring torus around `axis` through `center`.
struct Torus {
  Vec3 center = Vec3::Zero();
  Vec3 axis = Vec3::UnitZ();  ///< unit axis of revolution
  double majorRadius = 1.0;   ///< distance from the axis to the tube centre
  double minorRadius = 0.25;  ///< tube radius, 0 < minor <= major
};

/// One of the primitive shapes.
using PrimitiveShape = std::variant<HalfSpace, Box, Cylinder, Cone, Sphere, Torus>;

/// A solid primitive: a shape with its exact signed distance field.
class Primitive {
 public:
  Primitive() = default;                                         ///< the half-space z <= 0
  Primitive(PrimitiveShape shape) : shape_(std::move(shape)) {}  // NOLINT: implicit by design
  Primitive(HalfSpace s) : shape_(s) {}                          // NOLINT
  Primitive(Box s) : shape_(s) {}                                // NOLINT
  Primitive(Cylinder s) : shape_(s) {}                           // NOLINT
  Primitive(Cone s) : shape_(s) {}                               // NOLINT
  Primitive(Sphere s) : shape_(s) {}                             // NOLINT
  Primitive(Torus s) : shape_(s) {}                              // NOLINT

  PrimitiveType type() const { return static_cast<PrimitiveType>(shape_.index()); }
  const PrimitiveShape& shape() const { return shape_; }
  /// The shape as T, or nullptr when it is another kind.
  template <class T>
  const T* as() const {
    return std::get_if<T>(&shape_);
  }

  /// Signed distance at p: >= 0 inside, < 0 outside.
  double value(const Vec3& p) const;
  /// Signed distance at p and its gradient (unit length almost everywhere).
  /// The value is bit for bit that of value(p).
  double valueAndGradient(const Vec3& p, Vec3& gradient) const;
  /// out[i] = value(points[i]) (bit for bit), one loop over the points.
  /// @throw std::invalid_argument when the spans differ in size.
  void values(std::span<const Vec3> points, std::span<double> out) const;

  /// Tight axis-aligned bounds; unbounded for a half-space.
  Aabb bounds() const;
  /// True for every primitive except the half-space.
  bool isBounded() const { return type() != PrimitiveType::HalfSpace; }
  /// Volume (infinite for a half-space).
  double volume() const;
  /// Surface area (infinite for a half-space).
  double surfaceArea() const;
  /// The directions its shape depends on: a half-space's normal, a box's
  /// three axes, a cylinder's, cone's or torus's axis (none for a sphere).
  std::vector<Vec3> directions() const;

  /// Checks parameters (finite, unit axes, positive sizes).
  /// @throw std::invalid_argument naming the offending parameter.
  void validate() const;

  /// Same type and every parameter within `tolerance` (absolute, in scan
  /// units for lengths, in radians-ish units for unit vectors).
  bool approxEqual(const Primitive& other, double tolerance) const;
  bool operator==(const Primitive& other) const { return approxEqual(other, 0.0); }
  /// A hash of the type and parameters: primitives equal by approxEqual(other,
  /// 0) hash equal (-0 and +0 hash alike).
  std::size_t hash() const;

 private:
  PrimitiveShape shape_;
};

/// Lower-case type name used in files: "halfspace", "box", "cylinder",
/// "cone", "sphere", "torus".
std::string_view primitiveTypeName(PrimitiveType type);
/// Inverse of primitiveTypeName. @throw std::invalid_argument for an unknown name.
PrimitiveType primitiveTypeFromName(std::string_view name);

}  // namespace csgvox
