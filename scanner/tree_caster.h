#pragma once
/// Rays cast exactly at a CSG tree's surface: sphere tracing on the tree's
/// min/max field, then bisection on the sign change.

#include <memory>

#include "core/csg_tree.h"
#include "scanner/ray_caster.h"

namespace csgvox {

class TreeProgram;

/// Options of TreeCaster.
struct TreeCasterOptions {
  double minStep = 1e-5;    ///< smallest march step, fraction of the tree's bounds diagonal D
  double tolerance = 1e-9;  ///< bisection stops at this interval, fraction of D
  int maxSteps = 4096;      ///< march steps per ray before it counts as a miss
};

/// A RayCaster on the boundary of a bounded CSG tree, evaluated with min/max
/// (the field every csgvox file means). Every primitive's value is its exact
/// signed distance and min/max keep the field 1-Lipschitz, so |f| is never
/// more than the distance to the surface: a step of |f| cannot jump over it.
/// The march steps max(|f|, minStep) (only features thinner than minStep
/// can be stepped over) and bisects the first step whose end is inside; the
/// hit lies within `tolerance` of the surface along the ray. The normal is
/// -grad f there (the face whose distance decides the field).
class TreeCaster final : public RayCaster {
 public:
  /// @throw std::invalid_argument if the tree is empty or unbounded.
  explicit TreeCaster(const CsgTree& tree, const TreeCasterOptions& options = {});
  ~TreeCaster() override;
  TreeCaster(const TreeCaster&) = delete;
  TreeCaster& operator=(const TreeCaster&) = delete;

  Aabb bounds() const override { return bounds_; }
  std::optional<RayHit> firstHit(const Vec3& origin, const Vec3& direction,
                                 double maxDistance) const override;

 private:
  std::unique_ptr<const TreeProgram> program_;
  Aabb bounds_;
  double minStep_ = 0.0;    // scan units
  double tolerance_ = 0.0;  // scan units
  int maxSteps_ = 0;
};

}  // namespace csgvox
