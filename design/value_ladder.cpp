#include "design/value_ladder.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <span>

namespace csgvox {
namespace {

constexpr double kInch = 25.4;
constexpr std::array<double, 4> kMillimetreSteps = {1.0, 0.5, 0.1, 0.01};
constexpr std::array<double, 6> kInchSteps = {kInch,     kInch / 2,  kInch / 4,
                                              kInch / 8, kInch / 16, kInch / 32};
constexpr std::array<double, 6> kAngleSteps = {90.0, 45.0, 30.0, 15.0, 5.0, 1.0};

std::span<const double> stepsOf(UnitSystem units) {
  if (units == UnitSystem::Inch) return kInchSteps;
  return kMillimetreSteps;
}

// The multiple of `step` nearest `value`, written so that tenths and
// hundredths are the doubles their decimal text reads as (0.1 * 3 is not 0.3).
double multipleOf(double value, double step) {
  const double k = std::round(value / step);
  if (step < 1.0 && std::abs(1.0 / step - std::round(1.0 / step)) < 1e-12) {
    return k / std::round(1.0 / step);
  }
  return k * step;
}

std::optional<double> onLadder(double value, double uncertainty, std::span<const double> steps) {
  if (!std::isfinite(value)) return std::nullopt;
  if (std::isinf(uncertainty)) return multipleOf(value, steps.front());
  for (double step : steps) {
    // A finer step than twice the uncertainty always has a multiple within
    // it: that would be rounding, not a designed value found.
    if (step != steps.front() && step <= 2.0 * uncertainty) break;
    const double candidate = multipleOf(value, step);
    if (std::abs(candidate - value) <= uncertainty) return candidate == 0.0 ? 0.0 : candidate;
  }
  return std::nullopt;
}

}  // namespace

std::string unitSystemName(UnitSystem units) { return units == UnitSystem::Inch ? "inch" : "mm"; }

std::optional<double> simplestLength(double value, double uncertainty, UnitSystem units) {
  return onLadder(value, uncertainty, stepsOf(units));
}

std::optional<double> simplestAngle(double degrees, double uncertainty) {
  return onLadder(degrees, uncertainty, kAngleSteps);
}

int ladderRung(double value, UnitSystem units) {
  const auto steps = stepsOf(units);
  for (std::size_t i = 0; i < steps.size(); ++i) {
    const double k = value / steps[i];
    if (std::abs(k - std::round(k)) <= 1e-9) return int(i);
  }
  return -1;
}

double ladderStep(int rung, UnitSystem units) {
  const auto steps = stepsOf(units);
  return steps[std::size_t(std::clamp(rung, 0, int(steps.size()) - 1))];
}

std::string inchText(double millimetres) {
  const double k = millimetres / (kInch / 32);
  if (std::abs(k - std::round(k)) > 1e-9) return "";
  long n = std::lround(std::abs(k));
  const long whole = n / 32;
  long num = n % 32, den = 32;
  while (num != 0 && num % 2 == 0) {
    num /= 2;
    den /= 2;
  }
  std::string s = millimetres < 0 ? "-" : "";
  if (whole != 0 || num == 0) s += std::to_string(whole);
  if (num != 0) s += (whole != 0 ? " " : "") + std::to_string(num) + "/" + std::to_string(den);
  return s + " in";
}

}  // namespace csgvox
