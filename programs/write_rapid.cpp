// ABB RAPID: a module with the tool, PROC main() and the scan procedure of MoveAbsJ \T steps.
#include <fmt/format.h>

#include <scanplan/kinematics/units.h>
#include <scanplan/programs/detail/program_text.h>

namespace scanplan::programs::detail {

namespace {

std::string signalName(const ProgramOptions& o) {
  return o.trigger.rapid_signal.empty() ? "do" + std::to_string(o.trigger.output)
                                        : o.trigger.rapid_signal;
}

std::string setDo(const ProgramContext& c, bool level) {
  return "    SetDO " + signalName(c.options) + ", " + (level ? "1" : "0") + ";\n";
}

std::string toolName(const ProgramContext& c) {
  return c.options.payload_kg > 0.0 ? "t_" + c.name : "tool0";
}

// PERS tooldata: the scanner's frame (mm, quaternion w x y z) and its load as tload.
std::string toolData(const ProgramContext& c) {
  const ProgramOptions& o = c.options;
  const Eigen::Vector3d p = o.tool.translation() * 1000.0;
  Eigen::Quaterniond q(o.tool.linear());
  if (q.w() < 0.0) q.coeffs() *= -1.0;
  q.normalize();
  const Eigen::Vector3d m = o.payload_cog * 1000.0;
  return fmt::format(
      "  PERS tooldata {}:=[TRUE,[[{},{},{}],[{},{},{},{}]],[{},[{},{},{}],[1,0,0,0],0,0,0]];\n",
      toolName(c), fixed(p.x(), 3), fixed(p.y(), 3), fixed(p.z(), 3), fixed(q.w(), 9),
      fixed(q.x(), 9), fixed(q.y(), 9), fixed(q.z(), 9), fixed(o.payload_kg, 3), fixed(m.x(), 3),
      fixed(m.y(), 3), fixed(m.z(), 3));
}

Header rapidHeader(const ProgramContext& c) {
  const ProgramOptions& o = c.options;
  Header header(c, "the robot cannot keep \\T");
  header.add("Units: robax in degrees, eax_a (the table) in degrees, lengths in mm, times in s.");
  header.add("Run: PROC main() calls " + c.name + ".");
  header.add("Timing: the first MoveAbsJ goes to the start at v100 and stops there (fine).");
  header.add("  Every later step is one MoveAbsJ with \\T:= its planned time, which replaces");
  header.add("  the speed data (v1000 is not used); zone z0, the last one fine.");
  if (o.payload_kg > 0.0) {
    header.add("Tool: " + toolName(c) + ", the scanner's laser frame on the flange, its load the");
    header.add("  scanner's (tload; inertia not known: 0).");
  } else {
    const Eigen::Vector3d p = o.tool.translation() * 1000.0;
    header.add(
        fmt::format("Tool: tool0. The scanner's frame is at ({}, {}, {}) mm on the flange, but",
                    fixed(p.x(), 1), fixed(p.y(), 1), fixed(p.z(), 1)));
    header.add("  tooldata needs its mass (tload): give scanner.mass_kg and re-export.");
  }
  header.add(payloadLines(o, "in the tooldata's tload."));
  header.add(triggerLines(
      o, "SetDO " + signalName(o) + " follows the MoveAbsJ that reaches its sample. In a z0"));
  if (o.trigger.output > 0) {
    header.add("  zone RAPID runs it as the arm enters the zone (within 0.3 mm of the point);");
    header.add("  after the fine start point, once the arm is in position. Joint targets keep the");
    header.add("  program free of the base and tool calibration that TriggJ's robtargets need.");
  }
  if (o.table_endless) {
    header.add(endlessLines(o, "eax_a"));
  } else {
    header.add("Table: the external axis eax_a, in degrees (its mechanical unit active), as");
    header.add("  planned; eax_b ... eax_f are unused (9E9).");
  }
  return header;
}

std::string moveAbsJ(const ProgramContext& c, std::size_t k) {
  const auto& samples = c.trajectory.samples;
  std::string s = "    MoveAbsJ [[" + degrees(samples[k], ",") + "],[" +
                  fixed(c.table_deg[k], kDecimals) + ",9E9,9E9,9E9,9E9,9E9]]\\NoEOffs, ";
  if (k == 0) return s + "v100, fine, " + toolName(c) + ";\n";
  return s + "v1000\\T:=" + fixed(c.step[k].dt, kDecimals) +
         (k + 1 == samples.size() ? ", fine, " : ", z0, ") + toolName(c) + ";\n";
}

}  // namespace

std::string rapidProgram(const ProgramContext& c) {
  const auto& samples = c.trajectory.samples;
  const ProgramOptions& o = c.options;
  const bool trigger = o.trigger.output > 0;
  std::string s = "MODULE MOD_" + c.name + "\n" + rapidHeader(c).write("!");
  if (o.payload_kg > 0.0) s += toolData(c);
  s += "\n  PROC main()\n    " + c.name + ";\n  ENDPROC\n\n";
  s += "  PROC " + c.name + "()\n";
  if (trigger) s += setDo(c, levelAfter(Switch::kOff, o.trigger));
  for (std::size_t k = 0; k < samples.size(); ++k) {
    if (c.step[k].over_speed) s += "    ! " + warningText(k, c.step[k]) + "\n";
    s += "    ! " + stepText(samples[k], c.table_deg[k]) + "\n";
    s += moveAbsJ(c, k);
    if (c.switches[k] != Switch::kNone) s += setDo(c, levelAfter(c.switches[k], o.trigger));
  }
  if (endsSwitchedOn(c)) s += setDo(c, levelAfter(Switch::kOff, o.trigger));
  s += "  ENDPROC\nENDMODULE\n";
  return s;
}

}  // namespace scanplan::programs::detail
