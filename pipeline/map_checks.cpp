#include <scanplan/pipeline/map_checks.h>

#include <algorithm>
#include <array>
#include <vector>

#include <fmt/format.h>

namespace scanplan::pipeline {

std::optional<std::size_t> blockedColumn(const planner::ConfigMap& map, std::size_t branch) {
  for (std::size_t k = 0; k < map.times.size(); ++k) {
    bool open = false;
    for (std::size_t a = 0; a < map.angles.size() && !open; ++a) {
      open = map.f[map.index(branch, a, k)] > 0.0f;
    }
    if (!open) return k;
  }
  return std::nullopt;
}

std::string columnLimits(const planner::ConfigMap& map, std::size_t branch, std::size_t k) {
  std::array<std::size_t, planner::kLimitCount> count{};
  for (std::size_t a = 0; a < map.angles.size(); ++a) ++count[map.limit[map.index(branch, a, k)]];
  std::vector<int> order(planner::kLimitCount);
  for (int i = 0; i < planner::kLimitCount; ++i) order[static_cast<std::size_t>(i)] = i;
  std::stable_sort(order.begin(), order.end(), [&](int x, int y) {
    return count[static_cast<std::size_t>(x)] > count[static_cast<std::size_t>(y)];
  });
  std::string text;
  for (const int i : order) {
    const std::size_t n = count[static_cast<std::size_t>(i)];
    if (n == 0) continue;
    text += fmt::format("{}{} at {:.0f}% of the angles", text.empty() ? "" : ", ",
                        planner::limitName(static_cast<planner::Limit>(i)),
                        100.0 * static_cast<double>(n) / static_cast<double>(map.angles.size()));
  }
  return text;
}

}  // namespace scanplan::pipeline
