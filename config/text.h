#pragma once
// Text helpers of the job and robot files that need no YAML: number text and "did you mean"
// hints. Shared by the readers, the writers and the command line.

#include <optional>
#include <string>
#include <vector>

namespace scanplan::config {

/// Shortest round-trip decimal text of a number ("250", "0.1", "-1e-05").
std::string formatNumber(double v);

/// The number `text` holds, whole and finite ("12.5", "-3e2"); none for "", "12x", "nan", "1e999".
std::optional<double> parseFiniteNumber(const std::string& text);

/// The key of `valid` that `written` most likely means, or "" when none is close: the same key
/// with its unit or plural ending (phi → phi_deg, radius → radius_mm, repeat → repeats), else
/// the nearest by edit distance (radius_m → radius_mm, hieght_mm → height_mm).
std::string suggestKey(const std::string& written, const std::vector<std::string>& valid);

}  // namespace scanplan::config
