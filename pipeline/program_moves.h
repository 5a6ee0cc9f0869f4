#pragma once
// The moves between the segments of a scan (ScanPath::breaks: the automatic scan's passes): each
// a point-to-point move of all seven axes at the robot's and the table's own speed and
// acceleration limits (kinematics/ptp_move.h), checked against the cell at every step. Where the
// direct move is blocked the head backs off along its laser at one end or both, only as far as
// needed.

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include <scanplan/collision/scene.h>
#include <scanplan/kinematics/cell.h>
#include <scanplan/kinematics/ptp_move.h>
#include <scanplan/kinematics/trajectory.h>

namespace scanplan::pipeline {

/// Moves joinSegments() planned, for later joins of the same scene with the same settings: a
/// move whose both ends (every axis; the table's up to whole turns when it turns without end) and
/// speeds there are the same is taken from here, so a join of the same passes in another order
/// plans only the moves that are new. Joins may share it from several threads: each move is
/// planned once.
class MoveCache {
 public:
  MoveCache();
  ~MoveCache();
  MoveCache(const MoveCache&) = delete;
  MoveCache& operator=(const MoveCache&) = delete;
  std::size_t size() const;
  struct Impl;
  Impl& impl() { return *impl_; }

 private:
  std::unique_ptr<Impl> impl_;
};

/// How the moves are made.
struct MoveSettings {
  /// Share of each axis's speed and acceleration limit a move may use (a margin for the
  /// controller's own profile). In (0, 1].
  double speed_scale = 0.95;
  /// s, a joint without an acceleration limit reaches its full speed in this time.
  double accel_time = 0.25;
  /// s, the longest step between the samples of a move (the programs' points).
  double max_step = 0.1;
  /// Back-off distances tried, in order, when the direct move is blocked, m.
  std::vector<double> retreats{0.02, 0.05, 0.1, 0.15, 0.25};
  /// Also try backing off at one end only (either end): where the other end is clear, the move
  /// then stops once less on its way. False: both ends always.
  bool one_sided = true;
  /// rad, the largest change of any axis between two poses at which the clearance is checked
  /// (nearer the cell the poses lie closer: at most half the distance to the nearest pair's
  /// d_low of motion apart).
  double check_step = 0.02;
  /// The head above the part (part frame, laser pointing down): the last resort of a blocked
  /// move goes up there and across. Unset: no such detour.
  std::optional<Eigen::Isometry3d> above;
  /// m, the farthest point the table carries from its axis (the part): with the links' lengths
  /// it bounds how fast the cell's points move, which spaces the checked poses.
  double part_reach = 0.0;
  /// Polled at every leg of every move tried: once set, joinSegments() throws Cancelled
  /// (pipeline/cancel.h). nullptr: never.
  const std::atomic<bool>* cancel = nullptr;
  /// Moves planned before, reused (and the new ones added). nullptr: none.
  MoveCache* cache = nullptr;
};

/// The program's time split.
struct ProgramTimes {
  double total = 0.0;       ///< s, the whole program
  double scanning = 0.0;    ///< s, intervals whose both ends scan
  double moving = 0.0;      ///< s, the rest: moves between passes (and stretches that do not scan)
  std::size_t moves = 0;    ///< moves between segments
  std::size_t detours = 0;  ///< of them, backed off because the direct move was blocked
  /// Passes whose table path was shifted to start where the table stood after the pass before
  /// (the moves into and out of them then shorter). Set by planScan().
  std::size_t held = 0;
  double held_cost = 0.0;  ///< s, what holding them added to the objective J (summed)
  /// s of the moves' time by the axis that set it (kinematics::ptpTimeByAxis(): 0 the table,
  /// 1…6 joints 1…6); sums to the moves' time. Set by joinSegments().
  kinematics::AxisVector moving_by_axis = kinematics::AxisVector::Zero();
};

/// The segments joined into one program.
struct JoinedProgram {
  kinematics::Trajectory trajectory;  ///< program time from 0
  ProgramTimes times;
  /// Segments left out because no move reaches them (index into the input, reason).
  std::vector<std::pair<std::size_t, std::string>> dropped;
  /// Per input segment: the time its first sample runs at in the program (NaN when dropped).
  std::vector<double> start_times;
  /// Per input segment: 1 when it runs backwards (put off to the end and reached that way).
  std::vector<std::uint8_t> flipped;
  /// The moves as made: into segment `to` from the end of segment `from` (input indices), s.
  struct Made {
    std::size_t from = 0, to = 0;
    double duration = 0.0;
  };
  std::vector<Made> made;
};

/// An order to run segments in: `order[k]` runs k-th, backwards when `reversed[k]`.
struct SegmentOrder {
  std::vector<std::size_t> order;
  std::vector<std::uint8_t> reversed;
  bool operator==(const SegmentOrder&) const = default;
};

/// A move's time as measured (joinSegments()): from the end of segment `from` (run backwards
/// when `from_reversed`) to the start of `to`, s. It stands for ptpDuration()'s estimate, and
/// for the same move run the other way.
struct KnownMove {
  std::size_t from = 0, to = 0;
  bool from_reversed = false, to_reversed = false;
  double duration = 0.0;
};

/// The order that keeps the moves between `segments` short, each costed by ptpDuration() from
/// one segment's end (at its end speed) to the next one's start (at its start speed), the table
/// a whole turn the shorter way round when it turns without end. The first `fixed` segments run
/// first, in order and forwards (hand-written paths); every other one may run either way (a pass
/// run backwards covers what it covers forwards). Nearest neighbour from up to 12 first
/// segments, then, in turn until neither shortens it, 2-opt (reversing a stretch of the tour and
/// every segment in it) and Or-opt (a chain of one to three segments put in elsewhere, either way
/// round; 2-opt alone when not `or_opt`). Deterministic.
SegmentOrder orderSegments(const kinematics::CellModel& cell,
                           const std::vector<kinematics::Trajectory>& segments,
                           std::size_t fixed,
                           const MoveSettings& settings = {},
                           bool or_opt = true);

/// orderSegments()'s 2-opt and Or-opt from `start` (a permutation of the segments whose first
/// `fixed` run first, forwards), with the moves in `known` costed at their measured time (a
/// move that had to back off then costs what it took) and every other at its estimate plus the
/// known moves' mean excess over theirs (it may have to back off too). Deterministic.
SegmentOrder reorderSegments(const kinematics::CellModel& cell,
                             const std::vector<kinematics::Trajectory>& segments,
                             std::size_t fixed,
                             const SegmentOrder& start,
                             const std::vector<KnownMove>& known,
                             const MoveSettings& settings = {});

/// The time orderSegments() costs the move from the end of `from` (at its end speed) to the start
/// of `to` (at its start speed) at: ptpDuration() under the moves' limits, the table the shorter
/// way round when it turns without end. Both non-empty.
double moveCost(const kinematics::CellModel& cell,
                const kinematics::Trajectory& from,
                const kinematics::Trajectory& to,
                const MoveSettings& settings = {});

/// A segment run backwards: the same poses in reverse order over the same times.
kinematics::Trajectory reversedSegment(const kinematics::Trajectory& segment);

/// Joins `segments` (each a trajectory with its own times, on the path's time axis) into one
/// program: a table that turns without end is unwound by whole turns to the nearest equivalent,
/// a joint whose range exceeds a turn likewise where the whole segment stays in its limits; then
/// a move from each segment's end (at its end speed) to the next one's start (at its start
/// speed). A move whose every checked pose keeps each pair of the cell beyond its d_low is taken;
/// else the head backs off along −z_S by one of MoveSettings::retreats at one end or at both
/// (inverse kinematics nearest the end poses), the fastest such move whose poses are clear (each
/// way checked at its samples first, then between them), else it goes via
/// MoveSettings::above. A segment no move
/// reaches is put off (the next one is tried from the same end) and tried again at the end of the
/// program, forwards and then backwards; it is dropped only when neither is reached. The first
/// segment is never dropped. The moves are planned in parallel (TBB); the result does not depend on
/// threads.
JoinedProgram joinSegments(const collision::Scene& scene,
                           const std::vector<kinematics::Trajectory>& segments,
                           const MoveSettings& settings = {});

/// The segment slowed down evenly, where needed, so that no joint and not the table turns
/// faster than `speed_scale` of its limit between two samples (a pass too fast for the arm at
/// some point runs slower as a whole: its points only get denser). Returns the factor its
/// duration grew by (1: unchanged).
double slowToLimits(const kinematics::CellModel& cell,
                    kinematics::Trajectory& segment,
                    double speed_scale = 0.98);

/// The segment run in `duration` s (it spans that or more: the path's samples stand whole time
/// steps apart), evenly, where each joint's and the table's speed and the table's acceleration
/// stay within `speed_scale` of their limits (and each joint's acceleration within its limit
/// where it was before); else as near that time as they allow. A segment already faster than
/// `speed_scale` of a speed limit is slowed to it as slowToLimits() does. A pass then runs at
/// the speed it was planned for. Returns the factor its duration changed by (< 1: faster).
double retimeSegment(const kinematics::CellModel& cell,
                     kinematics::Trajectory& segment,
                     double duration,
                     double speed_scale = 0.98);

/// The program's time split of a trajectory.
ProgramTimes programTimes(const kinematics::Trajectory& trajectory);

}  // namespace scanplan::pipeline
