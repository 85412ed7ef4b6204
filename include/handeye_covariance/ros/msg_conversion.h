// The only place where ROS messages meet the core's Eigen types (camera
// models, which need the vision library, are in camera_info_conversion.h).
// Covariances: ROS order (x, y, z, rx, ry, rz), row-major arrays, always read and
// written through explicit row-major maps (pose_covariance.h).
#pragma once

#include <geometry_msgs/Pose.h>
#include <geometry_msgs/PoseWithCovariance.h>
#include <geometry_msgs/Transform.h>

#include <boost/array.hpp>
#include <optional>

#include "handeye_covariance/core/pose_covariance.h"

namespace handeye {
namespace conversions {

Eigen::Isometry3d to_eigen(const geometry_msgs::Pose& pose);
Eigen::Isometry3d to_eigen(const geometry_msgs::Transform& transform);
geometry_msgs::Pose to_pose_msg(const Eigen::Isometry3d& pose);
geometry_msgs::Transform to_transform_msg(const Eigen::Isometry3d& pose);

PoseWithCovariance to_core(const geometry_msgs::PoseWithCovariance& msg);
geometry_msgs::PoseWithCovariance to_msg(const PoseWithCovariance& pose);

/// The full ROS 6x6 covariance (cross block included), or nothing when it is all
/// zeros (apriltag_ros and most detectors send zeros).
std::optional<Matrix6d> covariance_if_nonzero(const boost::array<double, 36>& covariance);

boost::array<double, 9> to_msg_array(const Eigen::Matrix3d& covariance);

/// |q| of a message quaternion, to refuse non-unit ones before use.
double quaternion_norm(const geometry_msgs::Quaternion& q);

}  // namespace conversions
}  // namespace handeye
