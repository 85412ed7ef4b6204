#include "handeye_covariance/core/pose_covariance.h"

#include <Eigen/Eigenvalues>
#include <algorithm>

namespace handeye {

Vector6d pose_error(const Eigen::Isometry3d& pose, const Eigen::Isometry3d& reference) {
  Vector6d error;
  error.head<3>() = pose.translation() - reference.translation();
  error.tail<3>() = so3::log(pose.linear() * reference.linear().transpose());
  return error;
}

using Eigen::Matrix3d;

Matrix6d DecoupledCovariance::as_pose_covariance() const {
  Matrix6d covariance = Matrix6d::Zero();
  covariance.topLeftCorner<3, 3>() = translation;
  covariance.bottomRightCorner<3, 3>() = rotation;
  return covariance;
}

Matrix6d PoseNoise::as_pose_covariance() const {
  Matrix6d covariance;
  covariance << translation, translation_rotation, translation_rotation.transpose(), rotation;
  return covariance;
}

PoseNoise PoseNoise::from_pose_covariance(const Matrix6d& covariance) {
  const Matrix6d symmetric = 0.5 * (covariance + covariance.transpose());
  return {symmetric.bottomRightCorner<3, 3>(), symmetric.topLeftCorner<3, 3>(), symmetric.topRightCorner<3, 3>()};
}

Matrix6d inverse_jacobian(const Eigen::Isometry3d& T) {
  // R' = R^T exp(-[xi_R]) = exp(-[R^T xi_R]) R^T  and
  // t' = -R^T t  ->  d t' = -R^T xi_t - R^T [t] xi_R.
  const Matrix3d Rt = T.linear().transpose();
  Matrix6d J = Matrix6d::Zero();
  J.topLeftCorner<3, 3>() = -Rt;
  J.topRightCorner<3, 3>() = -Rt * so3::hat(T.translation());
  J.bottomRightCorner<3, 3>() = -Rt;
  return J;
}

Matrix6d compose_jacobian_left(const Eigen::Isometry3d& T1, const Eigen::Isometry3d& T2) {
  // exp([xi1]) R1 R2 and t1 + xi_t1 + exp([xi1]) R1 t2  ->  d t = xi_t1 - [R1 t2] xi1.
  Matrix6d J = Matrix6d::Identity();
  J.topRightCorner<3, 3>() = -so3::hat(T1.linear() * T2.translation());
  return J;
}

Matrix6d compose_jacobian_right(const Eigen::Isometry3d& T1) {
  // R1 exp([xi2]) R2 = exp([R1 xi2]) R1 R2 and d t = R1 xi_t2.
  Matrix6d J = Matrix6d::Zero();
  J.topLeftCorner<3, 3>() = T1.linear();
  J.bottomRightCorner<3, 3>() = T1.linear();
  return J;
}

PoseWithCovariance inverse(const PoseWithCovariance& T) {
  const Matrix6d J = inverse_jacobian(T.pose);
  return {T.pose.inverse(), J * T.covariance * J.transpose()};
}

PoseWithCovariance compose(const PoseWithCovariance& T1, const PoseWithCovariance& T2) {
  const Matrix6d J1 = compose_jacobian_left(T1.pose, T2.pose);
  const Matrix6d J2 = compose_jacobian_right(T1.pose);
  return {T1.pose * T2.pose,
          J1 * T1.covariance * J1.transpose() + J2 * T2.covariance * J2.transpose()};
}

namespace {
// <<M>> := -tr(M) I + M   (eq. 75)
Matrix3d double_bracket(const Matrix3d& M) { return -M.trace() * Matrix3d::Identity() + M; }
// <<M, N>> := <<M>><<N>> + <<N M>>   (eq. 76)
Matrix3d double_bracket(const Matrix3d& M, const Matrix3d& N) {
  return double_bracket(M) * double_bracket(N) + double_bracket(N * M);
}
}  // namespace

DecoupledPose compose_decoupled(const DecoupledPose& T1, const DecoupledPose& T2) {
  const Matrix3d& R1 = T1.pose.linear();
  const Matrix3d& sigma_R1 = T1.covariance.rotation;
  const Matrix3d sigma_R2_rotated = R1 * T2.covariance.rotation * R1.transpose();  // Sigma'_R2
  const Matrix3d A1 = double_bracket(sigma_R1);                                    // eq. (74)
  const Matrix3d A2 = double_bracket(sigma_R2_rotated);
  const Matrix3d B = double_bracket(sigma_R1, sigma_R2_rotated);

  DecoupledPose result;
  result.pose = T1.pose * T2.pose;  // eq. (70-71)
  result.covariance.rotation =      // eq. (72)
      sigma_R1 + sigma_R2_rotated +
      (A1 * sigma_R2_rotated + sigma_R2_rotated * A1.transpose() + sigma_R1 * A2 +
       sigma_R1 * A2.transpose()) /
          12.0 +
      B / 4.0;
  const Matrix3d lever = so3::hat(R1 * T2.pose.translation());
  result.covariance.translation = T1.covariance.translation +  // eq. (77)
                                  R1 * T2.covariance.translation * R1.transpose() +
                                  lever * sigma_R1 * lever.transpose();
  return result;
}

DecoupledPose inverse_decoupled(const DecoupledPose& T) {
  const Matrix3d Rt = T.pose.linear().transpose();
  const Matrix3d lever = so3::hat(T.pose.translation());
  DecoupledPose result;
  result.pose = T.pose.inverse();
  result.covariance.rotation = Rt * T.covariance.rotation * Rt.transpose();
  result.covariance.translation =
      Rt * (T.covariance.translation + lever * T.covariance.rotation * lever.transpose()) *
      Rt.transpose();
  return result;
}

Matrix3d point_covariance(const PoseWithCovariance& T, const Eigen::Vector3d& p_child) {
  Eigen::Matrix<double, 3, 6> J;
  J << Matrix3d::Identity(), -so3::hat(T.pose.linear() * p_child);
  return J * T.covariance * J.transpose();
}

Matrix6d from_row_major_6x6(const std::array<double, 36>& values) {
  return Eigen::Map<const Eigen::Matrix<double, 6, 6, Eigen::RowMajor>>(values.data());
}

std::array<double, 36> to_row_major_6x6(const Matrix6d& covariance) {
  std::array<double, 36> values;
  Eigen::Map<Eigen::Matrix<double, 6, 6, Eigen::RowMajor>>(values.data()) = covariance;
  return values;
}

Matrix3d from_row_major_3x3(const std::array<double, 9>& values) {
  return Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(values.data());
}

std::array<double, 9> to_row_major_3x3(const Matrix3d& covariance) {
  std::array<double, 9> values;
  Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(values.data()) = covariance;
  return values;
}

double max_sigma(const Matrix3d& covariance) {
  const Eigen::SelfAdjointEigenSolver<Matrix3d> eig(0.5 * (covariance + covariance.transpose()),
                                                    Eigen::EigenvaluesOnly);
  return std::sqrt(std::max(0.0, eig.eigenvalues().maxCoeff()));
}

}  // namespace handeye
