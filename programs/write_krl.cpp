// KUKA KRL (KSS 8): the approach PTP, then PTP_SPLINE blocks timed by TIME_BLOCK.
#include <fmt/format.h>

#include <scanplan/kinematics/units.h>
#include <scanplan/programs/detail/program_text.h>

namespace scanplan::programs::detail {

namespace {

using kinematics::kNumJoints;

const char* const kVel = "SCANPLAN_VEL";
// TIME_BLOCK PART in percent with 9 decimals: hundreds of equal steps rounded alike would
// otherwise shift the block's middle by ~1e-5 s (the last PART makes the sum 100).
constexpr int kPartDecimals = 9;

std::string target(const ProgramContext& c, std::size_t k) {
  std::string out = "{";
  for (int j = 0; j < kNumJoints; ++j) {
    out +=
        fmt::format("A{} {}, ", j + 1, fixed(c.trajectory.samples[k].q(j) * kRadToDeg, kDecimals));
  }
  return out + "E1 " + fixed(c.table_deg[k], kDecimals) + "}";
}

std::string out(const ProgramContext& c, bool level) {
  return fmt::format("$OUT[{}]={}", c.options.trigger.output, level ? "TRUE" : "FALSE");
}

// The blocks' last samples: at most kKrlMaxSegments segments each, ending between scan passes
// (at a sample that is not scanning) when one lies in the block's second half.
std::vector<std::size_t> blockEnds(const ProgramContext& c) {
  const auto& samples = c.trajectory.samples;
  const std::size_t last = samples.size() - 1;
  std::vector<std::size_t> ends;
  for (std::size_t begin = 1; begin <= last;) {
    std::size_t end = std::min(begin + kKrlMaxSegments - 1, last);
    if (end < last) {
      for (std::size_t k = end; k >= begin + kKrlMaxSegments / 2; --k) {
        if (!samples[k].scanning) {
          end = k;
          break;
        }
      }
    }
    ends.push_back(end);
    begin = end + 1;
  }
  return ends;
}

Header krlHeader(const ProgramContext& c) {
  const ProgramOptions& o = c.options;
  Header header(c, "the time block cannot be kept");
  header.add("Units: A1..A6 and E1 in degrees, lengths in mm, times in s.");
  header.add("Timing: the first PTP goes to the start at " +
             fixed(roundedPercent(o.approach_speed_percent, 1.0), 0) +
             " % and stops there. The planned motion");
  header.add("  follows in PTP_SPLINE blocks (KSS 8.3 or later), one SPTP segment per step, at");
  header.add(fmt::format("  most {} a block, split between scan passes (the arm stops briefly at",
                         kKrlMaxSegments));
  header.add("  a block's end); $VEL_AXIS at 100 % under the TIME_BLOCKs.");
  header.add("  TIME_BLOCK times each block: END = its planned time, PART = each step's share");
  header.add("  of it in percent. A block the axes cannot keep runs slower (a KSS message).");
  header.add("Tool: $TOOL, the scanner's laser frame on the flange (A, B, C: Rz·Ry·Rx).");
  header.add(payloadLines(o, "$LOAD (inertia not known: J = 0)."));
  header.add(triggerLines(o, "TRIGGER WHEN PATH=0 DELAY=0 before a segment switches at its end"));
  if (o.trigger.output > 0) {
    header.add("  point (before the approach PTP: DISTANCE=1), in step with the path rather than");
    header.add("  the advance run.");
  }
  if (o.table_endless) {
    header.add(endlessLines(o, "E1"));
  } else {
    header.add("Table: external axis E1, in degrees, within its software limits as planned.");
  }
  return header;
}

std::string krlSetup(const ProgramContext& c) {
  const ProgramOptions& o = c.options;
  const Eigen::Vector3d p = o.tool.translation() * 1000.0;
  const Eigen::Vector3d a = krlAngles(o.tool.linear());
  std::string s = "  BAS(#INITMOV,0)\n";
  s += fmt::format("  $TOOL={{X {},Y {},Z {},A {},B {},C {}}}\n", fixed(p.x(), 3), fixed(p.y(), 3),
                   fixed(p.z(), 3), fixed(a.x(), kDecimals), fixed(a.y(), kDecimals),
                   fixed(a.z(), kDecimals));
  if (o.payload_kg > 0.0) {
    const Eigen::Vector3d m = o.payload_cog * 1000.0;
    s += "  $LOAD.M=" + fixed(o.payload_kg, 3) + "\n";
    s += fmt::format("  $LOAD.CM={{X {},Y {},Z {},A 0,B 0,C 0}}\n", fixed(m.x(), 3),
                     fixed(m.y(), 3), fixed(m.z(), 3));
    s += "  $LOAD.J={X 0,Y 0,Z 0}\n";
  }
  if (o.trigger.output > 0) s += "  " + out(c, levelAfter(Switch::kOff, o.trigger)) + "\n";
  return s;
}

// One PTP_SPLINE block, samples first..last, timed from sample first − 1.
std::string block(const ProgramContext& c, std::size_t first, std::size_t last) {
  const auto& samples = c.trajectory.samples;
  const double total = samples[last].t - samples[first - 1].t;
  std::string s = "  PTP_SPLINE\n    TIME_BLOCK START\n";
  double parts = 0.0;  // the PARTs as printed: the last one makes them 100 exactly
  for (std::size_t k = first; k <= last; ++k) {
    if (c.step[k].over_speed) s += "; " + warningText(k, c.step[k]) + "\n";
    s += "; " + stepText(samples[k], c.table_deg[k]) + "\n";
    if (c.switches[k] != Switch::kNone) {
      s += "    TRIGGER WHEN PATH=0 DELAY=0 DO " +
           out(c, levelAfter(c.switches[k], c.options.trigger)) + "\n";
    }
    s += "    SPTP " + target(c, k) + "\n";
    std::string part = fixed(100.0 * c.step[k].dt / total, kPartDecimals);
    if (k == last) part = fixed(std::max(0.0, 100.0 - parts), kPartDecimals);
    parts += std::stod(part);
    s += "    TIME_BLOCK PART=" + part + "\n";
  }
  s += "    TIME_BLOCK END=" + fixed(total, kDecimals) + "\n  ENDSPLINE\n";
  return s;
}

}  // namespace

std::string krlProgram(const ProgramContext& c) {
  const auto& samples = c.trajectory.samples;
  const ProgramOptions& o = c.options;
  std::string s = "DEF " + c.name + "( )\n" + krlHeader(c).write(";") + krlSetup(c);
  s += "; " + stepText(samples[0], c.table_deg[0]) + "\n";
  const std::string pct = fixed(roundedPercent(o.approach_speed_percent, 1.0), 0);
  s += "  " + std::string(kVel) + "(" + pct + ", " + pct + ")\n";
  if (c.switches[0] != Switch::kNone) {
    s += "  TRIGGER WHEN DISTANCE=1 DELAY=0 DO " + out(c, levelAfter(c.switches[0], o.trigger)) +
         "\n";
  }
  s += "  PTP " + target(c, 0) + "\n";
  // The spline blocks are timed by TIME_BLOCK: the axes' velocity limits at 100 % under it.
  if (samples.size() > 1) s += "  " + std::string(kVel) + "(100, 100)\n";
  std::size_t first = 1;
  for (const std::size_t last : samples.size() > 1 ? blockEnds(c) : std::vector<std::size_t>{}) {
    s += block(c, first, last);
    first = last + 1;
  }
  if (endsSwitchedOn(c)) {
    s += "  WAIT SEC 0  ; stops the advance run: the output goes off after the last point\n";
    s += "  " + out(c, levelAfter(Switch::kOff, o.trigger)) + "\n";
  }
  s += "END\n\n";
  return s + krlVelocityRoutine();
}

std::string krlVelocityRoutine() {
  // The declarations come first, alone: a strict KRL parser allows nothing before them.
  std::string s = "DEF " + std::string(kVel) + "(ARM_PCT:IN, E1_PCT:IN)\n";
  s += "  INT ARM_PCT, E1_PCT, AXIS\n";
  s += "  ; $VEL_AXIS[1..6] and $VEL_EXTAX[1] in percent of the axes' maximum speeds.\n";
  s += "  FOR AXIS=1 TO 6\n    $VEL_AXIS[AXIS]=ARM_PCT\n  ENDFOR\n";
  s += "  $VEL_EXTAX[1]=E1_PCT\nEND\n";
  return s;
}

}  // namespace scanplan::programs::detail
