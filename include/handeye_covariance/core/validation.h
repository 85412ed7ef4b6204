// Input checks shared by the file readers and the library entry points.
// Each throws HandEyeError naming the field (`where`) and the fix.
#pragma once

#include <string>

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/core/pose_covariance.h"

namespace handeye {

/// Finite, orthonormal rotation with det +1 (tolerance 1e-6), finite translation.
void check_pose(const Eigen::Isometry3d& pose, const std::string& where);
/// What check_pose accepts, without building an error.
bool is_proper_pose(const Eigen::Isometry3d& pose);
/// check_pose with the location made by `where()` only when the pose fails: for
/// loops over many samples, where building every location costs more than the check.
template <typename Where>
void check_pose_at(const Eigen::Isometry3d& pose, Where&& where) {
  if (!is_proper_pose(pose)) check_pose(pose, where());
}

/// Finite, symmetric and positive semi-definite.
void check_covariance(const Eigen::Matrix3d& covariance, const std::string& where);
void check_covariance(const DecoupledCovariance& covariance, const std::string& where);
/// Each block, then the cross block against them (a correlation beyond 1 is refused).
void check_covariance(const PoseNoise& covariance, const std::string& where);
void check_covariance(const Matrix6d& covariance, const std::string& where);  // ROS order, may have cross blocks
void check_covariance(const Matrix12d& covariance, const std::string& where);  // X and Y jointly

/// |q| within 1e-3 of 1 and finite; returns the normalised quaternion.
Eigen::Quaterniond checked_unit_quaternion(const Eigen::Quaterniond& q, const std::string& where);

}  // namespace handeye
