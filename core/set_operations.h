#pragma once
/// Pluggable implementations of the FRep set operations. Every implementation
/// keeps the same zero set (the same CSG solid); they differ in the field away
/// from the surface (min/max is exact where one operand dominates, R-functions
/// are smooth, SARDF is a C1 blend of min/max with bounded error).

#include "core/geometry.h"

#include <string_view>

namespace csgvox {

/// A field value with its gradient.
struct FieldValue {
  double f = 0.0;
  Vec3 gradient = Vec3::Zero();
};

/// Which implementation of the set operations to use.
enum class SetOperationKind { MinMax, RFunction };

/// The binary set operations on FRep values (f >= 0 inside). Complement is
/// always -f and difference is a ∩ ¬b.
class SetOperations {
 public:
  virtual ~SetOperations() = default;
  virtual FieldValue intersect(const FieldValue& a, const FieldValue& b) const = 0;
  virtual FieldValue unite(const FieldValue& a, const FieldValue& b) const = 0;
  virtual std::string_view name() const = 0;
};

/// min/max: ∩ = min, ∪ = max.
const SetOperations& minMaxOperations();
/// R-functions (R0 system): f1 + f2 ∓ sqrt(f1² + f2²).
const SetOperations& rFunctionOperations();
/// The implementation of a kind.
const SetOperations& setOperations(SetOperationKind kind);

}  // namespace csgvox
