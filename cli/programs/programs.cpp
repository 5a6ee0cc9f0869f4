#include "cli/programs/programs.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <regex>
#include <sstream>

#include <fmt/format.h>

#include "kinematics/error.h"
#include "kinematics/units.h"

namespace scanplan::cli {

using kinematics::kNumJoints;
using kinematics::RobotModel;
using kinematics::Trajectory;
using kinematics::TrajectorySample;

namespace {

constexpr int kTable = kNumJoints;  // Step::limiting for the table
// The printed precision: joints, table angles and times with 6 decimals (degrees, s); URScript's
// radians with 9 (about the same resolution). The controllers store single-precision reals
// (about 3e-5 deg at 360 deg), still far below their encoder resolution.
constexpr int kDecimals = 6;
constexpr int kRadDecimals = 9;
// A step needs more than the maximum speed when its percentage passes 100 by more than the
// relative tolerance validation allows (planner::ValidationSettings::speed_tolerance, 1e-6): a
// table path planned at its speed bound comes out at 100.0000x % from rounding alone, which
// validation rightly accepts.
constexpr double kOverSpeedTol = 100.0 * 1e-6;

std::string fixed(double v, int decimals) {
  std::string s = fmt::format("{:.{}f}", v, decimals);
  if (s[0] == '-' && s.find_first_not_of("-0.") == std::string::npos) s.erase(0, 1);  // no "-0"
  return s;
}

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::string upper(std::string s) {
  for (char& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return s;
}

// An identifier: letters, digits, '_' (and '.' when allowed); others become '_'. A leading
// non-letter gets a "p" prefix; empty → "scan"; at most max_length characters.
std::string identifier(const std::string& name, bool allow_dot, std::size_t max_length) {
  std::string id;
  for (const char c : name) {
    const bool ok = std::isalnum(static_cast<unsigned char>(c)) != 0 && (c & 0x80) == 0;
    id += ok || c == '_' || (allow_dot && c == '.') ? c : '_';
  }
  if (id.empty()) id = "scan";
  if (std::isalpha(static_cast<unsigned char>(id[0])) == 0) id = "p" + id;
  if (id.size() > max_length) id.resize(max_length);
  return id;
}

// Comment text: printable ASCII only (controllers' editors are not all UTF-8).
std::string commentText(const std::string& s) {
  std::string out;
  for (const char c : s) out += c >= 0x20 && c < 0x7f ? c : '?';
  return out;
}

// What each step (sample k ≥ 1, from sample k − 1) needs of the maximum speeds.
struct Step {
  double dt = 0.0;           // s
  double arm_percent = 0.0;  // of the limiting joint's maximum speed
  double percent = 0.0;      // the arm's or, when larger, the (known) table's
  int limiting = 0;          // 0-based joint, or kTable
  bool over_speed = false;
};

std::vector<Step> steps(const Trajectory& trajectory,
                        const RobotModel& robot,
                        const ProgramOptions& options) {
  std::vector<Step> out(trajectory.samples.size());
  for (std::size_t k = 1; k < out.size(); ++k) {
    const TrajectorySample& a = trajectory.samples[k - 1];
    const TrajectorySample& b = trajectory.samples[k];
    Step& s = out[k];
    s.dt = b.t - a.t;
    for (int j = 0; j < kNumJoints; ++j) {
      const double v_max = robot.joint(j).max_speed;
      const double p = v_max > 0.0 ? 100.0 * std::abs(b.q(j) - a.q(j)) / (s.dt * v_max) : 0.0;
      if (p > s.arm_percent) {
        s.arm_percent = p;
        s.limiting = j;
      }
    }
    s.percent = s.arm_percent;
    if (options.table_max_speed > 0.0) {
      const double p = 100.0 * std::abs(b.theta - a.theta) / (s.dt * options.table_max_speed);
      if (p > s.percent) {
        s.percent = p;
        s.limiting = kTable;
      }
    }
    s.over_speed = s.percent > 100.0 + kOverSpeedTol;
  }
  return out;
}

// The percentage a language can set, rounded up to its resolution (1: whole percent, 0.01 for
// V+), at least one step and at most 100: the limiting joint then covers its step in at most
// the planned time (DURATION or the synchronous PTP keeps the others in step).
double roundedPercent(double percent, double resolution) {
  const double steps = std::ceil(percent / resolution - 1e-9);
  return std::clamp(steps * resolution, resolution, 100.0);
}

std::string axisName(int limiting) {
  return limiting == kTable ? "the table" : "joint " + std::to_string(limiting + 1);
}

std::string warningText(std::size_t k, const Step& s) {
  return fmt::format("WARNING: step {} needs {:.2f} % of {}'s maximum speed", k, s.percent,
                     axisName(s.limiting));
}

std::string stepText(const TrajectorySample& s) {
  return "t=" + fixed(s.t, kDecimals) + " s table=" + fixed(s.theta * kRadToDeg, kDecimals) +
         " deg scan=" + (s.scanning ? "1" : "0");
}

std::string degrees(const TrajectorySample& s, const std::string& separator) {
  std::string out;
  for (int j = 0; j < kNumJoints; ++j) {
    out += (j ? separator : "") + fixed(s.q(j) * kRadToDeg, kDecimals);
  }
  return out;
}

// The header every program starts with, one comment line per element (without the marker).
struct Header {
  std::vector<std::string> lines;

  Header(const Trajectory& trajectory,
         const RobotModel& robot,
         const ProgramOptions& options,
         const std::string& program,
         std::size_t over_speed,
         const std::string& capped) {
    const auto& samples = trajectory.samples;
    lines.push_back("Generated by scanplan. Re-export rather than edit: moves and timing belong");
    lines.push_back("  together, and the program should be validated again before it is sent.");
    lines.push_back("Program " + program + " for the " + commentText(robot.name()) +
                    (options.job.empty() ? "" : ", job " + commentText(options.job)) + ".");
    lines.push_back(
        fmt::format("{} samples, one move each; duration {} s (t = {} ... {} s).", samples.size(),
                    fixed(samples.back().t - samples.front().t, kDecimals),
                    fixed(samples.front().t, kDecimals), fixed(samples.back().t, kDecimals)));
    double lo = samples.front().theta, hi = lo;
    for (const TrajectorySample& s : samples) {
      lo = std::min(lo, s.theta);
      hi = std::max(hi, s.theta);
    }
    lines.push_back("Table angles " + fixed(lo * kRadToDeg, 3) + " ... " +
                    fixed(hi * kRadToDeg, 3) + " deg, unwrapped (may pass +-360, never reduced).");
    if (over_speed == 0) {
      lines.push_back("Speed check: every step within the maximum speeds.");
    } else {
      lines.push_back(
          fmt::format("Speed check: {} step{} more than the maximum speed (WARNING): {}",
                      over_speed, over_speed == 1 ? " needs" : "s need", capped));
      lines.push_back("  there, and the step runs slower than planned.");
    }
  }

  void add(const std::string& text) { lines.push_back(text); }

  std::string write(const std::string& marker) const {
    std::string out;
    for (const std::string& line : lines) out += marker + " " + line + "\n";
    return out;
  }
};

void checkTrajectory(const Trajectory& trajectory, const std::string& what) {
  const auto fail = [&](std::size_t k, const std::string& why) {
    throw InputError(what + ": sample " + std::to_string(k) + ": " + why);
  };
  if (trajectory.samples.empty()) {
    throw InputError(what + ": the trajectory has no samples: expected at least one");
  }
  for (std::size_t k = 0; k < trajectory.samples.size(); ++k) {
    const TrajectorySample& s = trajectory.samples[k];
    if (!std::isfinite(s.t) || !std::isfinite(s.theta) || !s.q.allFinite()) {
      fail(k, "t, table angle and joints must be finite");
    }
    if (k > 0 && !(s.t > trajectory.samples[k - 1].t)) {
      fail(k, "t = " + fixed(s.t, kDecimals) + " s is not after the previous sample's " +
                  fixed(trajectory.samples[k - 1].t, kDecimals) +
                  " s: expected strictly increasing times");
    }
  }
}

std::string vplusProgram(const Trajectory& trajectory,
                         const RobotModel& robot,
                         const ProgramOptions& options,
                         const std::vector<Step>& step,
                         std::size_t over_speed,
                         const std::string& name,
                         const std::string& table_file) {
  const auto& samples = trajectory.samples;
  Header header(trajectory, robot, options, name, over_speed, "SPEED is capped at 100");
  header.add("Units: joints in degrees (#PPOINT), times in s, table angles in degrees.");
  header.add("Timing: the first MOVE goes to the start at SPEED " +
             fixed(options.approach_speed_percent, 2) + " and waits (BREAK).");
  header.add("  Every later step is one joint-interpolated MOVE: SPEED (percent of the maximum");
  header.add("  joint speeds; monitor SPEED 100 assumed) from the step's limiting joint, so that");
  header.add("  it covers its step in the planned time, rounded up to 0.01; DURATION (the");
  header.add("  planned time) so that no move ends early. Moves blend (continuous path).");
  header.add("Table: V+ has no rotary-table axis. Each step's comment has its table angle, and");
  header.add("  " + table_file + " (t_s,table_deg,scanning) lists them for the table");
  header.add("  controller, which plays it in step with the arm from the start of the second");
  header.add(options.vplus_table_start_signal > 0
                 ? "  move: SIGNAL " + std::to_string(options.vplus_table_start_signal) +
                       " turns on then."
                 : std::string("  move (wire a start signal after the first BREAK)."));
  header.add("  Bring the table to the first angle before the run.");
  header.add("Start configuration: " + robot.branchOf(samples.front().q).words());

  std::string out = ".PROGRAM " + name + "()\n" + header.write(";");
  std::istringstream words(robot.branchOf(samples.front().q).words());
  for (std::string word; words >> word;) out += "    " + word + "\n";
  for (std::size_t k = 0; k < samples.size(); ++k) {
    const Step& s = step[k];
    if (s.over_speed) out += "; " + warningText(k, s) + "\n";
    out += "; " + stepText(samples[k]) + "\n";
    if (k == 0) {
      out += "    SPEED " + fixed(options.approach_speed_percent, 2) + "\n";
    } else {
      out += "    SPEED " + fixed(roundedPercent(s.arm_percent, 0.01), 2) + "\n";
      out += "    DURATION " + fixed(s.dt, kDecimals) + "\n";
    }
    out += "    MOVE #PPOINT(" + degrees(samples[k], ", ") + ")\n";
    if (k == 0) {
      out += "    BREAK\n";
      if (options.vplus_table_start_signal > 0) {
        out += "    SIGNAL " + std::to_string(options.vplus_table_start_signal) + "\n";
      }
    }
  }
  out += "    BREAK\n.END\n";
  return out;
}

std::string vplusTable(const Trajectory& trajectory, const std::string& program) {
  std::string out = "# The table angles of V+ program " + program +
                    ", one row per MOVE: t_s (s, as in the program's comments),\n"
                    "# table_deg (degrees, unwrapped: may pass +-360), scanning (0/1).\n"
                    "# The table reaches each angle at its time, linearly between rows.\n"
                    "t_s,table_deg,scanning\n";
  for (const TrajectorySample& s : trajectory.samples) {
    out += fixed(s.t, kDecimals) + "," + fixed(s.theta * kRadToDeg, kDecimals) + "," +
           (s.scanning ? "1" : "0") + "\n";
  }
  return out;
}

std::string krlProgram(const Trajectory& trajectory,
                       const RobotModel& robot,
                       const ProgramOptions& options,
                       const std::vector<Step>& step,
                       std::size_t over_speed,
                       const std::string& name) {
  const auto& samples = trajectory.samples;
  const bool table_known = options.table_max_speed > 0.0;
  const std::string vel = "SCANPLAN_VEL";
  Header header(trajectory, robot, options, name, over_speed, "the velocity is capped at 100 %");
  header.add("Units: A1..A6 and E1 in degrees, times in s.");
  header.add("Timing: the first PTP goes to the start at " +
             fixed(roundedPercent(options.approach_speed_percent, 1.0), 0) +
             " % and stops there. Every later");
  header.add("  step is one PTP, approximated (C_PTP), with $VEL_AXIS[1..6] (whole percent, an");
  header.add("  INT) set by " + vel + "() from the step's limiting axis so that it covers its");
  header.add("  step in the planned time, rounded up to the next percent: a slow step can end");
  header.add(
      "  early (needing 5.2 %, set to 6 %: 87 % of its time). PTP is synchronous: the other");
  header.add("  axes follow the limiting one. KRL sets no time per PTP (the KSS 8 spline");
  header.add("  TIME_BLOCK would, with a spline path instead of joint-linear steps).");
  header.add("Table: external axis E1, in degrees. Configure E1 as an endless rotary axis, or");
  header.add("  give it software limits that cover the angles above.");
  header.add(table_known ? "  $VEL_EXTAX[1] is set with the arm's (the table can lead a step)."
                         : "  Its speed is not known here: $VEL_EXTAX[1] stays at 100 %.");

  std::string out = "DEF " + name + "( )\n" + header.write(";");
  out += "  BAS(#INITMOV,0)\n  $APO.CPTP=100\n";
  for (std::size_t k = 0; k < samples.size(); ++k) {
    const Step& s = step[k];
    if (s.over_speed) out += "; " + warningText(k, s) + "\n";
    out += "; " + stepText(samples[k]) + "\n";
    const double arm = k == 0 ? roundedPercent(options.approach_speed_percent, 1.0)
                              : roundedPercent(table_known ? s.percent : s.arm_percent, 1.0);
    const double e1 = k == 0 || table_known ? arm : 100.0;
    out += "  " + vel + "(" + fixed(arm, 0) + ", " + fixed(e1, 0) + ")\n";
    out += "  PTP {";
    for (int j = 0; j < kNumJoints; ++j) {
      out += fmt::format("A{} {}, ", j + 1, fixed(samples[k].q(j) * kRadToDeg, kDecimals));
    }
    out += "E1 " + fixed(samples[k].theta * kRadToDeg, kDecimals) + "}";
    out += k == 0 || k + 1 == samples.size() ? "\n" : " C_PTP\n";
  }
  out += "END\n\n";
  out += "DEF " + vel + "(ARM_PCT:IN, E1_PCT:IN)\n";
  out += "  ; $VEL_AXIS[1..6] and $VEL_EXTAX[1] in percent of the axes' maximum speeds.\n";
  out += "  INT ARM_PCT, E1_PCT, AXIS\n";
  out += "  FOR AXIS=1 TO 6\n    $VEL_AXIS[AXIS]=ARM_PCT\n  ENDFOR\n";
  out += "  $VEL_EXTAX[1]=E1_PCT\nEND\n";
  return out;
}

std::string rapidProgram(const Trajectory& trajectory,
                         const RobotModel& robot,
                         const ProgramOptions& options,
                         const std::vector<Step>& step,
                         std::size_t over_speed,
                         const std::string& name) {
  const auto& samples = trajectory.samples;
  Header header(trajectory, robot, options, name, over_speed, "the robot cannot keep \\T");
  header.add("Units: robax in degrees, eax_a (the table) in degrees, times in s.");
  header.add("Timing: the first MoveAbsJ goes to the start at v100 and stops there (fine).");
  header.add("  Every later step is one MoveAbsJ with \\T:= its planned time, which replaces");
  header.add("  the speed data (v1000 is not used); zone z0, the last one fine.");
  header.add("Table: the external axis eax_a, in degrees (its mechanical unit active); eax_b");
  header.add("  ... eax_f are unused (9E9). The angles are not reduced to +-180 deg: configure");
  header.add("  the axis as unlimited (or with limits that cover the angles above).");

  std::string out = "MODULE MOD_" + name + "\n" + header.write("!");
  out += "  PROC " + name + "()\n";
  for (std::size_t k = 0; k < samples.size(); ++k) {
    const Step& s = step[k];
    if (s.over_speed) out += "    ! " + warningText(k, s) + "\n";
    out += "    ! " + stepText(samples[k]) + "\n";
    out += "    MoveAbsJ [[" + degrees(samples[k], ",") + "],[" +
           fixed(samples[k].theta * kRadToDeg, kDecimals) + ",9E9,9E9,9E9,9E9,9E9]]\\NoEOffs, ";
    if (k == 0) {
      out += "v100, fine, tool0;\n";
    } else {
      out += "v1000\\T:=" + fixed(s.dt, kDecimals) + (k + 1 == samples.size() ? ", fine" : ", z0") +
             ", tool0;\n";
    }
  }
  out += "  ENDPROC\nENDMODULE\n";
  return out;
}

std::string urscriptProgram(const Trajectory& trajectory,
                            const RobotModel& robot,
                            const ProgramOptions& options,
                            const std::vector<Step>& step,
                            std::size_t over_speed,
                            const std::string& name) {
  const auto& samples = trajectory.samples;
  double slowest = std::numeric_limits<double>::infinity();
  for (int j = 0; j < kNumJoints; ++j) slowest = std::min(slowest, robot.joint(j).max_speed);
  const double approach_v = options.approach_speed_percent / 100.0 * slowest;
  Header header(trajectory, robot, options, name, over_speed, "movej cannot keep t");
  header.add("Units: joints in radians (movej), table angles in degrees, times in s.");
  header.add("Timing: the first movej goes to the start at v = " + fixed(approach_v, 3) +
             " rad/s. Every later");
  header.add("  step is one movej with t = its planned time (t has priority over a and v) and");
  header.add("  r = 0: the arm stops briefly at each point. servoj(q, t=...) with the same");
  header.add("  arguments streams the points without stopping, if the cell prefers.");
  header.add("Table: URScript has no external axis. table_start() and table_move() below are");
  header.add("  the cell's to implement (socket, Modbus register or digital IO); as written they");
  header.add("  only publish the target on RTDE output float registers 0 (deg) and 1 (s).");

  std::string out = "def " + name + "():\n" + header.write("  #");
  out +=
      "  def table_start(deg):\n"
      "    # Bring the table to deg (degrees, unwrapped) and return once it is there: as\n"
      "    # written it only publishes the target; wait here for the table's signal.\n"
      "    write_output_float_register(0, deg)\n"
      "    write_output_float_register(1, 0.0)\n"
      "  end\n"
      "  def table_move(deg, t):\n"
      "    # Start turning the table to deg (degrees, unwrapped), to arrive t s from now, and\n"
      "    # return at once: the arm's movej runs meanwhile.\n"
      "    write_output_float_register(0, deg)\n"
      "    write_output_float_register(1, t)\n"
      "  end\n";
  for (std::size_t k = 0; k < samples.size(); ++k) {
    const Step& s = step[k];
    if (s.over_speed) out += "  # " + warningText(k, s) + "\n";
    out += "  # " + stepText(samples[k]) + "\n";
    const std::string table = fixed(samples[k].theta * kRadToDeg, kDecimals);
    std::string q;
    for (int j = 0; j < kNumJoints; ++j)
      q += (j ? ", " : "") + fixed(samples[k].q(j), kRadDecimals);
    if (k == 0) {
      out += "  table_start(" + table + ")\n";
      out += "  movej([" + q + "], a=1.4, v=" + fixed(approach_v, 3) + ")\n";
    } else {
      const std::string dt = fixed(s.dt, kDecimals);
      out += "  table_move(" + table + ", " + dt + ")\n";
      out += "  movej([" + q + "], t=" + dt + ", r=0)\n";
    }
  }
  out += "end\n";
  return out;
}

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return {};
  const auto e = s.find_last_not_of(" \t\r");
  return s.substr(b, e - b + 1);
}

bool parseNumber(const std::string& text, double& value) {
  const std::string s = trim(text);
  if (s.empty()) return false;
  char* end = nullptr;
  value = std::strtod(s.c_str(), &end);
  return end == s.c_str() + s.size() && std::isfinite(value);
}

// Reads a V+ program as `plan` writes it (readVplusProgram): a step comment
// '; t=<s> s table=<deg> deg scan=<0|1>' before each MOVE #PPOINT(...), between .PROGRAM and
// .END. Errors name the source and line.
class VplusReader {
  static constexpr std::size_t kMaxLine = 1000;  // characters in a program line

 public:
  explicit VplusReader(const std::string& source) : source_(source) {}

  Trajectory read(const std::string& text) {
    std::istringstream in(text);
    std::string raw;
    while (!ended_ && std::getline(in, raw)) {
      ++line_number_;
      // Bounded before any pattern sees it (std::regex recurses per character: a 30 kB line
      // overflowed the stack); V+ itself keeps a program line far shorter.
      if (raw.size() > kMaxLine) {
        fail("'" + clipForMessage(raw) + "': expected a line of at most " +
             std::to_string(kMaxLine) + " characters");
      }
      const std::string line = trim(raw);
      if (line.empty()) continue;
      if (line[0] == ';') {
        readComment(line);
      } else {
        readInstruction(line);
      }
    }
    if (!in_program_) fail("no '.PROGRAM name()' line: expected a V+ program");
    if (pending_) {
      line_number_ = pending_line_;
      fail("step comment without its MOVE #PPOINT(...)");
    }
    if (!ended_) fail("the program has no .END");
    if (trajectory_.samples.empty()) fail("no MOVE #PPOINT(...) in the program");
    return trajectory_;
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    throw InputError(source_ + ":" + std::to_string(line_number_) + ": " + what);
  }

  // A comment: a step comment starts the sample its MOVE completes.
  void readComment(const std::string& line) {
    static const std::string kNum = R"([-+]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][-+]?[0-9]+)?)";
    static const std::regex kStep("t=(" + kNum + ") s table=(" + kNum + ") deg scan=([01])");
    const std::string comment = trim(line.substr(1));
    if (comment.rfind("t=", 0) != 0) return;  // an ordinary comment
    std::smatch m;
    if (!std::regex_match(comment, m, kStep)) {
      fail("step comment '" + clipForMessage(line) +
           "': expected '; t=<s> s table=<deg> deg scan=<0|1>'");
    }
    if (!in_program_) fail("step comment before .PROGRAM");
    if (pending_) {
      fail("step comment after the one on line " + std::to_string(pending_line_) +
           ", which has no MOVE: expected one MOVE #PPOINT(...) per step comment");
    }
    TrajectorySample s;
    s.t = std::strtod(m[1].str().c_str(), nullptr);
    s.theta = std::strtod(m[2].str().c_str(), nullptr) * kDegToRad;
    s.scanning = m[3].str() == "1";
    s.f = std::numeric_limits<double>::quiet_NaN();
    if (!std::isfinite(s.t) || !std::isfinite(s.theta)) fail("step comment: non-finite value");
    if (std::abs(s.theta) > kinematics::kMaxTrajectoryAngleDeg * kDegToRad) {
      fail(fmt::format("step comment: table={} deg: expected an angle within ±{} deg",
                       clipForMessage(m[2].str()), kinematics::kMaxTrajectoryAngleDeg));
    }
    if (!trajectory_.samples.empty() && !(s.t > trajectory_.samples.back().t)) {
      fail("t=" + m[1].str() + " s is not after the previous step's " +
           fixed(trajectory_.samples.back().t, kDecimals) +
           " s: expected strictly increasing times");
    }
    pending_ = s;
    pending_line_ = line_number_;
  }

  // An instruction, without a trailing comment.
  void readInstruction(const std::string& line) {
    static const std::regex kProgram(R"(\.PROGRAM\s+[A-Za-z][A-Za-z0-9._]*\s*\([^)]*\)\s*(;.*)?)",
                                     std::regex::icase);
    const std::string statement = trim(line.substr(0, line.find(';')));
    const std::string keyword = upper(statement.substr(0, statement.find_first_of(" \t(")));
    const std::string args = trim(statement.substr(keyword.size()));
    if (!in_program_) {
      if (keyword != ".PROGRAM" || !std::regex_match(line, kProgram)) {
        fail("'" + clipForMessage(line) + "': expected '.PROGRAM name()' first");
      }
      in_program_ = true;
      return;
    }
    if (keyword == ".END") {
      if (!args.empty()) fail("'" + clipForMessage(line) + "': expected '.END'");
      ended_ = true;
    } else if (keyword == "MOVE") {
      readMove(line, statement);
    } else if (keyword == "SPEED" || keyword == "DURATION") {
      checkSpeed(line, keyword, args);
    } else if (keyword == "SIGNAL") {
      if (!std::regex_match(args, std::regex(R"([-+]?[0-9]+(\s*,\s*[-+]?[0-9]+)*)"))) {
        fail("'" + clipForMessage(line) + "': expected 'SIGNAL n[, m ...]'");
      }
    } else if (keyword == "BREAK" || keyword == "LEFTY" || keyword == "RIGHTY" ||
               keyword == "ABOVE" || keyword == "BELOW" || keyword == "FLIP" ||
               keyword == "NOFLIP") {
      if (!args.empty()) fail("'" + clipForMessage(line) + "': expected '" + keyword + "' alone");
    } else {
      fail("'" + line +
           "': not an instruction this reader knows (MOVE #PPOINT(...), SPEED, DURATION, BREAK, "
           "SIGNAL, LEFTY/RIGHTY, ABOVE/BELOW, FLIP/NOFLIP, .END)");
    }
  }

  // MOVE #PPOINT(j1, ..., j6) in degrees: completes the pending step's sample.
  void readMove(const std::string& line, const std::string& statement) {
    static const std::regex kMove(R"(MOVE\s+#PPOINT\s*\(([^)]*)\))", std::regex::icase);
    std::smatch m;
    if (!std::regex_match(statement, m, kMove)) {
      fail("'" + clipForMessage(line) +
           "': expected 'MOVE #PPOINT(j1, j2, j3, j4, j5, j6)' (degrees)");
    }
    const std::string list = m[1].str();
    std::vector<std::string> values;
    std::stringstream cells(list);
    for (std::string cell; std::getline(cells, cell, ',');) values.push_back(cell);
    if (values.size() != static_cast<std::size_t>(kNumJoints)) {
      fail("'" + clipForMessage(line) + "': " + std::to_string(values.size()) +
           " joint values: expected 6 (degrees)");
    }
    if (!pending_) {
      fail(
          "MOVE without its step comment: expected '; t=<s> s table=<deg> deg scan=<0|1>' "
          "before it");
    }
    for (int j = 0; j < kNumJoints; ++j) {
      double v = 0.0;
      if (!parseNumber(values[static_cast<std::size_t>(j)], v)) {
        fail("'" + clipForMessage(line) + "': joint " + std::to_string(j + 1) + " '" +
             trim(values[static_cast<std::size_t>(j)]) + "' is not a finite number");
      }
      if (std::abs(v) > kinematics::kMaxTrajectoryAngleDeg) {
        fail(fmt::format("joint {} {} deg: expected an angle within ±{} deg", j + 1, v,
                         kinematics::kMaxTrajectoryAngleDeg));
      }
      pending_->q(j) = v * kDegToRad;
    }
    trajectory_.samples.push_back(*pending_);
    pending_.reset();
  }

  // SPEED or DURATION <value> [ALWAYS] (SPEED also in MMPS): checked, not used.
  void checkSpeed(const std::string& line,
                  const std::string& keyword,
                  const std::string& args) const {
    std::istringstream words(args);
    std::string value, rest;
    words >> value;
    std::getline(words, rest);
    double v = 0.0;
    const std::string tail = upper(trim(rest));
    const bool units_ok = tail.empty() || tail == "ALWAYS" ||
                          (keyword == "SPEED" && (tail == "MMPS" || tail == "MMPS ALWAYS"));
    if (!parseNumber(value, v) || v < 0.0 || !units_ok) {
      fail("'" + clipForMessage(line) + "': expected '" + keyword + " <value> [ALWAYS]'");
    }
  }

  const std::string& source_;
  Trajectory trajectory_;
  int line_number_ = 0;
  bool in_program_ = false, ended_ = false;
  std::optional<TrajectorySample> pending_;  // the step comment waiting for its MOVE
  int pending_line_ = 0;
};

}  // namespace

const std::vector<std::string>& programFormatNames() {
  static const std::vector<std::string> names = {"csv", "vplus", "krl", "rapid", "urscript"};
  return names;
}

std::string programFormatName(ProgramFormat format) {
  return programFormatNames()[static_cast<std::size_t>(format)];
}

std::optional<ProgramFormat> parseProgramFormat(const std::string& name) {
  const auto& names = programFormatNames();
  const auto it = std::find(names.begin(), names.end(), lower(name));
  if (it == names.end()) return std::nullopt;
  return static_cast<ProgramFormat>(it - names.begin());
}

ProgramFiles writeProgram(const Trajectory& trajectory,
                          const RobotModel& robot,
                          ProgramFormat format,
                          const ProgramOptions& options) {
  checkTrajectory(trajectory, programFormatName(format) + " program");
  if (!(options.approach_speed_percent > 0.0 && options.approach_speed_percent <= 100.0)) {
    throw InputError(fmt::format("program: approach speed {} %: expected (0, 100]",
                                 options.approach_speed_percent));
  }
  const std::vector<Step> step = steps(trajectory, robot, options);
  ProgramFiles result;
  for (const Step& s : step) {
    result.max_speed_percent = std::max(result.max_speed_percent, s.percent);
    if (s.over_speed) ++result.over_speed_segments;
  }
  const std::size_t over = result.over_speed_segments;
  switch (format) {
    case ProgramFormat::kCsv: {
      const std::string name = identifier(options.name, false, 64);
      result.files.emplace_back(name + ".csv", kinematics::trajectoryToCsv(trajectory));
      break;
    }
    case ProgramFormat::kVplus: {
      const std::string name = lower(identifier(options.name, true, 15));
      const std::string table_file = name + "_table.csv";
      result.files.emplace_back(
          name + ".v2", vplusProgram(trajectory, robot, options, step, over, name, table_file));
      result.files.emplace_back(table_file, vplusTable(trajectory, name));
      break;
    }
    case ProgramFormat::kKrl: {
      const std::string name = identifier(options.name, false, 24);
      result.files.emplace_back(name + ".src",
                                krlProgram(trajectory, robot, options, step, over, name));
      break;
    }
    case ProgramFormat::kRapid: {
      const std::string name = identifier(options.name, false, 28);
      result.files.emplace_back(name + ".mod",
                                rapidProgram(trajectory, robot, options, step, over, name));
      break;
    }
    case ProgramFormat::kUrscript: {
      const std::string name = identifier(options.name, false, 64);
      result.files.emplace_back(name + ".script",
                                urscriptProgram(trajectory, robot, options, step, over, name));
      break;
    }
  }
  return result;
}

Trajectory readVplusProgram(const std::string& text, const std::string& source) {
  return VplusReader(source).read(text);
}

}  // namespace scanplan::cli
