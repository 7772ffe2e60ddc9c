#pragma once
/// A designed value as written in the outputs: a sum of parameters with
/// small coefficients ("z1 - z0", "(x0 + x1) / 2"), never a bare number.

#include <span>
#include <string>
#include <utility>
#include <vector>

namespace csgvox {

struct DesignParameter;

/// A linear combination of parameters.
struct Expression {
  std::vector<std::pair<double, int>> terms;  ///< (coefficient, index into the parameters)

  /// The expression of one parameter.
  static Expression of(int parameter) { return Expression{{{1.0, parameter}}}; }
  /// True when the expression has no term (it stands for 0).
  bool empty() const { return terms.empty(); }
  /// Its value with the parameters' designed values.
  double value(std::span<const DesignParameter> parameters) const;
  /// Its text with the parameters' names, e.g. "hub_z1 - plate_z0"; "0" when empty.
  std::string text(std::span<const DesignParameter> parameters) const;
  /// Its text with each parameter's name passed through `nameOf` (e.g. a
  /// spreadsheet alias "Parameters.hub_z1").
  template <class NameOf>
  std::string textWith(const NameOf& nameOf) const;
};

/// The text of the sum of `terms`, names from `names`.
std::string expressionText(const std::vector<std::pair<double, int>>& terms,
                           const std::vector<std::string>& names);

template <class NameOf>
std::string Expression::textWith(const NameOf& nameOf) const {
  std::vector<std::string> names;
  std::vector<std::pair<double, int>> renumbered;
  for (const auto& [c, p] : terms) {
    renumbered.emplace_back(c, int(names.size()));
    names.push_back(nameOf(p));
  }
  return expressionText(renumbered, names);
}

}  // namespace csgvox
