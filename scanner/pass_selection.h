#pragma once
// Choosing and ordering scan passes (docs/design.md §11): a greedy weighted set cover of the area
// samples (new area per second of scanning), then a tour through the chosen passes, each run
// either way, that keeps the connecting moves short (nearest neighbour, then 2-opt), and the
// connecting moves themselves: out to a safe sphere around the part, along it, and in.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include <scanplan/scanner/scan_passes.h>

namespace scanplan::scanner {

struct CoverSettings {
  double target = 0.98;          ///< of the samples that count
  std::size_t max_passes = 250;  ///< passes chosen at most
  double pass_overhead = 3.0;    ///< s added to a pass's time in its gain (its approach)
  std::size_t min_gain = 1;      ///< samples: stop when the best pass adds fewer
};

struct CoverResult {
  std::vector<std::size_t> chosen;    ///< pass indices, in the order chosen
  std::vector<std::size_t> rejected;  ///< passes the filter refused
  std::vector<std::uint8_t> covered;  ///< per sample
  std::size_t counted = 0;            ///< samples that count
  std::size_t covered_counted = 0;    ///< of those, covered
  std::string stop;                   ///< "target reached", "no gain", "max_passes", "stopped"
};

/// Lazy greedy set cover: repeatedly the pass with the most newly covered counting samples per
/// second (duration + overhead), until `target` of the counting samples are covered, no pass
/// adds min_gain, max_passes are chosen or `keep_going` says stop. `accept` is asked once per
/// pass before it is chosen (e.g. a reachability check); refused passes are never asked again.
/// `counts[i]`: sample i counts toward the target; `covered`: samples covered before any pass.
CoverResult greedyCover(const std::vector<ScanPass>& passes,
                        const std::vector<std::uint8_t>& counts,
                        std::vector<std::uint8_t> covered,
                        const CoverSettings& settings,
                        const std::function<bool(std::size_t)>& accept = {},
                        const std::function<bool()>& keep_going = {});

/// The chosen passes cut down to what the cover needs of them (cutToCover()).
struct CutPasses {
  std::vector<ScanPass> passes;   ///< the pieces, in the order of `chosen`
  std::vector<std::size_t> from;  ///< per piece, the chosen pass it was cut from
  double cut_time = 0.0;          ///< s of scanning left out
  std::size_t dropped = 0;        ///< chosen passes that added nothing the others lack
  std::size_t split = 0;          ///< extra pieces (passes split where a stretch adds nothing)
};

/// Cuts each chosen pass (longest first) to the stretches that cover a counting sample no other
/// chosen pass (as cut so far) covers: the shortest run of stretches holding, for each such
/// sample, its first or last covering stretch (ScanPass::cover_first); a pass that covers no
/// such sample is left out; a pass is split in two where a run of `split_gap` s or more between
/// those samples adds nothing (a move then skips it). The counting samples the chosen passes
/// cover, and that `covered` does not already hold, stay covered (as far as those stretches
/// tell). Each piece runs `pad` s longer at either end where the pass does: a sample stands for
/// the area around it, which the profiles after the one that found it finish. Passes without
/// stretch records are kept whole. Deterministic.
CutPasses cutToCover(const std::vector<ScanPass>& passes,
                     const std::vector<std::size_t>& chosen,
                     const std::vector<std::uint8_t>& counts,
                     const std::vector<std::uint8_t>& covered,
                     double split_gap,
                     double pad = 0.0);

/// The passes kept when whole passes are left out while at least `goal` (a fraction) of the
/// counting samples (`counts`) stay covered: each time the pass whose own samples (those no other
/// kept pass covers) are fewest per second of its `cost` (s, > 0; a pass of no cost is kept), ties
/// to the first. For a selection that covers more than it needs: the tail of a cover judged on
/// finer samples than it was chosen on. Indices ascending. Deterministic.
std::vector<std::size_t> pruneToGoal(const std::vector<ScanPass>& passes,
                                     const std::vector<double>& cost,
                                     const std::vector<std::uint8_t>& counts,
                                     double goal);

/// The safe sphere the connecting moves run on (R frame): no part of the head inside it can
/// touch the part.
struct TransferSphere {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  double radius = 0.3;      ///< m
  double speed = 0.1;       ///< m/s
  double turn_speed = 0.5;  ///< rad/s of head rotation
};

/// A timed move of the head (R frame): keys and their times from the start of the move.
struct Move {
  std::vector<Eigen::Isometry3d> X_RS;
  std::vector<double> t;
};

/// The move from `from` to `to`: straight back along the laser (−z_S, holding the head still)
/// out to the sphere, along it (azimuth, elevation and radius about its centre interpolated, the
/// head turning with the azimuth and evenly besides), and in along the laser of `to`. Its speed
/// keeps within `speed` and `turn_speed`. Starts at `from` (t = 0) and ends at `to`.
Move transferMove(const Eigen::Isometry3d& from,
                  const Eigen::Isometry3d& to,
                  const TransferSphere& sphere);
/// The first leg of transferMove() from X (and, run backwards, the last into X): X backed off
/// along its laser to the sphere, a key every `step` m or less, X first.
std::vector<Eigen::Isometry3d> backOffLeg(const Eigen::Isometry3d& X,
                                          const TransferSphere& sphere,
                                          double step);
/// The duration of transferMove(), s, without building it.
double transferTime(const Eigen::Isometry3d& from,
                    const Eigen::Isometry3d& to,
                    const TransferSphere& sphere);

/// One step of a tour: a pass, run backwards or not; a spin turned to start where the head is.
struct TourStep {
  std::size_t pass = 0;
  bool reversed = false;
  double turn = 0.0;  ///< rad about R's z applied to a spin (rotatedPass)
};

/// Orders `chosen` (indices into passes) to keep the transfers short: nearest neighbour from
/// `start` (or from up to 12 first passes, the best kept), then 2-opt moves that reverse a stretch
/// of the tour (and each pass in it), judging 2·10⁷ transfers at most. Deterministic.
std::vector<TourStep> orderPasses(const std::vector<ScanPass>& passes,
                                  const std::vector<std::size_t>& chosen,
                                  const std::optional<Eigen::Isometry3d>& start,
                                  const TransferSphere& sphere);

/// The pass of a step as it is run: turned and reversed (times restart at 0).
ScanPass stepPass(const std::vector<ScanPass>& passes, const TourStep& step);

/// Total transfer time of a tour from `start`, s.
double tourTransferTime(const std::vector<ScanPass>& passes,
                        const std::vector<TourStep>& tour,
                        const std::optional<Eigen::Isometry3d>& start,
                        const TransferSphere& sphere);

}  // namespace scanplan::scanner
