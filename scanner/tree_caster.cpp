#include "scanner/tree_caster.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/tree_program.h"

namespace csgvox {

TreeCaster::TreeCaster(const CsgTree& tree, const TreeCasterOptions& options) {
  if (tree.empty()) throw std::invalid_argument("cannot scan an empty tree");
  bounds_ = tree.bounds();
  if (!bounds_.isBounded() || bounds_.isEmpty()) {
    throw std::invalid_argument("cannot scan an unbounded tree");
  }
  program_ = std::make_unique<const TreeProgram>(tree);
  const double d = bounds_.diagonal();
  minStep_ = options.minStep * d;
  tolerance_ = options.tolerance * d;
  maxSteps_ = options.maxSteps;
}

TreeCaster::~TreeCaster() = default;

std::optional<RayHit> TreeCaster::firstHit(const Vec3& origin, const Vec3& direction,
                                           double maxDistance) const {
  // March only where the solid can be: its bounds, grown so that the march
  // starts outside.
  const auto span = rayBoxInterval(bounds_.grown(4.0 * minStep_ + tolerance_), origin, direction,
                                   maxDistance);
  if (!span) return std::nullopt;
  double t = span->first;
  double f = program_->value(origin + t * direction);
  if (f >= 0.0 && t == 0.0) return std::nullopt;  // the origin is inside: not a ray from outside
  double inside = f >= 0.0 ? t : -1.0;           // a parameter where f >= 0, once found
  for (int step = 0; step < maxSteps_ && inside < 0.0; ++step) {
    const double next = t + std::max(-f, minStep_);
    if (next > span->second) return std::nullopt;
    const double fn = program_->value(origin + next * direction);
    if (fn >= 0.0) {
      inside = next;
    } else {
      t = next;
      f = fn;
    }
  }
  if (inside < 0.0) return std::nullopt;  // out of steps: a ray grazing the surface
  // Bisection: f(t) < 0 <= f(inside).
  double lo = f < 0.0 ? t : inside, hi = inside;
  while (hi - lo > tolerance_) {
    const double mid = 0.5 * (lo + hi);
    if (program_->value(origin + mid * direction) >= 0.0) {
      hi = mid;
    } else {
      lo = mid;
    }
  }
  RayHit hit;
  hit.distance = 0.5 * (lo + hi);
  const FieldValue fv = program_->evaluate(origin + hit.distance * direction);
  const double length = fv.gradient.norm();
  hit.normal = length > 0.0 ? Vec3(-fv.gradient / length) : Vec3(-direction);
  return hit;
}

}  // namespace csgvox
