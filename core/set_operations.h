#pragma once
/// Pluggable implementations of the FRep set operations. Every implementation
/// keeps the same zero set (the same CSG solid); they differ in the field away
/// from the surface (min/max is exact where one operand dominates, R-functions
/// are smooth). Value-only forms (MinMaxValues, RFunctionValues) give the same
/// values as the implementations, bit for bit, without gradients.

#include <cmath>
#include <string_view>

#include "core/geometry.h"

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
  /// Which implementation this is (value-only paths switch on it once).
  virtual SetOperationKind kind() const = 0;
};

/// min/max on values only: the f of the MinMax implementation.
struct MinMaxValues {
  static double intersect(double a, double b) { return b < a ? b : a; }
  static double unite(double a, double b) { return b > a ? b : a; }
};

/// R-functions on values only: the f of the RFunction implementation.
struct RFunctionValues {
  static double intersect(double a, double b) { return a + b + -1.0 * std::hypot(a, b); }
  static double unite(double a, double b) { return a + b + 1.0 * std::hypot(a, b); }
};

/// min/max: ∩ = min, ∪ = max.
const SetOperations& minMaxOperations();
/// R-functions (R0 system): f1 + f2 ∓ sqrt(f1² + f2²).
const SetOperations& rFunctionOperations();
/// The implementation of a kind.
const SetOperations& setOperations(SetOperationKind kind);

}  // namespace csgvox
