#include "core/set_operations.h"

#include <cmath>

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

}  // namespace

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
  }
  return minMaxOperations();
}

}  // namespace csgvox
