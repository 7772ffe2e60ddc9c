#pragma once
/// Designed values: the simplest number within a value's uncertainty, on a
/// ladder from coarse to fine — whole units, halves, tenths, hundredths of
/// a millimetre-like unit, or 1, 1/2, ... 1/32 inch; angles to 90°, 45°,
/// 30°, 15°, 5°, 1°.

#include <optional>
#include <string>

namespace csgvox {

/// Which grid lengths are designed on.
enum class UnitSystem {
  Millimetre,  ///< the scan's unit: whole units, halves, tenths, hundredths
  Inch         ///< the scan is in millimetres, values are fractions of an inch (25.4)
};

/// "mm" or "inch".
std::string unitSystemName(UnitSystem units);

/// The simplest length within [value − uncertainty, value + uncertainty]:
/// the multiple of the coarsest step of the ladder that lies in it (nearest
/// to `value`), or nothing when not even the finest step does. An infinite
/// uncertainty gives the nearest whole unit.
std::optional<double> simplestLength(double value, double uncertainty, UnitSystem units);

/// The simplest angle (degrees) within [value − uncertainty, value +
/// uncertainty] on the ladder 90, 45, 30, 15, 5, 1°, or nothing.
std::optional<double> simplestAngle(double degrees, double uncertainty);

/// How coarse the step is that `value` lies on (exactly, to 1e-9 of a
/// step): 0 for whole units (or 1 inch), higher for finer steps, -1 when on
/// none.
int ladderRung(double value, UnitSystem units);

/// The step of rung `rung` (as ladderRung() gives it), scan units.
double ladderStep(int rung, UnitSystem units);

/// A length of the inch grid as text, e.g. "1 1/4 in" for 31.75; empty when
/// it is not on the 1/32 inch grid.
std::string inchText(double millimetres);

}  // namespace csgvox
