// Universal Robots URScript: the trajectory as data, one row per planned sample, played by a
// short interpolating function (seg) that sends servoj every controller period along the
// joint-linear path between the rows. The file defines the program and then calls it. Current
// function names (set_standard_digital_out, set_target_payload: UR's script manual marks
// set_digital_out and set_payload deprecated).
#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include <scanplan/kinematics/error.h>
#include <scanplan/kinematics/units.h>
#include <scanplan/programs/detail/program_text.h>

namespace scanplan::programs::detail {

namespace {

using kinematics::JointVector;
using kinematics::kNumJoints;
using kinematics::TrajectorySample;

// servoj's smoothing: the shortest look-ahead URScript allows tracks the path closest; the gain
// is URScript's default.
constexpr double kLookahead = 0.03;  // s
constexpr int kGain = 300;

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
             " rad/s. Then each row a = seg(a, [t, table,");
  header.add(
      "  j1 .. j6, scan, out]) is a planned sample: t s from the start, the table in deg, the");
  header.add(
      "  joints in rad, scanning (1|0) and the trigger output's level after the sample (1|0).");
  header.add(
      fmt::format("  seg() sends servoj every {} s (the controller period; lookahead_time {},",
                  fixed(o.servo_period, 4), fixed(kLookahead, 2)));
  header.add(fmt::format(
      "  gain {}) along the joint-linear path from the previous row: one continuous", kGain));
  header.add("  motion, the last step reaching the last sample within one period of its time.");
  header.add("Size: at most 1 MB (UR controllers fail to load multi-megabyte scripts); a");
  header.add("  longer plan is refused, not cut.");
  header.add("Tool: set_tcp, the scanner's laser frame on the flange (rotation vector).");
  header.add(payloadLines(o, "set_target_payload."));
  header.add(triggerLines(o, "seg() switches it after the servo step that reaches the"));
  if (o.trigger.output > 0)
    header.add("  sample whose out column changes it (within one servo period).");
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
  s += urscriptStepFunction(o.servo_period, o.trigger.output);
  return s;
}

// servoj to q (URScript expressions), at the controller period.
std::string servojCall(const std::string& q, double period) {
  return fmt::format("servoj([{}], t={}, lookahead_time={}, gain={})", q, fixed(period, 4),
                     fixed(kLookahead, 2), kGain);
}

// One row of the program's data, a planned sample: t from the start, table, joints, scanning,
// the trigger output's level after it.
std::string urRow(const ProgramContext& c, std::size_t k, bool level) {
  const TrajectorySample& s = c.trajectory.samples[k];
  return fmt::format("{}, {}, {}, {}, {}", fixed(s.t - c.trajectory.samples.front().t, kDecimals),
                     fixed(c.table_deg[k], kDecimals), radians(s.q), s.scanning ? 1 : 0,
                     level ? 1 : 0);
}

}  // namespace

std::string urscriptStepFunction(double period, int output) {
  std::string q, previous;
  for (int j = 0; j < kNumJoints; ++j) {
    q += fmt::format("{}a[{}] + w * (d[{}] - a[{}])", j ? ", " : "", j + 3, j + 2, j + 3);
  }
  const std::string p = fixed(period, 4);
  std::string s =
      "  def seg(a, d):\n"
      "    table_move(d[1], d[0])\n"
      "    i = a[0] + 1\n"
      "    while i * " +
      p +
      " <= d[0] + 0.000001:\n"
      "      w = (i * " +
      p +
      " - a[1]) / (d[0] - a[1])\n"
      "      " +
      servojCall(q, period) +
      "\n"
      "      i = i + 1\n"
      "    end\n";
  if (output > 0) {
    s += fmt::format(
        "    if d[9] != a[10]:\n      set_standard_digital_out({}, d[9] == 1)\n    end\n", output);
  }
  return s +
         "    return [i - 1, d[0], d[1], d[2], d[3], d[4], d[5], d[6], d[7], d[8], d[9]]\n"
         "  end\n";
}

std::string urscriptLastStep(double period) {
  std::string q;
  for (int j = 0; j < kNumJoints; ++j) q += fmt::format("{}a[{}]", j ? ", " : "", j + 3);
  return "  if a[0] * " + fixed(period, 4) + " < a[1] - 0.000001:\n    " + servojCall(q, period) +
         "\n  end\n";
}

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
  bool level = levelAfter(Switch::kOff, o.trigger) && o.trigger.output > 0;
  if (c.switches[0] != Switch::kNone) {
    level = levelAfter(c.switches[0], o.trigger);
    s += setOut(c, level);
  }
  s += "  a = [0, " + urRow(c, 0, level) + "]\n";  // the state: no servo step yet, row 0
  for (std::size_t k = 1; k < samples.size(); ++k) {
    if (c.step[k].over_speed) s += "  # " + warningText(k, c.step[k]) + "\n";
    if (c.switches[k] != Switch::kNone) level = levelAfter(c.switches[k], o.trigger);
    s += "  a = seg(a, [" + urRow(c, k, level) + "])\n";
  }
  s += urscriptLastStep(o.servo_period);
  s += "  stopj(2.0)\n";
  if (endsSwitchedOn(c)) s += setOut(c, levelAfter(Switch::kOff, o.trigger));
  s += "end\n";
  s += c.name + "()\n";  // the program runs what it defines
  if (s.size() > kUrscriptMaxBytes) {
    throw InputError(fmt::format(
        "URScript program: {} bytes for {} samples over {} s: expected at most {} bytes (UR "
        "controllers fail to load multi-megabyte scripts): plan with a longer scan.dt_s (fewer "
        "samples), or scan the part in several jobs",
        s.size(), samples.size(), fixed(samples.back().t - samples.front().t, 1),
        kUrscriptMaxBytes));
  }
  return s;
}

}  // namespace scanplan::programs::detail
