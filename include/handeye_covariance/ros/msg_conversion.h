// The only place where ROS messages meet the core's Eigen types.
// Covariances: ROS order (x, y, z, rx, ry, rz), row-major arrays, always read and
// written through explicit row-major maps (pose_covariance.h).
#pragma once

#include <geometry_msgs/Pose.h>
#include <geometry_msgs/PoseWithCovariance.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <geometry_msgs/Transform.h>
#include <geometry_msgs/TransformStamped.h>
#include <ros/time.h>
#include <sensor_msgs/CameraInfo.h>
#include <trajectory_msgs/JointTrajectory.h>

#include <boost/array.hpp>
#include <memory>
#include <optional>

#include "handeye_covariance/core/camera.h"
#include "handeye_covariance/core/pose_covariance.h"
#include "handeye_covariance/estimation/calibration_check.h"
#include "handeye_covariance/motion/trajectory.h"
#include "handeye_covariance/ros/messages.h"

namespace handeye {
namespace conversions {

Eigen::Isometry3d to_eigen(const geometry_msgs::Pose& pose);
Eigen::Isometry3d to_eigen(const geometry_msgs::Transform& transform);
geometry_msgs::Pose to_pose_msg(const Eigen::Isometry3d& pose);
geometry_msgs::Transform to_transform_msg(const Eigen::Isometry3d& pose);

PoseWithCovariance to_core(const geometry_msgs::PoseWithCovariance& msg);
geometry_msgs::PoseWithCovariance to_msg(const PoseWithCovariance& pose);
/// `pose` with its covariance, in `frame` (the pose's parent) at `stamp`.
geometry_msgs::PoseWithCovarianceStamped to_stamped_msg(const PoseWithCovariance& pose, const std::string& frame,
                                                        const ros::Time& stamp);
/// The TF edge parent -> child, T_parent_child, at `stamp`.
geometry_msgs::TransformStamped to_transform_stamped(const Eigen::Isometry3d& T_parent_child, const std::string& parent,
                                                     const std::string& child, const ros::Time& stamp);

/// The full ROS 6x6 covariance (cross block included), or nothing when it is all
/// zeros (apriltag_ros and most detectors send zeros).
std::optional<Matrix6d> covariance_if_nonzero(const boost::array<double, 36>& covariance);

boost::array<double, 9> to_msg_array(const Eigen::Matrix3d& covariance);

/// The camera model of a CameraInfo (K, D, size). Throws HandEyeError for an
/// uncalibrated camera (K all zeros) or an unknown distortion model.
CameraModel to_camera_model(const sensor_msgs::CameraInfo& info);
sensor_msgs::CameraInfo to_camera_info(const CameraModel& camera);

/// The corners a detection's pose came from (TagDetection's object_points,
/// image_points, corner_block, corner_covariance, camera_info); nullptr when it
/// has none. Throws HandEyeError naming what is inconsistent (sizes, NaN, the
/// camera).
std::shared_ptr<TargetCorners> to_corners(const TagDetection& detection);
/// Fills those fields of `detection`.
void set_corners(const TargetCorners& corners, TagDetection& detection);

/// |q| of a message quaternion, to refuse non-unit ones before use.
/// A finished check (state consistent or changed; mm and degrees for the views' table).
CalibrationCheckMsg to_msg(const CalibrationCheck& check, const ros::Time& stamp);

double quaternion_norm(const geometry_msgs::Quaternion& q);

/// A trajectory controller's command (a zero stamp stays zero: "start now"; no
/// points: "hold"). Velocities and accelerations only where the points have them.
trajectory_msgs::JointTrajectory to_msg(const motion::TrajectoryCommand& command);
/// Any message, as sent: fields of other sizes are kept for the controller to refuse.
motion::TrajectoryCommand to_core(const trajectory_msgs::JointTrajectory& msg);

}  // namespace conversions
}  // namespace handeye
