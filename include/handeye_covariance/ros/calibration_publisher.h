// The calibration_publisher node (launch/publish.launch): a saved calibration
// published at every start-up, as easy_handeye's publish.launch does. X goes to
// TF at the root of the camera's own tree (as the calibration node hangs it,
// moved up when a camera driver starts later) and, when the file has a
// covariance (ours; easy_handeye's has none), to a latched
// PoseWithCovarianceStamped on `calibration`.
#pragma once

#include <ros/ros.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include "handeye_covariance/core/pose_covariance.h"
#include "handeye_covariance/core/rig.h"
#include "handeye_covariance/ros/static_edges.h"

namespace handeye {

class CalibrationPublisher {
 public:
  /// Reads ~calibration_file (ours or easy_handeye's) with ~eye_on_hand,
  /// ~robot_base_frame, ~robot_effector_frame, ~tracking_base_frame (each one
  /// set overrides the file's) and ~inverse (publish T_camera_parent instead).
  /// Throws HandEyeError naming the file and the fix when it cannot be published.
  CalibrationPublisher(ros::NodeHandle node, ros::NodeHandle private_node);

 private:
  Rig rig_;  // the setup and X's two frames
  PoseWithCovariance X_;
  bool inverse_ = false;
  tf2_ros::Buffer tf_buffer_;
  tf2_ros::TransformListener tf_listener_;
  StaticEdges edges_;
  ros::Publisher calibration_pub_;
  ros::Timer refresh_timer_;
};

}  // namespace handeye
