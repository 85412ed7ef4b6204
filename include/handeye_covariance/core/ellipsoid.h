// Covariance -> drawable geometry, as pure functions (used by the RViz display
// and by the node's MarkerArray, so both draw the same thing).
#pragma once

#include "handeye_covariance/core/pose_covariance.h"

namespace handeye {

/// The n-sigma ellipsoid of a 3x3 covariance: semi-axes `radii` along the
/// columns of `axes`, a proper rotation (right-handed, det +1), largest first.
struct Ellipsoid {
  Eigen::Vector3d radii = Eigen::Vector3d::Zero();
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();
  Eigen::Quaterniond orientation() const { return Eigen::Quaterniond(axes); }
};

/// Throws HandEyeError(InvalidNoise) unless `covariance` is finite, symmetric and
/// positive semi-definite (a rank-deficient covariance gives zero radii).
Ellipsoid ellipsoid_from_covariance(const Eigen::Matrix3d& covariance, double sigmas);

/// Covariance of where the tip of `axis` (unit vector in the parent frame, at
/// `length` from the origin) goes under a rotation uncertainty `rotation_covariance`
/// (left perturbation, parent frame): L^2 [a] Sigma_R [a]^T. It is flat along
/// the axis: the wobble of that axis, which the display draws as a disc.
Eigen::Matrix3d axis_tip_covariance(const Eigen::Matrix3d& rotation_covariance, const Eigen::Vector3d& axis,
                                    double length);

}  // namespace handeye
