// summary.md of a batch: the statuses, the means per setting, the cases without a plan and the
// figures.
#include <map>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "cli/batch/batch_internal.h"

namespace scanplan::cli::detail {

namespace {

// A setting: the job and the varied values except seeds (runs of a setting differ by seed and
// repeat only).
std::string settingOf(const BatchRow& row, const std::vector<std::string>& keys) {
  std::string text = row.job;
  for (const std::string& k : keys) {
    if (!isSeedKey(k)) text += " " + k + "=" + paramValue(row, k);
  }
  return text;
}

}  // namespace

std::string summaryMarkdown(const std::vector<BatchRow>& rows,
                            const std::vector<std::string>& keys,
                            const std::vector<std::string>& figures) {
  std::map<std::string, int> statuses;
  for (const BatchRow& r : rows) ++statuses[r.status];
  std::string md = "# scanplan batch summary\n\n";
  md += fmt::format("{} case(s):", rows.size());
  for (const auto& [s, n] : statuses) md += fmt::format(" {} {},", n, s);
  md.back() = '\n';
  md +=
      "\nMeans per setting (over seeds and repeats; J and its gap over planned cases only). Plan "
      "is the planner's own time, DP the DP yardstick's on top of it (none when the planner is "
      "DP).\n\n";
  md += "| job |";
  std::vector<std::string> shown;
  for (const std::string& k : keys) {
    if (!isSeedKey(k)) shown.push_back(k);
  }
  for (const std::string& k : shown) md += " " + k + " |";
  md +=
      " cases | planned | J (s) | DP gap (%) | min f | cycle (s) | coverage | plan (s) | DP (s) | "
      "map (s) |\n|---|";
  for (std::size_t i = 0; i < shown.size(); ++i) md += "---|";
  md += "---|---|---|---|---|---|---|---|---|---|\n";
  std::vector<std::string> order;
  std::map<std::string, std::vector<const BatchRow*>> groups;
  for (const BatchRow& r : rows) {
    const std::string s = settingOf(r, keys);
    if (!groups.count(s)) order.push_back(s);
    groups[s].push_back(&r);
  }
  for (const std::string& s : order) {
    const auto& group = groups[s];
    Mean j, gap, minf, cycle, coverage, plan, dp, map;
    int planned = 0;
    for (const BatchRow* r : group) {
      planned += r->status == "planned" ? 1 : 0;
      j.add(r->metrics[kJ]);
      gap.add(r->metrics[kGap]);
      minf.add(r->metrics[kMinF]);
      cycle.add(r->metrics[kCycle]);
      coverage.add(r->metrics[kCoverage]);
      plan.add(r->metrics[kPlanS]);
      dp.add(r->metrics[kDpS]);
      map.add(r->metrics[kMapS]);
    }
    md += "| " + group.front()->job + " |";
    for (const std::string& k : shown) md += " " + paramValue(*group.front(), k) + " |";
    md += fmt::format(" {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |\n", group.size(), planned,
                      j.text(), gap.text("{:.2f}"), minf.text(), cycle.text(), coverage.text(),
                      plan.text("{:.3f}"), dp.text("{:.3f}"), map.text("{:.2f}"));
  }
  const std::vector<const BatchRow*> failed = [&] {
    std::vector<const BatchRow*> out;
    for (const BatchRow& r : rows) {
      if (r.status != "planned") out.push_back(&r);
    }
    return out;
  }();
  if (!failed.empty()) {
    md += "\nCases without a plan:\n\n";
    for (const BatchRow* r : failed) {
      md += fmt::format("- `{}` {}: {}\n", r->case_id, r->status, r->reason);
    }
  }
  if (!figures.empty()) {
    md += "\nFigures (each metric against each varied value, one colour per planner):\n\n";
    for (const std::string& f : figures) md += fmt::format("- [{0}](plots/{0}.svg)\n", f);
  }
  return md;
}

}  // namespace scanplan::cli::detail
