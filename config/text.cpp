#include <scanplan/config/text.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstddef>
#include <cstdlib>
#include <system_error>

#include <fmt/format.h>

namespace scanplan::config {
namespace {

// Edit distance, for "did you mean" hints on misspelt keys.
std::size_t editDistance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diag = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (a[i - 1] == b[j - 1] ? 0u : 1u)});
      diag = up;
    }
  }
  return row[b.size()];
}

}  // namespace

std::string formatNumber(double v) {
  char buf[64];
  const auto [ptr, ec] = std::to_chars(buf, buf + sizeof buf, v);
  return ec == std::errc() ? std::string(buf, ptr) : fmt::format("{}", v);
}

std::string suggestKey(const std::string& written, const std::vector<std::string>& valid) {
  // The key without its unit (phi for phi_deg, radius for radius_mm) or its plural s (repeat
  // for repeats): the shortest valid key that extends it so.
  std::string best;
  for (const std::string& v : valid) {
    if (written.size() >= 2 && v.size() > written.size() &&
        v.compare(0, written.size(), written) == 0 &&
        (v[written.size()] == '_' || v.size() == written.size() + 1) &&
        (best.empty() || v.size() < best.size())) {
      best = v;
    }
  }
  if (!best.empty()) return best;
  // Otherwise only near misses: a unit suffix (radius_m for radius_mm) or a typo.
  std::size_t best_d = std::max<std::size_t>(3, written.size() / 3) + 1;
  for (const std::string& v : valid) {
    const std::size_t d = editDistance(written, v);
    if (d < best_d) {
      best_d = d;
      best = v;
    }
  }
  return best;
}

std::optional<double> parseFiniteNumber(const std::string& text) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size() || !std::isfinite(v)) return std::nullopt;
  return v;
}

}  // namespace scanplan::config
