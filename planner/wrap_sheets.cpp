#include <scanplan/planner/wrap_sheets.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <scanplan/kinematics/joint_wrap.h>
#include <scanplan/kinematics/ramp.h>
#include <scanplan/kinematics/units.h>

namespace scanplan::planner {

namespace {

// Eq. 7 of one joint.
double jointTerm(const kinematics::RobotModel& robot,
                 const ConstraintSettings& settings,
                 int j,
                 double q) {
  const auto& limits = robot.joint(j);
  return jointLimitFactor(q, limits.min, limits.max,
                          settings.joint_gamma[static_cast<std::size_t>(j)]);
}

}  // namespace

WrapSheets::WrapSheets(const kinematics::CellModel& cell,
                       const ConstraintSettings& settings,
                       const kinematics::ScanPath& path,
                       const ConfigMap& map,
                       std::size_t branch,
                       int joint)
    : map_(&map), branch_(branch), robot_(&cell.robot), settings_(settings), joint_(joint) {
  if (path.samples.size() != map.times.size() || branch >= map.branches.size() || joint < 0 ||
      joint >= kinematics::kNumJoints) {
    throw std::logic_error("WrapSheets: the map was not built on this path");
  }
  const auto& limits = robot_->joint(joint);
  if (!kinematics::turnsMoreThanOnce(limits)) return;
  const std::size_t na = map.angles.size(), nt = map.times.size(), cells = na * nt;
  const kinematics::IkBranch ik_branch = map.branches[branch];

  // The branch's solution in every open cell: the joint in (−π, π], Eq. 7 of the rest with the
  // map's choice (the whole-turn variants are a product of per-joint choices, so the map's
  // farthest variant is each joint's best equivalent).
  value_.assign(cells, std::numeric_limits<double>::quiet_NaN());
  rest_.assign(cells, 0.0);
  tbb::parallel_for(std::size_t{0}, na, [&](std::size_t a) {
    for (std::size_t t = 0; t < nt; ++t) {
      const std::size_t c = a * nt + t;
      if (!(map.f[branch * cells + c] > 0.0f)) continue;
      const auto solutions = robot_->ik(cell.flangeTarget(map.angles[a], path.samples[t].X_PS),
                                        {.within_limits_only = true});
      const auto s = std::find_if(solutions.begin(), solutions.end(),
                                  [&](const auto& x) { return x.branch == ik_branch; });
      if (s == solutions.end()) continue;
      double rest = 1.0;
      for (int j = 0; j < kinematics::kNumJoints; ++j) {
        if (j == joint) continue;
        double best = 0.0;
        for (const double turn : {0.0, -kinematics::kTurn, kinematics::kTurn})
          best = std::max(best, jointTerm(*robot_, settings_, j, s->q(j) + turn));
        rest *= best;
      }
      value_[c] = kinematics::nearestTurn(s->q(joint), 0.0);
      rest_[c] = rest;
    }
  });

  // Windows from min − margin, at most 90° apart, the last ending at max + margin.
  const double first = limits.min - kWrapMargin;
  const double last = limits.max + kWrapMargin - kinematics::kTurn;
  const int steps = static_cast<int>(std::ceil((last - first) / (0.5 * std::numbers::pi)));
  for (int i = 0; i <= steps; ++i) {
    const double lo = steps == 0 ? first : first + (last - first) * i / steps;
    bool everywhere = true;
    for (std::size_t t = 0; t < nt && everywhere; ++t) {
      bool open = false;
      for (std::size_t a = 0; a < na && !open; ++a) open = sheetJoint(a * nt + t, lo) > 0.0;
      everywhere = open;
    }
    if (everywhere) windows_.push_back(lo);
  }
}

double WrapSheets::sheetJoint(std::size_t c, double lo) const {
  if (std::isnan(value_[c])) return 0.0;
  // The equivalent in [lo, lo + 2π), closed within the margin of either edge.
  const double v = kinematics::nearestTurn(value_[c], lo + std::numbers::pi);
  if (v < lo + kWrapMargin || v > lo + kinematics::kTurn - kWrapMargin) return 0.0;
  return rest_[c] * jointTerm(*robot_, settings_, joint_, v);
}

std::string WrapSheets::describe(std::size_t i) const {
  return fmt::format("joint {} in [{:.0f}, {:.0f}) deg", joint_ + 1, toDeg(windows_[i]),
                     toDeg(windows_[i] + kinematics::kTurn));
}

ConfigMap WrapSheets::map(std::size_t i) const {
  const ConfigMap& m = *map_;
  ConfigMap out;
  out.angles = m.angles;
  out.times = m.times;
  out.branches = {m.branches[branch_]};
  const std::size_t cells = m.cellsPerBranch(), base = branch_ * cells;
  const auto layer = [&](const auto& v) {
    return std::vector(v.begin() + static_cast<std::ptrdiff_t>(base),
                       v.begin() + static_cast<std::ptrdiff_t>(base + cells));
  };
  out.f = layer(m.f);
  out.joint = layer(m.joint);
  out.singularity = layer(m.singularity);
  out.clearance = layer(m.clearance);
  out.limit = layer(m.limit);
  for (std::size_t c = 0; c < cells; ++c) {
    if (!(out.f[c] > 0.0f)) continue;
    const double joint = sheetJoint(c, windows_[i]);
    // f' = f · J'/J (Eq. 6: the other factors do not change with whole turns).
    out.f[c] = static_cast<float>(static_cast<double>(out.f[c]) * joint /
                                  static_cast<double>(out.joint[c]));
    out.joint[c] = static_cast<float>(joint);
    const float lowest = std::min({out.joint[c], out.singularity[c], out.clearance[c]});
    if (lowest < 1.0f && out.joint[c] == lowest) {
      out.limit[c] = static_cast<std::uint8_t>(Limit::kJointLimit);
    }
  }
  return out;
}

}  // namespace scanplan::planner
