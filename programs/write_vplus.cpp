// Adept V+: the program (.v2) and the table list for the table controller.
#include <sstream>

#include <fmt/format.h>

#include <scanplan/kinematics/units.h>
#include <scanplan/programs/detail/program_text.h>

namespace scanplan::programs::detail {

namespace {

std::string signal(const ProgramContext& c, bool level) {
  return "    SIGNAL " + std::string(level ? "" : "-") + std::to_string(c.options.trigger.output) +
         "\n";
}

std::string toolLine(const ProgramOptions& o) {
  const Eigen::Vector3d p = o.tool.translation() * 1000.0;
  const Eigen::Vector3d a = vplusAngles(o.tool.linear());
  return fmt::format("    TOOL TRANS({}, {}, {}, {}, {}, {})\n", fixed(p.x(), 3), fixed(p.y(), 3),
                     fixed(p.z(), 3), fixed(a.x(), kDecimals), fixed(a.y(), kDecimals),
                     fixed(a.z(), kDecimals));
}

Header vplusHeader(const ProgramContext& c, const std::string& table_file) {
  const ProgramOptions& o = c.options;
  Header header(c, "SPEED is capped at 100");
  header.add("Units: joints in degrees (#PPOINT), times in s, table angles in degrees.");
  header.add("Timing: the first MOVE goes to the start at SPEED " +
             fixed(o.approach_speed_percent, 2) + " and waits (BREAK).");
  header.add("  Every later step is one joint-interpolated MOVE: SPEED (percent of the maximum");
  header.add("  joint speeds; monitor SPEED 100 assumed) from the step's limiting joint, so that");
  header.add("  it covers its step in the planned time, rounded up to 0.01; DURATION (the");
  header.add("  planned time) so that no move ends early. Moves blend (continuous path).");
  header.add("Tool: TOOL TRANS(x, y, z mm, yaw, pitch, roll deg), the scanner's laser frame.");
  header.add(payloadLines(o, "V+ has no payload in kg (PAYLOAD is a percentage, on some arms"));
  if (o.payload_kg > 0.0) header.add("  only): set it in the robot's SPEC data.");
  header.add(triggerLines(o, "V+ runs the instructions after a MOVE as that move starts:"));
  if (o.trigger.output > 0) header.add("  each SIGNAL follows the MOVE that leaves its sample.");
  header.add("Table: V+ has no rotary-table axis. Each step's comment has its table angle, and");
  header.add("  " + table_file + " lists them for the table controller, one row per MOVE:");
  header.add(std::string("  t_s (s, as in the step comments), table_deg (degrees") +
             (o.table_endless ? ", within (-180, 180]" : ", as planned") + "), scanning (0/1).");
  header.add("  The table reaches each angle at its time, linearly between rows: the controller");
  header.add("  plays the list in step with the arm from the start of the second");
  header.add(o.vplus_table_start_signal > 0
                 ? "  move: SIGNAL " + std::to_string(o.vplus_table_start_signal) +
                       " turns on then."
                 : std::string("  move (wire a start signal after the first BREAK)."));
  header.add("  Bring the table to the first angle before the run.");
  header.add(endlessLines(o, "the table"));
  header.add("Start configuration: " + c.robot.branchOf(c.trajectory.samples.front().q).words());
  return header;
}

}  // namespace

std::string vplusProgram(const ProgramContext& c, const std::string& table_file) {
  const auto& samples = c.trajectory.samples;
  const ProgramOptions& o = c.options;
  const bool trigger = o.trigger.output > 0;
  std::string out = ".PROGRAM " + c.name + "()\n" + vplusHeader(c, table_file).write(";");
  std::istringstream words(c.robot.branchOf(samples.front().q).words());
  for (std::string word; words >> word;) out += "    " + word + "\n";
  out += toolLine(o);
  if (trigger) out += signal(c, levelAfter(Switch::kOff, o.trigger));
  if (o.vplus_table_start_signal > 0) {  // off first: the table controller sees a rising edge
    out += "    SIGNAL -" + std::to_string(o.vplus_table_start_signal) + "\n";
  }
  // The switch at sample k goes after the MOVE that leaves it (k + 1), or after a BREAK.
  const auto switchAt = [&](std::size_t k) {
    if (c.switches[k] != Switch::kNone) out += signal(c, levelAfter(c.switches[k], o.trigger));
  };
  for (std::size_t k = 0; k < samples.size(); ++k) {
    const Step& s = c.step[k];
    if (s.over_speed) out += "; " + warningText(k, s) + "\n";
    out += "; " + stepText(samples[k], c.table_deg[k]) + "\n";
    if (k == 0) {
      out += "    SPEED " + fixed(o.approach_speed_percent, 2) + "\n";
    } else {
      out += "    SPEED " + fixed(roundedPercent(s.arm_percent, 0.01), 2) + "\n";
      out += "    DURATION " + fixed(s.dt, kDecimals) + "\n";
    }
    out += "    MOVE #PPOINT(" + degrees(samples[k], ", ") + ")\n";
    if (k == 0) {
      out += "    BREAK\n";
      switchAt(0);
      if (o.vplus_table_start_signal > 0) {
        out += "    SIGNAL " + std::to_string(o.vplus_table_start_signal) + "\n";
      }
    } else if (k >= 2) {
      switchAt(k - 1);
    }
  }
  out += "    BREAK\n";
  if (samples.size() >= 2) switchAt(samples.size() - 1);
  if (endsSwitchedOn(c)) out += signal(c, levelAfter(Switch::kOff, o.trigger));
  out += ".END\n";
  return out;
}

// A plain CSV, header row first (a '#' line would read as data in most CSV readers): what it
// holds is in the program's header.
std::string vplusTable(const ProgramContext& c) {
  std::string out = "t_s,table_deg,scanning\n";
  const auto& samples = c.trajectory.samples;
  for (std::size_t k = 0; k < samples.size(); ++k) {
    out += fixed(samples[k].t, kDecimals) + "," + fixed(c.table_deg[k], kDecimals) + "," +
           (samples[k].scanning ? "1" : "0") + "\n";
  }
  return out;
}

}  // namespace scanplan::programs::detail
