// Universal Robots URScript: movej to the start, then servoj at the controller's period; the file
// defines the program and then calls it. Current function names (set_standard_digital_out,
// set_target_payload: UR's script manual marks set_digital_out and set_payload deprecated).
#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "cli/programs/detail/program_text.h"
#include "kinematics/error.h"
#include "kinematics/units.h"

namespace scanplan::cli::detail {

namespace {

using kinematics::JointVector;
using kinematics::kNumJoints;
using kinematics::TrajectorySample;

// servoj's smoothing: the shortest look-ahead URScript allows tracks the path closest; the gain
// is URScript's default.
constexpr double kLookahead = 0.03;  // s
constexpr int kGain = 300;
// One program line per step (about 90 bytes): 2 M steps, 4.4 h at 8 ms, are 180 MB of script.
constexpr std::size_t kMaxServoSteps = 2'000'000;

std::string radians(const JointVector& q) {
  std::string s;
  for (int j = 0; j < kNumJoints; ++j) s += (j ? ", " : "") + fixed(q(j), kRadDecimals);
  return s;
}

std::string setOut(const ProgramContext& c, bool level) {
  return fmt::format("  set_standard_digital_out({}, {})\n", c.options.trigger.output,
                     level ? "True" : "False");
}

Header urHeader(const ProgramContext& c, double approach_v) {
  const ProgramOptions& o = c.options;
  Header header(c, "servoj cannot keep the path");
  header.add("Units: joints in radians, lengths in m, table angles in degrees, times in s.");
  header.add("Timing: movej goes to the start at v = " + fixed(approach_v, 3) +
             " rad/s. Then servo() streams the");
  header.add(fmt::format("  joint-linear path between the samples every {} s (servoj, t = the",
                         fixed(o.servo_period, 4)));
  header.add(fmt::format("  controller period; lookahead_time {}, gain {}): one continuous motion,",
                         fixed(kLookahead, 2), kGain));
  header.add("  the last step reaching the last sample within one period of its time.");
  header.add("Tool: set_tcp, the scanner's laser frame on the flange (rotation vector).");
  header.add(payloadLines(o, "set_target_payload."));
  header.add(triggerLines(o, "Each set_standard_digital_out follows the servo step that"));
  if (o.trigger.output > 0) header.add("  reaches its sample (within one servo period).");
  header.add("Table: URScript has no external axis. table_start() and table_move() below are");
  header.add("  the cell's to implement (socket, Modbus register or digital IO); as written they");
  header.add("  only publish the target on RTDE output float registers 0 (deg) and 1 (s).");
  header.add(endlessLines(o, "the table"));
  return header;
}

std::string urSetup(const ProgramContext& c) {
  const ProgramOptions& o = c.options;
  const Eigen::Vector3d p = o.tool.translation();
  const Eigen::Vector3d r = rotationVector(o.tool.linear());
  std::string s = fmt::format("  set_tcp(p[{}, {}, {}, {}, {}, {}])\n", fixed(p.x(), kRadDecimals),
                              fixed(p.y(), kRadDecimals), fixed(p.z(), kRadDecimals),
                              fixed(r.x(), kRadDecimals), fixed(r.y(), kRadDecimals),
                              fixed(r.z(), kRadDecimals));
  if (o.payload_kg > 0.0) {
    s += fmt::format("  set_target_payload({}, [{}, {}, {}])\n", fixed(o.payload_kg, 3),
                     fixed(o.payload_cog.x(), 6), fixed(o.payload_cog.y(), 6),
                     fixed(o.payload_cog.z(), 6));
  }
  if (o.trigger.output > 0) s += setOut(c, levelAfter(Switch::kOff, o.trigger));
  s += "  def table_start(deg):\n"
       "    # Bring the table to deg (degrees) and return once it is there: as written it only\n"
       "    # publishes the target; wait here for the table's signal.\n"
       "    write_output_float_register(0, deg)\n"
       "    write_output_float_register(1, 0.0)\n"
       "  end\n"
       "  def table_move(deg, t):\n"
       "    # The table is at deg (degrees) t s after the servo motion starts, linearly from the\n"
       "    # previous point: queue the point and return at once (each comes one step ahead).\n"
       "    write_output_float_register(0, deg)\n"
       "    write_output_float_register(1, t)\n"
       "  end\n";
  s += fmt::format("  def servo(q):\n    servoj(q, t={}, lookahead_time={}, gain={})\n  end\n",
                   fixed(o.servo_period, 4), fixed(kLookahead, 2), kGain);
  return s;
}

}  // namespace

std::string urscriptProgram(const ProgramContext& c) {
  const auto& samples = c.trajectory.samples;
  const ProgramOptions& o = c.options;
  if (o.trigger.output > 7) {
    throw InputError(
        fmt::format("URScript program: trigger output {}: expected 1 ... 7 "
                    "(set_standard_digital_out's outputs; 0: none)",
                    o.trigger.output));
  }
  double slowest = std::numeric_limits<double>::infinity();
  for (int j = 0; j < kNumJoints; ++j) slowest = std::min(slowest, c.robot.joint(j).max_speed);
  const double approach_v = o.approach_speed_percent / 100.0 * slowest;
  std::string s = "def " + c.name + "():\n" + urHeader(c, approach_v).write("  #") + urSetup(c);
  s += "  # " + stepText(samples[0], c.table_deg[0]) + "\n";
  s += "  table_start(" + fixed(c.table_deg[0], kDecimals) + ")\n";
  s += "  movej([" + radians(samples[0].q) + "], a=1.4, v=" + fixed(approach_v, 3) + ")\n";
  if (c.switches[0] != Switch::kNone) s += setOut(c, levelAfter(c.switches[0], o.trigger));
  // Servo step i reaches t0 + i·period (the last one: the last sample).
  const double t0 = samples.front().t, period = o.servo_period;
  const double count = std::max(0.0, std::ceil((samples.back().t - t0) / period - 1e-9));
  if (count > static_cast<double>(kMaxServoSteps)) {
    throw InputError(fmt::format(
        "URScript program: {:.0f} servo steps of {} s over {} s: expected at most {} (a longer "
        "outputs.servo_period_s, or the scan in parts)",
        count, fixed(period, 4), fixed(samples.back().t - t0, 1), kMaxServoSteps));
  }
  const auto steps = static_cast<std::size_t>(count);
  std::size_t i = 0;  // servo steps written
  for (std::size_t k = 1; k < samples.size(); ++k) {
    if (c.step[k].over_speed) s += "  # " + warningText(k, c.step[k]) + "\n";
    s += "  # " + stepText(samples[k], c.table_deg[k]) + "\n";
    s += "  table_move(" + fixed(c.table_deg[k], kDecimals) + ", " +
         fixed(samples[k].t - t0, kDecimals) + ")\n";
    const TrajectorySample& a = samples[k - 1];
    const TrajectorySample& b = samples[k];
    while (i < steps &&
           (k + 1 == samples.size() || t0 + static_cast<double>(i + 1) * period <= b.t + 1e-12)) {
      ++i;
      const double tau = std::min(t0 + static_cast<double>(i) * period, b.t);
      const double w = std::clamp((tau - a.t) / (b.t - a.t), 0.0, 1.0);
      s += "  servo([" + radians(a.q + w * (b.q - a.q)) + "])\n";
    }
    if (c.switches[k] != Switch::kNone) s += setOut(c, levelAfter(c.switches[k], o.trigger));
  }
  s += "  stopj(2.0)\n";
  if (o.trigger.output > 0) s += setOut(c, levelAfter(Switch::kOff, o.trigger));
  s += "end\n";
  s += c.name + "()\n";  // the program runs what it defines
  return s;
}

}  // namespace scanplan::cli::detail
