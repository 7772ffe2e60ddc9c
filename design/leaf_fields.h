#pragma once
/// The values of one designed leaf, inside design/ (designed_tree.cpp): how
/// a primitive in the part's frame is written (its LeafForm), which values
/// place it (its fields: faces, caps, axis lines, radii, angles) and which
/// scan points hold each of them.

#include <string>
#include <vector>

#include "design/designed_tree.h"

namespace csgvox {

/// What a value measures, for grouping: close values of one category are one
/// parameter.
enum class ValueCategory { PositionX, PositionY, PositionZ, Radius, Step, Angle, Count };

/// A position along frame axis `axis` (0, 1, 2).
inline ValueCategory positionAlong(int axis) { return ValueCategory(axis); }

/// A value of a leaf: the expression to fill and its fitted value.
struct LeafField {
  Expression* expression = nullptr;              ///< the leaf's expression it fills
  ValueCategory category = ValueCategory::Step;  ///< what it measures
  std::string name;            ///< "x0", "r", ... (a parameter's name ends with it)
  double value = 0.0;          ///< fitted value
  bool crossPosition = false;  ///< a position across z that a circular pattern sets
  int positionAxis = -1;       ///< a position along this frame axis (rows move it), else -1
};

/// Sets the leaf's type, frame-coordinate primitive and form: aligned when
/// its directions lie within `tolerance` radians of the frame's axes.
void classifyLeaf(DesignedLeaf& leaf, const Primitive& primitive, double tolerance);

/// The fields of a classified leaf, with their fitted values.
std::vector<LeafField> leafFields(DesignedLeaf& leaf);

/// Points holding each field of `fields` (as leafFields() gives them), from
/// the frame-coordinate field gradients of the points on the leaf: a
/// box's points hold the face they lie on, a cylinder's or cone's a cap or
/// the axis line and radii, a torus's or sphere's all of them.
std::vector<double> fieldSupport(const DesignedLeaf& leaf, const std::vector<LeafField>& fields,
                                 const std::vector<Vec3>& gradients);

/// For each field of `fields`, how far each point near the leaf would move
/// it onto itself (the point's coordinate less a face's or cap's position,
/// its distance from a cylinder's axis less the radius); empty for the
/// other fields. `points` and `gradients` are the leaf's, in frame
/// coordinates.
std::vector<std::vector<double>> fieldOffsets(const DesignedLeaf& leaf,
                                              const std::vector<LeafField>& fields,
                                              const std::vector<Vec3>& points,
                                              const std::vector<Vec3>& gradients);

/// How near its apex a cone's narrow cap must be to run on to it.
struct ApexReach {
  double radius = 0.0;  ///< the cap's radius at most (scan units)
  double length = 0.0;  ///< the tip it adds at most, along the axis (scan units)
};

/// A cone's cap that no point holds slides along the cone to the nearest
/// whole unit along its axis, its radius following the slope (so that its
/// numbers become those the cone was drawn with); its narrow cap runs on to
/// the apex when within `reach` of it (a tip the fit cut short).
void slideFreeConeCaps(const DesignedLeaf& leaf, std::vector<LeafField>& fields,
                       const std::vector<double>& support, const ApexReach& reach);

}  // namespace csgvox
