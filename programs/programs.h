#pragma once
// Robot programs (docs/design.md §7): a planned trajectory written for the controller that runs it
// — Adept V+, KUKA KRL, ABB RAPID, URScript — or as the CSV interchange file, and every program
// read back into a trajectory so that it can be validated before it is sent (§7.3).

#include <cstddef>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include <scanplan/kinematics/robot_model.h>
#include <scanplan/kinematics/trajectory.h>

namespace scanplan::programs {

enum class ProgramFormat { kCsv, kVplus, kKrl, kRapid, kUrscript };

/// "csv", "vplus", "krl", "rapid", "urscript" (the CLI's names, in this order).
const std::vector<std::string>& programFormatNames();
std::string programFormatName(ProgramFormat format);
/// One of programFormatNames(), case-insensitive; nullopt otherwise.
std::optional<ProgramFormat> parseProgramFormat(const std::string& name);

/// The scanner trigger: a digital output switched exactly at each scan pass's start and end.
struct ProgramTrigger {
  int output = 0;  ///< the digital output's number (V+ SIGNAL, KRL $OUT, URScript); 0: none
  /// RAPID's signal name (RAPID names its signals); empty: "do<output>".
  std::string rapid_signal;
  /// true: on while scanning (on at a pass's start, off at its end); false: the reverse.
  bool on_at_scan_start = true;
};

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
  /// The tool (TCP) on the flange: the scanner's laser frame X_FS, m. V+ TOOL, KRL $TOOL,
  /// RAPID tooldata, URScript set_tcp.
  Eigen::Isometry3d tool = Eigen::Isometry3d::Identity();
  /// kg, the scanner's mass; ≤ 0: unknown (no payload is set, and the header says so).
  double payload_kg = 0.0;
  /// m, the scanner's centre of gravity in the flange frame. KRL $LOAD, RAPID tload, URScript
  /// set_target_payload; a comment in V+ (its PAYLOAD instruction is a percentage, on some arms
  /// only).
  Eigen::Vector3d payload_cog = Eigen::Vector3d::Zero();
  ProgramTrigger trigger;
  /// The table is an endless axis: its angles are written within (-180, 180] and the
  /// controller turns it the shorter way between steps (each step turns less than 180°).
  /// false: the planned angles as they are (a limited table stays within its limits).
  bool table_endless = false;
  /// s, URScript's servoj period: the controller's (0.008 on CB3, 0.002 on e-Series).
  double servo_period = 0.008;
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

/// Writes `trajectory` for `robot`'s controller, timed as planned in the language's own timing
/// model (the first move, to the start, is not timed). Joints, table angles and times with 6
/// decimals (degrees, s; URScript's joints in radians with 9); t, the table angle and the
/// scanning flag in every step's comment. Every program sets the tool (options.tool) and,
/// when known, the payload, switches the trigger output (when set) exactly at each pass's
/// first and last sample, and says in its header how its timing, trigger and table are done:
///
/// - kCsv: <name>.csv, kinematics::trajectoryToCsv() (12 significant digits).
/// - kVplus: <name>.v2 (.PROGRAM/.END, TOOL TRANS, MOVE #PPOINT(j1..j6) per step, SPEED in %
///   rounded up to 0.01 from the step's limiting joint, DURATION = the step's planned time,
///   monitor speed 100 assumed; SIGNAL n / -n after the MOVE that leaves the sample, which V+
///   runs as that move starts) and <name>_table.csv (t_s,table_deg,scanning) for the table
///   controller: V+ has no rotary-table axis. The start configuration's words come first.
/// - kKrl: <name>.src: $TOOL, $LOAD, the approach PTP, then PTP_SPLINE blocks of SPTP
///   {A1..A6, E1} segments (at most kKrlMaxSegments, split between scan passes) timed by
///   TIME_BLOCK (PART = each step's share, END = the block's planned time); the trigger by
///   TRIGGER WHEN PATH=0 before the segment that ends at the pass's sample.
/// - kRapid: <name>.mod, PERS tooldata with the payload as tload, PROC main() calling the scan
///   procedure, MoveAbsJ with the table in eax_a and \T:= the step's planned time, zone z0;
///   SetDO after the MoveAbsJ that reaches the pass's sample, which RAPID runs as the arm
///   enters that point's z0 zone.
/// - kUrscript: <name>.script, `def <name>(): … end` and then `<name>()`, which runs it;
///   set_tcp/set_target_payload, movej to the start, then one data row per planned sample,
///   `a = seg(a, [t, table, j1..j6, scan, out])`, which servoj's every options.servo_period
///   along the joint-linear path from the previous row (continuous motion) and switches
///   set_standard_digital_out where the row's output level changes; the table through
///   table_start()/table_move(), which the integrator implements (UR has no external axis).
///   At most kUrscriptMaxBytes: a longer program is refused (InputError).
///
/// Joint values are the robot file's q, which the bundled robots define as their controllers'
/// own joint convention. Joint limits and collisions are not checked here: validate first.
/// Throws InputError for an empty trajectory, non-finite values, times not strictly increasing,
/// an approach speed outside (0, 100], a trigger output outside 0..4096, a non-finite tool or
/// payload, a servo period outside [0.001, 0.1] s, (endless table) a step of 180° or more, or a
/// URScript program over kUrscriptMaxBytes.
ProgramFiles writeProgram(const kinematics::Trajectory& trajectory,
                          const kinematics::RobotModel& robot,
                          ProgramFormat format,
                          const ProgramOptions& options = {});

/// The files writeProgram() writes, in every format, for a program named `name` (the names as
/// each language makes them valid): what a command that writes programs owns in its folder.
std::vector<std::string> programFileNames(const std::string& name);

/// URScript: the largest program written, bytes. UR controllers have failed to load scripts of
/// several megabytes (an 18 MB one crashed a UR5 on import); at about 130 bytes per planned
/// sample this holds some 7 500 samples, a 25-minute scan at 0.2 s.
inline constexpr std::size_t kUrscriptMaxBytes = 1'000'000;

/// KRL: the most SPTP segments one PTP_SPLINE block holds.
inline constexpr std::size_t kKrlMaxSegments = 1000;

/// A trigger switch read back from a program: at time t (s, the language's timing), on or off.
struct TriggerSwitch {
  double t = 0.0;
  int output = 0;  ///< the output's number (RAPID: the number in the signal's name, or 0)
  bool on = false;
};

/// A program read back: the motion as the controller would run it, timed by the language's own
/// timing model (V+ DURATION, KRL TIME_BLOCK, RAPID \T, URScript servoj t), from the first
/// sample's time in its step comment (0 without one). Table angles are unwrapped (each step the
/// shorter way: what an endless axis does); the scanning flag comes from the step comments
/// (URScript: its data rows) and holds until the next one (URScript's servo steps between samples).
/// f is NaN and X_PS the identity (unknown).
struct ProgramReading {
  kinematics::Trajectory trajectory;
  std::vector<TriggerSwitch> triggers;
  std::optional<Eigen::Isometry3d> tool;  ///< the tool the program sets (flange frame, m)
  double payload_kg = 0.0;                ///< 0: none set
  Eigen::Vector3d payload_cog = Eigen::Vector3d::Zero();  ///< m, flange frame
  /// The planned samples' times: the step comments' (URScript: its data rows', between which its
  /// servo steps lie).
  std::vector<double> step_times;
  bool servo_steps = false;  ///< the samples are servo steps between the step times (URScript)
};

/// The reading at its step comments' times when its samples are servo steps (URScript): the
/// motion interpolated linearly between them, so that it is checked at the plan's own resolution
/// (a piecewise-linear table read at the servo period shows its kinks as accelerations 12× those
/// at the plan's step). Other readings are returned as they are.
kinematics::Trajectory atStepTimes(const ProgramReading& reading);

/// Reads a program written by writeProgram(format) (or edited by hand in its form; kCsv: the
/// trajectory CSV). A reader models or refuses every statement that changes motion or timing,
/// so that what it returns is what the controller runs:
/// - V+: a MOVE takes the longer of its DURATION and its time at SPEED s % (the largest
///   |Δq_j| / (s/100 · robot.joint(j).max_speed), monitor speed 100 assumed). SPEED holds for
///   the next MOVE only, SPEED ... ALWAYS for every MOVE after it (default 100). A SPEED that
///   makes a move outlast its DURATION (beyond 1e-3 of it + 1e-6 s, the printed rounding) is
///   refused, naming the MOVE's line and the SPEED's. Without `robot` (a library caller with no
///   robot) SPEED is checked for its form and range only and the DURATIONs time the moves.
///   Refused: a MOVE without DURATION, DURATION ALWAYS, SPEED in MMPS or outside (0, 100], a
///   BREAK between timed moves (the arm would stop), CALL, WAIT, DELAY and any other
///   instruction, anything but comments after .END.
/// - KRL: SCANPLAN_VEL(arm %, E1 %) (each 1 ... 100) is kept, and every timed PTP_SPLINE block
///   must start under SCANPLAN_VEL(100, 100); the text after the program's END must be the
///   SCANPLAN_VEL routine writeProgram writes (line by line, comments and blank lines aside).
///   Refused: SCANPLAN_VEL inside a block, BAS other than BAS(#INITMOV,0) before the first
///   motion, a PTP after the first (untimed) one, loops, waits (but WAIT SEC 0), other calls.
/// - RAPID: PROC main() holds exactly one call, to the module's only other procedure, which
///   holds every MoveAbsJ and SetDO. Refused: a second call (naming both lines), no call, no
///   main(), moves in main() or outside a procedure, any other procedure or call, a MoveAbsJ
///   after the first without \\T, a zone other than z0 (fine only on the first and the last
///   MoveAbsJ: the arm stops there).
/// - URScript: only the seg() and last step writeProgram writes, compared line by line.
/// `robot` is read by the V+ reader alone. Errors (InputError) name `source` and the line: an
/// instruction the reader does not know, malformed values, a move without its step comment (V+:
/// the table angle is only there), times not strictly increasing, no moves.
ProgramReading readProgram(const std::string& text,
                           ProgramFormat format,
                           const std::string& source,
                           const kinematics::RobotModel* robot = nullptr);

/// The format of a program file from its extension (.v2, .src, .mod, .script, .csv).
std::optional<ProgramFormat> programFormatOfFile(const std::string& file_name);

/// readProgram(text, kVplus, source, robot).trajectory.
kinematics::Trajectory readVplusProgram(const std::string& text,
                                        const std::string& source,
                                        const kinematics::RobotModel* robot = nullptr);

}  // namespace scanplan::programs
