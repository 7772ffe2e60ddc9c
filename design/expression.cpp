#include "design/expression.h"

#include <cmath>

#include "core/decimal.h"
#include "design/designed_tree.h"

namespace csgvox {

double Expression::value(std::span<const DesignParameter> parameters) const {
  double sum = 0.0;
  for (const auto& [c, p] : terms) sum += c * parameters[std::size_t(p)].value;
  return sum;
}

std::string Expression::text(std::span<const DesignParameter> parameters) const {
  return textWith([&](int p) { return parameters[std::size_t(p)].name; });
}

std::string expressionText(const std::vector<std::pair<double, int>>& terms,
                           const std::vector<std::string>& names) {
  if (terms.empty()) return "0";
  bool halves = terms.size() > 1;
  for (const auto& t : terms) halves = halves && std::abs(std::abs(t.first) - 0.5) < 1e-15;
  std::string s;
  for (std::size_t i = 0; i < terms.size(); ++i) {
    double c = halves ? 2.0 * terms[i].first : terms[i].first;
    const std::string& name = names[std::size_t(terms[i].second)];
    if (i == 0) {
      if (c < 0) s += "-";
    } else {
      s += c < 0 ? " - " : " + ";
    }
    c = std::abs(c);
    if (c != 1.0) s += toDecimal(c) + " * ";
    s += name;
  }
  return halves ? "(" + s + ") / 2" : s;
}

}  // namespace csgvox
