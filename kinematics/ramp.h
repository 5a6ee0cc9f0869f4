#pragma once

#include <cmath>
#include <numbers>

namespace scanplan {

/// The constraint ramp of Eq. 8, made monotone (docs/design.md §4): 0 below `low`, 1 at and above
/// `high`, sin(π/2 · (x − low)/(high − low))^γ between. The seed's literal sin(π·…) would fall
/// back to 0 at `high`, contradicting "fully satisfied above high". Requires low < high, γ > 0.
inline double rampFactor(double x, double low, double high, double gamma) noexcept {
  if (!(x >= low)) return 0.0;  // also NaN
  if (x >= high) return 1.0;
  const double s = std::sin(0.5 * std::numbers::pi * (x - low) / (high - low));
  return gamma == 1.0 ? s : std::pow(s, gamma);
}

/// Joint-limit factor of Eq. 7: sin(π · (q − min)/(max − min))^γ, 0 outside the limits.
inline double jointLimitFactor(double q, double min, double max, double gamma) noexcept {
  if (!(q > min && q < max)) return 0.0;
  const double s = std::sin(std::numbers::pi * (q - min) / (max - min));
  return gamma == 1.0 ? s : std::pow(s, gamma);
}

}  // namespace scanplan
