#include "handeye_covariance/core/lie.h"

#include <cmath>
#include <stdexcept>

namespace handeye {
namespace so3 {

namespace {
// Below this angle the closed forms lose digits to cancellation; the Taylor
// series used instead is accurate to ~1e-17 there.
constexpr double kSmallAngle = 1e-4;
// exp's series to theta^6 is exact in double precision below 1e-2 (the next
// term is < 1e-21) and avoids sin/cos for noise-sized rotations.
constexpr double kSeriesAngle = 1e-2;
}  // namespace

Eigen::Matrix3d hat(const Eigen::Vector3d& w) {
  Eigen::Matrix3d W;
  W << 0.0, -w.z(), w.y(),  //
      w.z(), 0.0, -w.x(),   //
      -w.y(), w.x(), 0.0;
  return W;
}

Eigen::Vector3d vee(const Eigen::Matrix3d& W) {
  return 0.5 * Eigen::Vector3d(W(2, 1) - W(1, 2), W(0, 2) - W(2, 0), W(1, 0) - W(0, 1));
}

Eigen::Matrix3d exp(const Eigen::Vector3d& phi) {
  const double theta2 = phi.squaredNorm();
  const double theta = std::sqrt(theta2);
  const Eigen::Matrix3d K = hat(phi);
  double a, b;  // R = I + a [phi] + b [phi]^2
  if (theta < kSeriesAngle) {
    a = 1.0 - theta2 / 6.0 * (1.0 - theta2 / 20.0 * (1.0 - theta2 / 42.0));
    b = 0.5 - theta2 / 24.0 * (1.0 - theta2 / 30.0 * (1.0 - theta2 / 56.0));
  } else {
    a = std::sin(theta) / theta;
    b = (1.0 - std::cos(theta)) / theta2;
  }
  return Eigen::Matrix3d::Identity() + a * K + b * K * K;
}

Eigen::Vector3d log(const Eigen::Matrix3d& R) {
  // Eigen builds the quaternion with Shepperd's method, which is stable for
  // every rotation; with w >= 0 the angle 2 atan2(|v|, w) lies in [0, pi].
  Eigen::Quaterniond q(R);
  if (q.w() < 0.0) q.coeffs() *= -1.0;
  const Eigen::Vector3d v = q.vec();
  const double n = v.norm();
  if (n < 1e-2 * q.w()) {
    // Angles below about 1.1 deg (residuals, small steps), without atan2:
    // theta / n = (2 / w) atan(x) / x, x = n / w, by its series to x^6 (error < x^8 / 9 < 1e-16).
    const double w = q.w(), x2 = n * n / (w * w);
    return (2.0 / w) * (1.0 - x2 * (1.0 / 3.0 - x2 * (1.0 / 5.0 - x2 / 7.0))) * v;
  }
  const double theta = 2.0 * std::atan2(n, q.w());
  return (theta / n) * v;
}

Eigen::Matrix3d left_jacobian(const Eigen::Vector3d& phi) {
  const double theta2 = phi.squaredNorm();
  const double theta = std::sqrt(theta2);
  const Eigen::Matrix3d K = hat(phi);
  double a, b;  // J = I + a [phi] + b [phi]^2
  if (theta < kSmallAngle) {
    a = 0.5 - theta2 / 24.0;
    b = 1.0 / 6.0 - theta2 / 120.0;
  } else {
    a = (1.0 - std::cos(theta)) / theta2;
    b = (theta - std::sin(theta)) / (theta2 * theta);
  }
  return Eigen::Matrix3d::Identity() + a * K + b * K * K;
}

Eigen::Matrix3d left_jacobian_inverse(const Eigen::Vector3d& phi) {
  const double theta2 = phi.squaredNorm();
  const double theta = std::sqrt(theta2);
  const Eigen::Matrix3d K = hat(phi);
  double b;  // J^{-1} = I - 1/2 [phi] + b [phi]^2
  if (theta < kSmallAngle) {
    b = 1.0 / 12.0 + theta2 / 720.0;
  } else {
    // (1 + cos)/(2 theta sin) written with cot(theta/2) so theta = pi is finite.
    const double half = 0.5 * theta;
    b = 1.0 / theta2 - (std::cos(half) / std::sin(half)) / (2.0 * theta);
  }
  return Eigen::Matrix3d::Identity() - 0.5 * K + b * K * K;
}

Eigen::Vector3d other_representative(const Eigen::Vector3d& phi) {
  const double theta = phi.norm();
  if (theta == 0.0) return phi;
  return phi * ((theta - 2.0 * M_PI) / theta);
}

}  // namespace so3

namespace se3 {

Eigen::Isometry3d make_pose(const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = R;
  T.translation() = t;
  return T;
}

Eigen::Isometry3d exp(const Vector6d& twist) {
  const Eigen::Vector3d rho = twist.head<3>();
  const Eigen::Vector3d phi = twist.tail<3>();
  return make_pose(so3::exp(phi), so3::left_jacobian(phi) * rho);
}

Vector6d log(const Eigen::Isometry3d& T) {
  const Eigen::Vector3d phi = so3::log(T.linear());
  Vector6d twist;
  twist.head<3>() = so3::left_jacobian_inverse(phi) * T.translation();
  twist.tail<3>() = phi;
  return twist;
}

}  // namespace se3

Eigen::Isometry3d mean_pose(const std::vector<Eigen::Isometry3d>& poses, int max_iterations) {
  if (poses.empty()) throw std::invalid_argument("mean_pose of no poses");
  Eigen::Matrix3d R = poses.front().linear();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  for (const Eigen::Isometry3d& p : poses) t += p.translation();
  for (int iteration = 0; iteration < max_iterations; ++iteration) {
    Eigen::Vector3d step = Eigen::Vector3d::Zero();
    for (const Eigen::Isometry3d& p : poses) step += so3::log(p.linear() * R.transpose());
    step /= static_cast<double>(poses.size());
    R = so3::exp(step) * R;  // eq. (66), re-centred on the current mean
    if (step.norm() < 1e-13) break;
  }
  return se3::make_pose(R, t / static_cast<double>(poses.size()));
}

}  // namespace handeye
