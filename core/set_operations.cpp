#include "core/set_operations.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace csgvox {
namespace {

class MinMax final : public SetOperations {
 public:
  FieldValue intersect(const FieldValue& a, const FieldValue& b) const override {
    return b.f < a.f ? b : a;
  }
  FieldValue unite(const FieldValue& a, const FieldValue& b) const override {
    return b.f > a.f ? b : a;
  }
  std::string_view name() const override { return "minmax"; }
  SetOperationKind kind() const override { return SetOperationKind::MinMax; }
};

class RFunction final : public SetOperations {
 public:
  FieldValue intersect(const FieldValue& a, const FieldValue& b) const override {
    return combine(a, b, -1.0);
  }
  FieldValue unite(const FieldValue& a, const FieldValue& b) const override {
    return combine(a, b, 1.0);
  }
  std::string_view name() const override { return "rfunction"; }
  SetOperationKind kind() const override { return SetOperationKind::RFunction; }

 private:
  static FieldValue combine(const FieldValue& a, const FieldValue& b, double sign) {
    const double r = std::hypot(a.f, b.f);
    FieldValue out;
    out.f = a.f + b.f + sign * r;
    if (r > 0.0) {
      out.gradient = a.gradient * (1.0 + sign * a.f / r) + b.gradient * (1.0 + sign * b.f / r);
    } else {
      out.gradient = 0.5 * (a.gradient + b.gradient);
    }
    return out;
  }
};

FieldValue fromSardf(const SardfResult& r, const FieldValue& a, const FieldValue& b) {
  FieldValue out;
  out.f = r.f;
  out.gradient = r.d1 * a.gradient + r.d2 * b.gradient;
  return out;
}

}  // namespace

SardfOperations::SardfOperations(double radius) : radius_(radius) {
  if (!(std::isfinite(radius) && radius > 0.0)) {
    throw std::invalid_argument("SARDF radius must be finite and > 0, got " +
                                std::to_string(radius));
  }
}

FieldValue SardfOperations::intersect(const FieldValue& a, const FieldValue& b) const {
  return fromSardf(sardfIntersect(a.f, b.f, radius_), a, b);
}

FieldValue SardfOperations::unite(const FieldValue& a, const FieldValue& b) const {
  return fromSardf(sardfUnite(a.f, b.f, radius_), a, b);
}

const SetOperations& minMaxOperations() {
  static const MinMax ops;
  return ops;
}

const SetOperations& rFunctionOperations() {
  static const RFunction ops;
  return ops;
}

const SetOperations& setOperations(SetOperationKind kind) {
  switch (kind) {
    case SetOperationKind::MinMax:
      return minMaxOperations();
    case SetOperationKind::RFunction:
      return rFunctionOperations();
    case SetOperationKind::Sardf:
      break;
  }
  throw std::invalid_argument("setOperations: SARDF needs a radius (use SardfOperations)");
}

}  // namespace csgvox
