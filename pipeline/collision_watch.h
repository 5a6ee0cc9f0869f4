#pragma once
// Predictive collision watch (seed §7.3): a stream of measured arm and table positions goes in,
// one sample at a time; the motion is fitted (Eq. 9 or Eq. 10, kinematics/motion_model.h) over a
// sliding window and extrapolated over a horizon, and the predicted poses are checked against
// the cell with the clearance code. A pair is reported only while the bodies are getting closer
// (the seed: "warnings should be given only when two possibly colliding bodies become closer").

#include <optional>
#include <vector>

#include <Eigen/Geometry>

#include <scanplan/collision/clearance.h>
#include <scanplan/collision/scene.h>
#include <scanplan/kinematics/motion_model.h>

namespace scanplan::pipeline {

struct WatchOptions {
  std::size_t window = 25;      ///< samples the motion is fitted on (0.1 s at 250 Hz), ≥ 3
  double horizon = 1.0;         ///< s predicted ahead
  double step = 0.02;           ///< s between predicted poses
  double warn_distance = 0.02;  ///< m: a pair getting closer than this within the horizon warns
  /// m: a pair getting closer than this within stop_time calls for a stop; negative: never.
  double stop_distance = -1.0;
  double stop_time = 0.2;  ///< s: how far ahead a stop distance breach calls for a stop
  kinematics::MotionModelOptions model;
  /// Measure each pair only below the distance that matters (the larger of the warning and
  /// stop distances); false: every pair's exact distance at every predicted pose, the
  /// straightforward reference of the benchmark. The warnings are the same either way.
  bool bounded = true;
};

/// One body pair that is getting closer and is predicted within the warning distance, or that is
/// in contact now and still in contact at the next predicted pose.
struct WatchWarning {
  int pair = -1;                          ///< index into Scene::pairs()
  double distance_now = 0.0;              ///< m; ≥ the warning distance when `far_now`
  bool far_now = false;                   ///< now beyond the distance measured (the bound)
  double closest = 0.0;                   ///< m, the least predicted distance
  double time_to_closest = 0.0;           ///< s from the sample to that least distance
  std::optional<double> time_to_contact;  ///< s, when predicted to touch within the horizon
  bool stop = false;                      ///< below the stop distance within stop_time
};

/// What the watch concluded at one sample.
struct WatchStep {
  double t = 0.0;  ///< s, the sample's time
  kinematics::MotionFit fit;
  double predicted = 0.0;  ///< s actually predicted: less than the horizon when the motion
                           ///< leaves the arm's reach or limits, or bodies touch
  std::vector<WatchWarning> warnings;
  bool stop = false;  ///< some warning calls for a stop
};

/// The watch over one cell. Holds the window and per-thread scratch: one per stream. The scene
/// must outlive it.
class CollisionWatch {
 public:
  /// X_FT: the tool frame on the flange (m), the frame Eq. 10 moves on a line. Throws
  /// std::invalid_argument for options out of range (window < 3, non-positive horizon or step).
  CollisionWatch(const collision::Scene& scene,
                 const Eigen::Isometry3d& X_FT,
                 const WatchOptions& options = {});

  /// Takes the next measured sample (times strictly increasing, values finite; else
  /// std::invalid_argument) and predicts from the window ending with it. Angles may come
  /// wrapped (an endless table reported within ±180°): each axis is taken at the whole turn
  /// nearest the previous sample.
  WatchStep push(const kinematics::AxisSample& sample);

 private:
  struct Prediction;
  Prediction predictAhead(const kinematics::MotionFit& fit);
  double contactTime(const kinematics::MotionFit& fit, double before, double at);

  const collision::Scene* scene_;
  WatchOptions options_;
  kinematics::MotionModel model_;
  collision::ClearanceEvaluator evaluator_;
  std::vector<kinematics::AxisSample> window_;
};

}  // namespace scanplan::pipeline
