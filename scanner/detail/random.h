#pragma once
// Private to scanner/ (detail/ is not installed): the seeded noise both simulation modes draw.

#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <utility>

namespace scanplan::scanner::detail {

// SplitMix64 (Steele et al.): decorrelates the per-profile noise seeds.
inline std::uint64_t mix(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

// Uniform in (0, 1) from 53 random bits; std::normal_distribution is not specified across
// standard libraries, this is, so a seed gives the same cloud everywhere.
inline double uniformOpen(std::mt19937_64& rng) {
  return (static_cast<double>(rng() >> 11) + 0.5) * 0x1.0p-53;
}

// Two independent standard normal deviates (Box–Muller).
inline std::pair<double, double> gaussianPair(std::mt19937_64& rng) {
  const double r = std::sqrt(-2.0 * std::log(uniformOpen(rng)));
  const double a = 2.0 * std::numbers::pi * uniformOpen(rng);
  return {r * std::cos(a), r * std::sin(a)};
}

}  // namespace scanplan::scanner::detail
