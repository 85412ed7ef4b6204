// Poses with covariance: first-order Jacobians, the paper's decoupled compounding
// (Appendix A, eq. 70-77), and the ROS row-major array layout.
//
// A pose T = (R, t) is perturbed as
//     R = exp([xi_R]) R_hat,   t = t_hat + xi_t,
// so the 6-vector (xi_t, xi_R) is in the PARENT frame and in ROS order
// (x, y, z, rx, ry, rz). Every 6x6 covariance in this package uses that order.
#pragma once

#include <array>

#include "handeye_covariance/core/lie.h"

namespace handeye {

/// A pose and its 6x6 covariance in ROS order (m^2, rad^2, parent frame).
struct PoseWithCovariance {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  Matrix6d covariance = Matrix6d::Zero();
};

/// The perturbation (xi_t, xi_R) above that takes `reference` to `pose`:
/// (t - t_ref, log(R R_ref^T)), ROS order. An estimate's error against the truth
/// (the paper's definitions), a sample's residual (eq. 64-65), two estimates' difference.
Vector6d pose_error(const Eigen::Isometry3d& pose, const Eigen::Isometry3d& reference);

/// Rotation and translation covariances with no cross term, as in the paper.
struct DecoupledCovariance {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Zero();     // rad^2, left perturbation
  Eigen::Matrix3d translation = Eigen::Matrix3d::Zero();  // m^2

  /// Block-diagonal 6x6 in ROS order.
  Matrix6d as_pose_covariance() const;
};

/// A measured pose's noise: the full 6x6 covariance in ROS order, kept as its
/// blocks. Detectors give a cross block (a pattern seen off-centre couples its
/// rotation and translation errors); it travels with the pose to the estimator.
struct PoseNoise {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Zero();     // rad^2, left perturbation
  Eigen::Matrix3d translation = Eigen::Matrix3d::Zero();  // m^2
  /// E[xi_t xi_R^T] (m rad): the top-right block of the ROS-order 6x6.
  Eigen::Matrix3d translation_rotation = Eigen::Matrix3d::Zero();

  Matrix6d as_pose_covariance() const;
  static PoseNoise from_pose_covariance(const Matrix6d& covariance);  // symmetrised
  bool has_cross_block() const { return !translation_rotation.isZero(0.0); }
};

/// d(perturbation of T^-1) / d(perturbation of T), ROS order.
Matrix6d inverse_jacobian(const Eigen::Isometry3d& T);

/// d(perturbation of T1 T2) / d(perturbation of T1), ROS order.
Matrix6d compose_jacobian_left(const Eigen::Isometry3d& T1, const Eigen::Isometry3d& T2);

/// d(perturbation of T1 T2) / d(perturbation of T2), ROS order.
Matrix6d compose_jacobian_right(const Eigen::Isometry3d& T1);

/// First-order inverse with the full 6x6 covariance (keeps the R-t cross term).
PoseWithCovariance inverse(const PoseWithCovariance& T);

/// First-order compounding T1 T2 of independent poses, full 6x6 covariance.
PoseWithCovariance compose(const PoseWithCovariance& T1, const PoseWithCovariance& T2);

/// The paper's compounding of independent poses with decoupled covariances:
/// mean by eq. (70-71), rotation covariance by eq. (72) (fourth-order terms
/// included), translation covariance by eq. (77).
struct DecoupledPose {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  DecoupledCovariance covariance;
};
DecoupledPose compose_decoupled(const DecoupledPose& T1, const DecoupledPose& T2);

/// Inverse with decoupled covariances: Sigma_R' = R^T Sigma_R R and
/// Sigma_t' = R^T (Sigma_t + [t] Sigma_R [t]^T) R (the cross term is dropped).
DecoupledPose inverse_decoupled(const DecoupledPose& T);

/// Covariance of the point T * p_child (in T's parent frame), to first order:
/// J = [I, -[R p_child]] on the ROS-order perturbation (dt, xi_R).
Eigen::Matrix3d point_covariance(const PoseWithCovariance& T, const Eigen::Vector3d& p_child);

/// ROS covariance arrays are row-major; read and write them only through these.
Matrix6d from_row_major_6x6(const std::array<double, 36>& values);
std::array<double, 36> to_row_major_6x6(const Matrix6d& covariance);
Eigen::Matrix3d from_row_major_3x3(const std::array<double, 9>& values);
std::array<double, 9> to_row_major_3x3(const Eigen::Matrix3d& covariance);

/// Square root of the largest eigenvalue (the worst 1-sigma along any axis).
double max_sigma(const Eigen::Matrix3d& covariance);

}  // namespace handeye
