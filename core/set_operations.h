#pragma once
/// Pluggable implementations of the FRep set operations. Every implementation
/// keeps the same zero set (the same CSG solid); they differ in the field away
/// from the surface (min/max is exact where one operand dominates, R-functions
/// are smooth, SARDF is min/max with its corners rounded within a radius, see
/// core/sardf.h). Value-only forms (MinMaxValues, RFunctionValues,
/// SardfValues) give the same values as the implementations, bit for bit,
/// without gradients.

#include <array>
#include <cmath>
#include <string_view>

#include "core/geometry.h"
#include "core/named_values.h"
#include "core/sardf.h"

namespace csgvox {

/// A field value with its gradient.
struct FieldValue {
  double f = 0.0;
  Vec3 gradient = Vec3::Zero();
};

/// Which implementation of the set operations to use. Sardf also needs a
/// radius: it is always a SardfOperations object.
enum class SetOperationKind { MinMax, RFunction, Sardf };

/// The names users give the set operations ("minmax", "rfunction", "sardf").
inline constexpr std::array<NamedValue<SetOperationKind>, 3> kSetOperationNames = {{
    {"minmax", SetOperationKind::MinMax},
    {"rfunction", SetOperationKind::RFunction},
    {"sardf", SetOperationKind::Sardf},
}};

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

/// SARDF on values only, for one radius: the f of SardfOperations.
struct SardfValues {
  double radius = 1.0;  ///< blending radius R (length unit of the values)
  double intersect(double a, double b) const { return sardfIntersectValue(a, b, radius); }
  double unite(double a, double b) const { return sardfUniteValue(a, b, radius); }
};

/// SARDF set operations with a fixed blending radius (core/sardf.h); the
/// gradient is ∂f/∂f1·∇a + ∂f/∂f2·∇b. Holds only its radius: cheap to create
/// per part or per tree, and safe to share between threads.
class SardfOperations final : public SetOperations {
 public:
  /// @throw std::invalid_argument unless `radius` is finite and > 0.
  explicit SardfOperations(double radius);
  FieldValue intersect(const FieldValue& a, const FieldValue& b) const override;
  FieldValue unite(const FieldValue& a, const FieldValue& b) const override;
  std::string_view name() const override { return "sardf"; }
  SetOperationKind kind() const override { return SetOperationKind::Sardf; }
  /// The blending radius R.
  double radius() const { return radius_; }
  /// The value-only form with this radius.
  SardfValues values() const { return SardfValues{radius_}; }

 private:
  double radius_;
};

/// min/max: ∩ = min, ∪ = max.
const SetOperations& minMaxOperations();
/// R-functions (R0 system): f1 + f2 ∓ sqrt(f1² + f2²).
const SetOperations& rFunctionOperations();
/// The implementation of a kind that needs no parameter (MinMax, RFunction).
/// @throw std::invalid_argument for Sardf, which needs a radius: construct a
///        SardfOperations instead.
const SetOperations& setOperations(SetOperationKind kind);

}  // namespace csgvox
