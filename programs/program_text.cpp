#include <scanplan/programs/detail/program_text.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <regex>
#include <sstream>
#include <string_view>
#include <utility>

#include <fmt/format.h>

#include <scanplan/kinematics/error.h>
#include <scanplan/kinematics/units.h>

namespace scanplan::programs::detail {

using kinematics::kNumJoints;
using kinematics::RobotModel;
using kinematics::Trajectory;
using kinematics::TrajectorySample;

namespace {

// A step needs more than the maximum speed when its percentage passes 100 by more than the
// relative tolerance validation allows (planner::ValidationSettings::speed_tolerance, 1e-6): a
// table path planned at its speed bound comes out at 100.0000x % from rounding alone, which
// validation rightly accepts.
constexpr double kOverSpeedTol = 100.0 * 1e-6;

std::string axisName(int limiting) {
  return limiting == kTable ? "the table" : "joint " + std::to_string(limiting + 1);
}

}  // namespace

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

std::string commentText(const std::string& s) {
  std::string out;
  for (const char c : asciiText(s)) out += c >= 0x20 && c < 0x7f ? c : '?';
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

std::vector<Switch> triggerSwitches(const Trajectory& trajectory, const ProgramTrigger& trigger) {
  const auto& samples = trajectory.samples;
  std::vector<Switch> out(samples.size(), Switch::kNone);
  if (trigger.output <= 0) return out;
  for (std::size_t k = 0; k < samples.size(); ++k) {
    if (!samples[k].scanning || (k > 0 && samples[k - 1].scanning)) continue;
    std::size_t last = k;
    while (last + 1 < samples.size() && samples[last + 1].scanning) ++last;
    out[k] = Switch::kOn;
    // A pass that runs to the end stays on until the program switches the output off last.
    if (last + 1 == samples.size()) continue;
    out[last > k ? last : last + 1] = Switch::kOff;
  }
  return out;
}

bool endsSwitchedOn(const ProgramContext& c) {
  for (auto s = c.switches.rbegin(); s != c.switches.rend(); ++s) {
    if (*s != Switch::kNone) return *s == Switch::kOn;
  }
  return false;
}

bool levelAfter(Switch s, const ProgramTrigger& trigger) {
  return (s == Switch::kOn) == trigger.on_at_scan_start;
}

std::vector<double> writtenTable(const Trajectory& trajectory, bool endless) {
  std::vector<double> out;
  out.reserve(trajectory.samples.size());
  for (std::size_t k = 0; k < trajectory.samples.size(); ++k) {
    const double planned = trajectory.samples[k].theta * kRadToDeg;
    if (!endless) {
      out.push_back(planned);
      continue;
    }
    if (k > 0 && std::abs(planned - trajectory.samples[k - 1].theta * kRadToDeg) >= 180.0) {
      throw InputError(fmt::format(
          "program: sample {}: the table turns {} deg in one step: an endless table takes the "
          "shorter way, which needs steps below 180 deg (resample the trajectory)",
          k, fixed(planned - trajectory.samples[k - 1].theta * kRadToDeg, 3)));
    }
    double wrapped = std::remainder(planned, 360.0);  // [-180, 180]
    if (wrapped <= -180.0) wrapped += 360.0;
    out.push_back(wrapped);
  }
  return out;
}

double roundedPercent(double percent, double resolution) {
  const double count = std::ceil(percent / resolution - 1e-9);
  return std::clamp(count * resolution, resolution, 100.0);
}

std::string warningText(std::size_t k, const Step& s) {
  return fmt::format("WARNING: step {} needs {:.2f} % of {}'s maximum speed", k, s.percent,
                     axisName(s.limiting));
}

std::string stepText(const TrajectorySample& s, double table_deg) {
  return "t=" + fixed(s.t, kDecimals) + " s table=" + fixed(table_deg, kDecimals) +
         " deg scan=" + (s.scanning ? "1" : "0");
}

std::string degrees(const TrajectorySample& s, const std::string& separator) {
  std::string out;
  for (int j = 0; j < kNumJoints; ++j) {
    out += (j ? separator : "") + fixed(s.q(j) * kRadToDeg, kDecimals);
  }
  return out;
}

std::vector<std::string> payloadLines(const ProgramOptions& options, const std::string& how) {
  if (!(options.payload_kg > 0.0)) {
    return {"Payload: NOT SET (scanner.mass_kg is not given): set the scanner's mass and",
            "  centre of gravity on the controller, or give scanner.mass_kg and re-export."};
  }
  const Eigen::Vector3d c = options.payload_cog * 1000.0;
  return {
      fmt::format("Payload: the scanner, {} kg, centre of gravity ({}, {}, {}) mm in the",
                  fixed(options.payload_kg, 3), fixed(c.x(), 1), fixed(c.y(), 1), fixed(c.z(), 1)),
      "  flange frame; " + how};
}

std::vector<std::string> triggerLines(const ProgramOptions& options, const std::string& how) {
  const ProgramTrigger& t = options.trigger;
  if (t.output <= 0) return {"Trigger: none (outputs.trigger.output is 0)."};
  return {fmt::format("Trigger: output {} is {} from each scan pass's first sample to its last,",
                      t.output, t.on_at_scan_start ? "on" : "off"),
          fmt::format("  {} otherwise (so before the first move and after the last).",
                      t.on_at_scan_start ? "off" : "on"),
          "  " + how};
}

std::vector<std::string> endlessLines(const ProgramOptions& options, const std::string& axis) {
  if (!options.table_endless) return {};
  return {
      "Table: an endless axis. Its angles are written within (-180, 180] deg, and every",
      "  step turns it less than 180 deg: configure " + axis + " as an endless (modulo) axis that",
      "  takes the shorter way, or set table.continuous: false to plan within limits."};
}

Header::Header(const ProgramContext& c, const std::string& capped) {
  const auto& samples = c.trajectory.samples;
  lines.push_back("Generated by scanplan. Re-export rather than edit: moves and timing belong");
  lines.push_back("  together, and the program should be validated again before it is sent.");
  lines.push_back("Program " + c.name + " for the " + commentText(c.robot.name()) +
                  (c.options.job.empty() ? "" : ", job " + commentText(c.options.job)) + ".");
  lines.push_back(fmt::format("{} samples; duration {} s (t = {} ... {} s).", samples.size(),
                              fixed(samples.back().t - samples.front().t, kDecimals),
                              fixed(samples.front().t, kDecimals),
                              fixed(samples.back().t, kDecimals)));
  const auto [lo, hi] = std::minmax_element(c.table_deg.begin(), c.table_deg.end());
  lines.push_back(
      "Table angles " + fixed(*lo, 3) + " ... " + fixed(*hi, 3) + " deg" +
      (c.options.table_endless ? ", wrapped (endless axis)." : ", as planned (never reduced)."));
  if (c.over_speed == 0) {
    lines.push_back("Speed check: every step within the maximum speeds.");
  } else {
    lines.push_back(fmt::format("Speed check: {} step{} more than the maximum speed (WARNING): {}",
                                c.over_speed, c.over_speed == 1 ? " needs" : "s need", capped));
    lines.push_back("  there, and the step runs slower than planned.");
  }
}

std::string Header::write(const std::string& marker) const {
  std::string out;
  for (const std::string& line : lines) out += marker + " " + line + "\n";
  return out;
}

Eigen::Vector3d vplusAngles(const Eigen::Matrix3d& R) {
  // R = Rz(a)·Ry(b)·Rz(c), b in [0, 180]; at b = 0 or 180 only a ± c is defined: c = 0 then.
  const double b = std::atan2(std::hypot(R(0, 2), R(1, 2)), R(2, 2));
  double a = 0.0, c = 0.0;
  if (std::hypot(R(0, 2), R(1, 2)) > 1e-12) {
    a = std::atan2(R(1, 2), R(0, 2));
    c = std::atan2(R(2, 1), -R(2, 0));
  } else if (R(2, 2) > 0.0) {  // R = Rz(a)
    a = std::atan2(R(1, 0), R(0, 0));
  } else {  // R = Rz(a)·Ry(180)
    a = std::atan2(-R(1, 0), -R(0, 0));
  }
  return Eigen::Vector3d(a, b, c) * kRadToDeg;
}

Eigen::Matrix3d fromVplusAngles(double yaw, double pitch, double roll) {
  using Eigen::AngleAxisd;
  using Eigen::Vector3d;
  return (AngleAxisd(yaw * kDegToRad, Vector3d::UnitZ()) *
          AngleAxisd(pitch * kDegToRad, Vector3d::UnitY()) *
          AngleAxisd(roll * kDegToRad, Vector3d::UnitZ()))
      .toRotationMatrix();
}

Eigen::Vector3d krlAngles(const Eigen::Matrix3d& R) {
  // R = Rz(A)·Ry(B)·Rx(C), B in [-90, 90]; at B = ±90 only A ∓ C is defined: C = 0 then.
  const double b = std::atan2(-R(2, 0), std::hypot(R(0, 0), R(1, 0)));
  double a = 0.0, c = 0.0;
  if (std::hypot(R(0, 0), R(1, 0)) > 1e-12) {
    a = std::atan2(R(1, 0), R(0, 0));
    c = std::atan2(R(2, 1), R(2, 2));
  } else {
    a = std::atan2(-R(0, 1), R(1, 1));
  }
  return Eigen::Vector3d(a, b, c) * kRadToDeg;
}

Eigen::Matrix3d fromKrlAngles(double a, double b, double c) {
  using Eigen::AngleAxisd;
  using Eigen::Vector3d;
  return (AngleAxisd(a * kDegToRad, Vector3d::UnitZ()) *
          AngleAxisd(b * kDegToRad, Vector3d::UnitY()) *
          AngleAxisd(c * kDegToRad, Vector3d::UnitX()))
      .toRotationMatrix();
}

Eigen::Vector3d rotationVector(const Eigen::Matrix3d& R) {
  const Eigen::AngleAxisd aa(R);
  return aa.axis() * aa.angle();
}

Eigen::Matrix3d fromRotationVector(const Eigen::Vector3d& r) {
  const double angle = r.norm();
  if (angle < 1e-15) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(angle, r / angle).toRotationMatrix();
}

LineReader::LineReader(const std::string& text, const std::string& source)
    : text_(text), source_(source) {}

bool LineReader::next(std::string& line) {
  if (at_ >= text_.size()) return false;
  const std::size_t end = std::min(text_.find('\n', at_), text_.size());
  const std::size_t length = end - at_;
  ++line_number_;
  if (length > kMaxLine) {
    // Quoted as clipForMessage quotes, without copying the whole line.
    fail("'" + text_.substr(at_, 80) + "… (" + std::to_string(length) +
         " characters)': expected a line of at most " + std::to_string(kMaxLine) + " characters");
  }
  line = trim(text_.substr(at_, length));
  at_ = end + 1;
  return true;
}

void LineReader::fail(const std::string& what) const { failAt(line_number_, what); }

void LineReader::failAt(int line, const std::string& what) const {
  throw InputError(source_ + ":" + std::to_string(line) + ": " + what);
}

std::vector<double> numberList(const LineReader& in,
                               const std::string& list,
                               std::size_t expected,
                               const std::string& what) {
  std::vector<double> out;
  std::stringstream cells(list);
  for (std::string cell; std::getline(cells, cell, ',');) {
    double v = 0.0;
    if (!parseNumber(cell, v)) {
      in.fail(what + ": '" + clipForMessage(trim(cell)) + "' is not a finite number");
    }
    out.push_back(v);
  }
  if (out.size() != expected) {
    in.fail(fmt::format("{}: {} values: expected {}", what, out.size(), expected));
  }
  return out;
}

bool readStepComment(const LineReader& in,
                     const std::string& comment,
                     double& t,
                     double& table_deg,
                     bool& scanning) {
  static const std::string kNum = R"([-+]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][-+]?[0-9]+)?)";
  static const std::regex kStep("t=(" + kNum + ") s table=(" + kNum + ") deg scan=([01])");
  const std::string text = trim(comment);
  if (text.rfind("t=", 0) != 0) return false;  // an ordinary comment
  std::smatch m;
  if (!std::regex_match(text, m, kStep)) {
    in.fail("step comment '" + clipForMessage(text) +
            "': expected 't=<s> s table=<deg> deg scan=<0|1>'");
  }
  t = std::strtod(m[1].str().c_str(), nullptr);
  table_deg = std::strtod(m[2].str().c_str(), nullptr);
  scanning = m[3].str() == "1";
  if (!std::isfinite(t) || !std::isfinite(table_deg)) in.fail("step comment: non-finite value");
  if (std::abs(table_deg) > kinematics::kMaxTrajectoryAngleDeg) {
    in.fail(fmt::format("step comment: table={} deg: expected an angle within ±{} deg",
                        clipForMessage(m[2].str()), kinematics::kMaxTrajectoryAngleDeg));
  }
  return true;
}

void appendSample(const LineReader& in,
                  Trajectory& trajectory,
                  double t,
                  const std::vector<double>& q_deg,
                  double table_deg,
                  bool scanning) {
  TrajectorySample s;
  s.t = t;
  s.scanning = scanning;
  s.f = std::numeric_limits<double>::quiet_NaN();
  for (int j = 0; j < kNumJoints; ++j) {
    const double v = q_deg[static_cast<std::size_t>(j)];
    if (std::abs(v) > kinematics::kMaxTrajectoryAngleDeg) {
      in.fail(fmt::format("joint {} {} deg: expected an angle within ±{} deg", j + 1, v,
                          kinematics::kMaxTrajectoryAngleDeg));
    }
    s.q(j) = v * kDegToRad;
  }
  if (std::abs(table_deg) > kinematics::kMaxTrajectoryAngleDeg) {
    in.fail(fmt::format("table {} deg: expected an angle within ±{} deg", table_deg,
                        kinematics::kMaxTrajectoryAngleDeg));
  }
  double table = table_deg;
  if (!trajectory.samples.empty()) {
    const TrajectorySample& prev = trajectory.samples.back();
    const double prev_deg = prev.theta * kRadToDeg;
    table = prev_deg + std::remainder(table_deg - prev_deg, 360.0);  // the shorter way
    if (!(t > prev.t)) {
      in.fail("t = " + fixed(t, kDecimals) + " s is not after the previous step's " +
              fixed(prev.t, kDecimals) + " s: expected strictly increasing times");
    }
  }
  if (!std::isfinite(t)) in.fail("a non-finite time");
  s.theta = table * kDegToRad;
  trajectory.samples.push_back(s);
}

std::string asciiText(const std::string& text) {
  static const std::pair<std::string_view, std::string_view> kWords[] = {
      {"\u00b7", "*"},   {"\u00b0", " deg"}, {"\u2026", "..."}, {"\u00b1", "+/-"}, {"\u2212", "-"},
      {"\u00d7", "x"},   {"\u00b2", "^2"},   {"\u2192", "->"},  {"\u2264", "<="},  {"\u2265", ">="},
      {"\u2213", "-/+"}, {"\u2013", "-"},    {"\u2014", "-"},   {"\u00b3", "^3"}};
  if (std::all_of(text.begin(), text.end(), [](char ch) { return (ch & 0x80) == 0; })) return text;
  std::string out;
  out.reserve(text.size());
  for (std::size_t i = 0; i < text.size();) {
    if ((text[i] & 0x80) == 0) {
      out += text[i++];
      continue;
    }
    const std::string_view rest(text.data() + i, text.size() - i);
    bool known = false;
    for (const auto& [from, to] : kWords) {
      if (rest.substr(0, from.size()) != from) continue;
      out += to;
      i += from.size();
      known = true;
      break;
    }
    if (known) continue;
    out += '?';  // one character of any length: its lead byte, then its continuation bytes
    for (++i; i < text.size() && (static_cast<unsigned char>(text[i]) & 0xC0) == 0x80; ++i) {
    }
  }
  return out;
}

}  // namespace scanplan::programs::detail
