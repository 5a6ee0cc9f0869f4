#include <scanplan/kinematics/motion_model.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/SVD>

#include <scanplan/kinematics/joint_wrap.h>

namespace scanplan::kinematics {
namespace {

using Rows = Eigen::Matrix<double, Eigen::Dynamic, 7>;

struct RankOne {
  MotionVector direction = MotionVector::Zero();
  Eigen::VectorXd sigma;  ///< each row's path parameter along `direction`
  double travel = 0.0;    ///< the largest row norm
};

// The least-squares rank-one fit through the origin: rows ≈ σ · directionᵀ. The direction is the
// first right singular vector; it is turned so that the newest row lies ahead.
RankOne rankOne(const Rows& rows) {
  RankOne out;
  out.sigma = Eigen::VectorXd::Zero(rows.rows());
  for (Eigen::Index k = 0; k < rows.rows(); ++k)
    out.travel = std::max(out.travel, rows.row(k).norm());
  if (out.travel == 0.0) return out;
  const Eigen::JacobiSVD<Rows> svd(rows, Eigen::ComputeThinV);
  out.direction = svd.matrixV().col(0);
  out.sigma = rows * out.direction;
  if (out.sigma(out.sigma.size() - 1) < 0.0) {
    out.direction = -out.direction;
    out.sigma = -out.sigma;
  }
  return out;
}

Eigen::Vector3d rotationVector(const Eigen::Matrix3d& R) {
  const Eigen::AngleAxisd aa(R);
  return aa.angle() * aa.axis();
}

Eigen::Matrix3d rotationOf(const Eigen::Vector3d& v) {
  const double angle = v.norm();
  if (angle == 0.0) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(angle, v / angle).toRotationMatrix();
}

// The speed factor now: the slope of σ over time on the newest `count` samples (least squares).
double speedAtEnd(std::span<const AxisSample> window,
                  const Eigen::VectorXd& sigma,
                  std::size_t count) {
  const std::size_t n = window.size();
  const std::size_t m = std::clamp<std::size_t>(count, 2, n);
  double mt = 0.0, ms = 0.0;
  for (std::size_t k = n - m; k < n; ++k) {
    mt += window[k].t;
    ms += sigma(static_cast<Eigen::Index>(k));
  }
  mt /= static_cast<double>(m);
  ms /= static_cast<double>(m);
  double stt = 0.0, sts = 0.0;
  for (std::size_t k = n - m; k < n; ++k) {
    const double dt = window[k].t - mt;
    stt += dt * dt;
    sts += dt * (sigma(static_cast<Eigen::Index>(k)) - ms);
  }
  return stt > 0.0 ? sts / stt : 0.0;
}

}  // namespace

MotionModel::MotionModel(const RobotModel& robot,
                         const Eigen::Isometry3d& X_FT,
                         const MotionModelOptions& options)
    : robot_(&robot), X_FT_(X_FT), options_(options) {}

MotionFit MotionModel::fit(std::span<const AxisSample> window) const {
  MotionFit out;
  const auto n = static_cast<Eigen::Index>(window.size());
  if (n < 3) return out;
  const double lever = options_.lever;
  const AxisSample& first = window.front();
  const Eigen::Isometry3d X_0 = toolPose(first.q);
  std::vector<Eigen::Isometry3d> X(window.size());
  Rows joint(n, 7), cartesian(n, 7);
  for (Eigen::Index k = 0; k < n; ++k) {
    const AxisSample& s = window[static_cast<std::size_t>(k)];
    X[static_cast<std::size_t>(k)] = toolPose(s.q);
    const Eigen::Isometry3d& X_k = X[static_cast<std::size_t>(k)];
    joint.row(k).head<6>() = (s.q - first.q).transpose();
    joint(k, 6) = s.theta - first.theta;
    cartesian.row(k).head<3>() = (X_k.translation() - X_0.translation()).transpose();
    cartesian.row(k).segment<3>(3) =
        lever * rotationVector(X_k.linear() * X_0.linear().transpose()).transpose();
    cartesian(k, 6) = lever * (s.theta - first.theta);
  }
  const RankOne j = rankOne(joint);
  const RankOne c = rankOne(cartesian);
  if (j.travel < options_.still && c.travel < options_.still) return out;

  // Both reconstructions measured alike: tool position, lever × tool rotation, lever × table.
  const auto error = [&](const Eigen::Isometry3d& A, double theta_a, std::size_t k) {
    const Eigen::Isometry3d& B = X[k];
    const double turn = Eigen::AngleAxisd(A.linear().transpose() * B.linear()).angle();
    return (A.translation() - B.translation()).norm() + lever * turn +
           lever * std::abs(theta_a - window[k].theta);
  };
  double sj = 0.0, sc = 0.0;
  for (Eigen::Index k = 0; k < n; ++k) {
    const auto i = static_cast<std::size_t>(k);
    const MotionVector jk = j.sigma(k) * j.direction;
    const double ej = error(toolPose(first.q + jk.head<6>()), first.theta + jk(6), i);
    const MotionVector ck = c.sigma(k) * c.direction;
    Eigen::Isometry3d Xc = Eigen::Isometry3d::Identity();
    Xc.linear() = rotationOf(ck.segment<3>(3) / lever) * X_0.linear();
    Xc.translation() = X_0.translation() + ck.head<3>();
    const double ec = error(Xc, first.theta + ck(6) / lever, i);
    sj += ej * ej;
    sc += ec * ec;
  }
  out.joint_residual = std::sqrt(sj / static_cast<double>(n));
  out.cartesian_residual = std::sqrt(sc / static_cast<double>(n));
  const bool joint_wins = out.joint_residual <= out.cartesian_residual;
  const RankOne& chosen = joint_wins ? j : c;
  out.kind = joint_wins ? MotionKind::kJoint : MotionKind::kCartesian;
  out.direction = chosen.direction;
  out.speed = speedAtEnd(window, chosen.sigma, options_.speed_samples);
  return out;
}

std::optional<AxisSample> MotionModel::predict(const MotionFit& fit,
                                               const AxisSample& last,
                                               double tau) const {
  AxisSample out = last;
  out.t = last.t + tau;
  const double step = fit.speed * tau;
  if (fit.kind == MotionKind::kStill) return out;
  if (fit.kind == MotionKind::kJoint) {
    out.q = last.q + step * fit.direction.head<6>();
    out.theta = last.theta + step * fit.direction(6);
    if (!robot_->withinLimits(out.q)) return std::nullopt;
    return out;
  }
  const double lever = options_.lever;
  const Eigen::Isometry3d X_last = toolPose(last.q);
  Eigen::Isometry3d X_BT = Eigen::Isometry3d::Identity();
  X_BT.linear() = rotationOf(step * fit.direction.segment<3>(3) / lever) * X_last.linear();
  X_BT.translation() = X_last.translation() + step * fit.direction.head<3>();
  out.theta = last.theta + step * fit.direction(6) / lever;
  double best = std::numeric_limits<double>::infinity();
  bool found = false;
  for (const IkSolution& s : robot_->ik(X_BT * X_FT_.inverse())) {
    const JointVector q = unwrapNear(s.q, last.q);
    if (!robot_->withinLimits(q)) continue;
    const double d = (q - last.q).norm();
    if (d < best) {
      best = d;
      out.q = q;
      found = true;
    }
  }
  if (!found) return std::nullopt;
  return out;
}

}  // namespace scanplan::kinematics
