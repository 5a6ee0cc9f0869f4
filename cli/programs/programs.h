#pragma once
// Robot programs (DESIGN.md §7): a planned trajectory written for the controller that runs it —
// Adept V+, KUKA KRL, ABB RAPID, URScript — or as the CSV interchange file, and the V+ program
// read back into a trajectory so that it can be validated before it is sent (§7.3).

#include <cstddef>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "kinematics/robot_model.h"
#include "kinematics/trajectory.h"

namespace scanplan::cli {

enum class ProgramFormat { kCsv, kVplus, kKrl, kRapid, kUrscript };

/// "csv", "vplus", "krl", "rapid", "urscript" (the CLI's names, in this order).
const std::vector<std::string>& programFormatNames();
std::string programFormatName(ProgramFormat format);
/// One of programFormatNames(), case-insensitive; nullopt otherwise.
std::optional<ProgramFormat> parseProgramFormat(const std::string& name);

struct ProgramOptions {
  /// The program name, made a valid identifier of each language (and the file names): V+
  /// lower case [a-z0-9._], ≤ 15 characters; KRL [A-Za-z0-9_], ≤ 24; RAPID ≤ 28 (the module is
  /// MOD_<name>); URScript [A-Za-z0-9_]. A leading digit gets a "p" prefix; empty → "scan".
  std::string name = "scan";
  /// The job's name, for the header comment only (may be empty).
  std::string job;
  /// %, the speed of the first move (from wherever the arm is to the first sample), which is not
  /// timed: V+ SPEED, KRL $VEL_AXIS (and E1), URScript movej v = this share of the slowest
  /// joint's maximum speed. RAPID uses v100. (0, 100].
  double approach_speed_percent = 10.0;
  /// rad/s, the table's maximum speed; ≤ 0: unknown. When known, the table takes part in the
  /// speed check, and KRL's E1 velocity is set with the arm's (the table may lead a PTP).
  double table_max_speed = 0.0;
  /// V+ only: a digital output that the program turns on as the timed motion starts, for the
  /// table controller to start playing the table list; 0: none (the integrator adds the
  /// start trigger).
  int vplus_table_start_signal = 0;
};

/// The written program: its files (the first is the program itself) and what the speed check
/// found.
struct ProgramFiles {
  std::vector<std::pair<std::string, std::string>> files;  ///< file name, content
  /// Steps after the first whose planned time would need more than 100 % of a joint's (or the
  /// known table's) maximum speed: each is marked by a WARNING comment in the program, and runs
  /// slower than planned. Counted for every format (the CSV has no comments).
  std::size_t over_speed_segments = 0;
  /// %, the largest speed any step needs, over the joints (and the table when known); 0 for a
  /// single sample.
  double max_speed_percent = 0.0;
};

/// Writes `trajectory` for `robot`'s controller: one joint move per sample, each timed as
/// planned as closely as the language allows (the first is the untimed move to the start).
/// Joints, table angles and times with 6 decimals (degrees, s; URScript's joints in radians with
/// 9); t, the table angle and the scanning flag in every step's comment. Each program's header says
/// how its timing and its table are done:
///
/// - kCsv: <name>.csv, kinematics::trajectoryToCsv() (12 significant digits).
/// - kVplus: <name>.v2 (.PROGRAM/.END, MOVE #PPOINT(j1..j6) per step, SPEED in % rounded up to
///   0.01 from the step's limiting joint, DURATION = the step's planned time, monitor speed 100
///   assumed) and <name>_table.csv (t_s,table_deg,scanning) for the table controller: V+ has no
///   rotary-table axis. The start configuration's words (RIGHTY ABOVE NOFLIP) come first.
/// - kKrl: <name>.src, PTP {A1..A6, E1} C_PTP with the table as E1 (degrees, unwrapped) and
///   $VEL_AXIS (whole %, rounded up) set per step from the limiting joint.
/// - kRapid: <name>.mod, MoveAbsJ with the table in eax_a (degrees, unwrapped), the unused
///   external axes 9E9, speeddata v1000 \T:= the step's planned time.
/// - kUrscript: <name>.script, movej(q rad, t = the step's time, r = 0), the table through the
///   table_start()/table_move() functions the integrator implements (UR has no external axis).
///
/// Joint values are the robot file's q, which the bundled robots define as their controllers'
/// own joint convention. Joint limits and collisions are not checked here: validate first.
/// Throws InputError for an empty trajectory, non-finite values, times not strictly increasing
/// or an approach speed outside (0, 100].
ProgramFiles writeProgram(const kinematics::Trajectory& trajectory,
                          const kinematics::RobotModel& robot,
                          ProgramFormat format,
                          const ProgramOptions& options = {});

/// Reads a V+ program written by writeProgram(kVplus) (or edited by hand in its form): every
/// `MOVE #PPOINT(j1, …, j6)` (degrees) is one sample, its time, table angle and scanning flag
/// from the `; t=<s> s table=<deg> deg scan=<0|1>` comment before it. f is NaN (unknown), X_PS
/// the identity (unknown), limit empty: what validation needs is t, theta and q. Comments,
/// SPEED, DURATION, BREAK, SIGNAL and the configuration words are accepted and ignored.
/// Errors (InputError) name `source` and the line: no .PROGRAM or .END, an unknown or malformed
/// instruction, a MOVE without its step comment, times not strictly increasing, no moves.
kinematics::Trajectory readVplusProgram(const std::string& text, const std::string& source);

}  // namespace scanplan::cli
