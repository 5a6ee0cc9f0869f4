#pragma once
// What the program writers and readers share (programs.h): number formatting, identifiers,
// the per-step speed check, the header, the trigger's switch points, the tool's angles in each
// language's convention, and a line reader that names the source and line in its errors.

#include <cstddef>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include <scanplan/kinematics/robot_model.h>
#include <scanplan/kinematics/trajectory.h>
#include <scanplan/programs/programs.h>

namespace scanplan::programs::detail {

inline constexpr int kTable = kinematics::kNumJoints;  // Step::limiting for the table
// The printed precision: joints, table angles and times with 6 decimals (degrees, s); URScript's
// radians with 9 (about the same resolution). The controllers store single-precision reals
// (about 3e-5 deg at 360 deg), still far below their encoder resolution.
inline constexpr int kDecimals = 6;
inline constexpr int kRadDecimals = 9;

std::string fixed(double v, int decimals);
std::string lower(std::string s);
std::string upper(std::string s);
/// Letters, digits, '_' (and '.' when allowed); others become '_'. A leading non-letter gets a
/// "p" prefix; empty → "scan"; at most max_length characters.
std::string identifier(const std::string& name, bool allow_dot, std::size_t max_length);
/// Printable ASCII only (controllers' editors are not all UTF-8).
std::string commentText(const std::string& s);
std::string trim(const std::string& s);
/// A whole finite number (strtod), surrounding blanks allowed.
bool parseNumber(const std::string& text, double& value);

/// What each step (sample k ≥ 1, from sample k − 1) needs of the maximum speeds.
struct Step {
  double dt = 0.0;           // s
  double arm_percent = 0.0;  // of the limiting joint's maximum speed
  double percent = 0.0;      // the arm's or, when larger, the (known) table's
  int limiting = 0;          // 0-based joint, or kTable
  bool over_speed = false;
};

/// How a trigger switches at a sample: on at a pass's first sample, off at its last.
enum class Switch { kNone, kOn, kOff };

/// Everything a writer needs, computed once.
struct ProgramContext {
  const kinematics::Trajectory& trajectory;
  const kinematics::RobotModel& robot;
  const ProgramOptions& options;
  std::vector<Step> step;
  std::size_t over_speed = 0;
  std::vector<Switch> switches;   ///< per sample (all kNone without a trigger)
  std::vector<double> table_deg;  ///< per sample, as written (wrapped when endless)
  std::string name;               ///< the program's identifier in its language
};

std::vector<Step> steps(const kinematics::Trajectory& trajectory,
                        const kinematics::RobotModel& robot,
                        const ProgramOptions& options);
/// Per sample: kOn at the first sample of each run of scanning samples, kOff at its last (a run
/// of one sample gets kOn, and kOff at the next sample; a run that reaches the trajectory's end,
/// none: the program switches the output off after its motion). kNone everywhere without a
/// trigger output.
std::vector<Switch> triggerSwitches(const kinematics::Trajectory& trajectory,
                                    const ProgramTrigger& trigger);
/// Whether the last switch turns the output on (a pass runs to the end): the program then
/// switches it off after its motion; otherwise it is already off and is not switched again.
bool endsSwitchedOn(const ProgramContext& c);
/// The output's level after a switch: on_at_scan_start decides the polarity.
bool levelAfter(Switch s, const ProgramTrigger& trigger);
/// The table angles as written, degrees: within (-180, 180] when endless (each step must then
/// turn less than 180°: InputError otherwise), else as planned.
std::vector<double> writtenTable(const kinematics::Trajectory& trajectory, bool endless);

/// The percentage a language can set, rounded up to its resolution, at least one step, ≤ 100.
double roundedPercent(double percent, double resolution);
std::string warningText(std::size_t k, const Step& s);
/// "t=<s> s table=<deg> deg scan=<0|1>", the table angle as written.
std::string stepText(const kinematics::TrajectorySample& s, double table_deg);
std::string degrees(const kinematics::TrajectorySample& s, const std::string& separator);
/// The payload's two header lines (mass, centre of gravity; or that it is not set).
std::vector<std::string> payloadLines(const ProgramOptions& options, const std::string& how);
/// The trigger's header lines, `how` saying where the language switches it.
std::vector<std::string> triggerLines(const ProgramOptions& options, const std::string& how);
/// The table's header line(s) for an endless table, or none.
std::vector<std::string> endlessLines(const ProgramOptions& options, const std::string& axis);

/// The header every program starts with, one comment line per element (without the marker).
struct Header {
  std::vector<std::string> lines;

  Header(const ProgramContext& c, const std::string& capped);
  void add(const std::string& text) { lines.push_back(text); }
  void add(const std::vector<std::string>& more) {
    lines.insert(lines.end(), more.begin(), more.end());
  }
  std::string write(const std::string& marker) const;
};

// Rotations in each language's convention (angles in degrees) and back.
/// V+ TRANS(x, y, z, yaw, pitch, roll): R = Rz(yaw)·Ry(pitch)·Rz(roll).
Eigen::Vector3d vplusAngles(const Eigen::Matrix3d& R);
Eigen::Matrix3d fromVplusAngles(double yaw, double pitch, double roll);
/// KRL {A, B, C}: R = Rz(A)·Ry(B)·Rx(C).
Eigen::Vector3d krlAngles(const Eigen::Matrix3d& R);
Eigen::Matrix3d fromKrlAngles(double a, double b, double c);
/// URScript p[x, y, z, rx, ry, rz]: the rotation vector (radians).
Eigen::Vector3d rotationVector(const Eigen::Matrix3d& R);
Eigen::Matrix3d fromRotationVector(const Eigen::Vector3d& r);

/// A line-by-line reader whose errors name the source and the line.
class LineReader {
 public:
  static constexpr std::size_t kMaxLine = 1000;  // characters in a program line

  /// `text` must outlive the reader: lines are taken from it as they are read.
  LineReader(const std::string& text, const std::string& source);
  /// The next line, trimmed (false at the end); refuses a line over kMaxLine characters
  /// before any pattern sees it (std::regex recurses per character).
  bool next(std::string& line);
  [[noreturn]] void fail(const std::string& what) const;
  [[noreturn]] void failAt(int line, const std::string& what) const;
  int lineNumber() const { return line_number_; }
  const std::string& source() const { return source_; }

 private:
  const std::string& text_;
  std::size_t at_ = 0;
  int line_number_ = 0;
  const std::string& source_;
};

/// The numbers of a comma-separated list ("1, -2.5, 3e2"); fails naming `what` when one is not
/// a finite number or the count is not `expected`.
std::vector<double> numberList(const LineReader& in,
                               const std::string& list,
                               std::size_t expected,
                               const std::string& what);
/// A step comment's body "t=<s> s table=<deg> deg scan=<0|1>" (without the marker): sets
/// t, table (degrees) and scanning; false when the text is not a step comment.
bool readStepComment(
    const LineReader& in, const std::string& comment, double& t, double& table_deg, bool& scanning);
/// Appends a sample at time t with joints q (degrees) and table angle table_deg (unwrapped to
/// within 180° of the previous sample's), checking bounds and increasing times.
void appendSample(const LineReader& in,
                  kinematics::Trajectory& trajectory,
                  double t,
                  const std::vector<double>& q_deg,
                  double table_deg,
                  bool scanning);

// The writers and readers of each language.
std::string vplusProgram(const ProgramContext& c, const std::string& table_file);
std::string vplusTable(const ProgramContext& c);
std::string krlProgram(const ProgramContext& c);
/// The SCANPLAN_VEL routine krlProgram writes after the program (its reader compares it).
std::string krlVelocityRoutine();
std::string rapidProgram(const ProgramContext& c);
std::string urscriptProgram(const ProgramContext& c);
/// URScript's seg(a, d), which plays one row of the program's data (write_urscript.cpp), and
/// the step after the last row: the writer writes them and the reader accepts only these.
std::string urscriptStepFunction(double period, int output);
std::string urscriptLastStep(double period);
ProgramReading readVplus(const std::string& text,
                         const std::string& source,
                         const kinematics::RobotModel* robot);
ProgramReading readKrl(const std::string& text, const std::string& source);
ProgramReading readRapid(const std::string& text, const std::string& source);
ProgramReading readUrscript(const std::string& text, const std::string& source);

/// `text` in 7-bit ASCII: controllers read their programs in their own code page (a KUKA
/// controller in Windows-1252, where UTF-8's "·" shows as "Â·"). The symbols the headers and
/// comments use become ASCII words ("·" → "*", "°" → " deg", "…" → "...", "±" → "+/-", "−" → "-",
/// "×" → "x", "²" → "^2", "→" → "->", "≤" → "<=", "≥" → ">="); any other non-ASCII character
/// becomes "?".
std::string asciiText(const std::string& text);

}  // namespace scanplan::programs::detail
