#pragma once

#include <numbers>

namespace scanplan {

/// Unit conversions: SI inside the libraries, mm and degrees at the boundary (docs/design.md §2).
inline constexpr double kMmToM = 1e-3;
inline constexpr double kMToMm = 1e3;
inline constexpr double kDegToRad = std::numbers::pi / 180.0;
inline constexpr double kRadToDeg = 180.0 / std::numbers::pi;

constexpr double mm(double v) { return v * kMmToM; }
constexpr double deg(double v) { return v * kDegToRad; }
constexpr double toMm(double metres) { return metres * kMToMm; }
constexpr double toDeg(double radians) { return radians * kRadToDeg; }

}  // namespace scanplan
