// The object_localizer node: detections of an object in the camera frame in,
// T_base_object with its covariance out (paper eq. 68, core/object_pose.h).
// It compounds the robot pose at the detection's stamp (eye-in-hand), X with
// its covariance (from the calibration node's latched ~calibration topic or a
// result file) and the detection's covariance. The logic is in the core; this
// class only looks up TF and converts messages.
#pragma once

#include <ros/ros.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_broadcaster.h>
#include <tf2_ros/transform_listener.h>

#include <map>
#include <mutex>
#include <optional>

#include "handeye_covariance/core/object_pose.h"
#include "handeye_covariance/ros/observations.h"
#include <geometry_msgs/PoseWithCovarianceStamped.h>

namespace handeye {

class ObjectLocalizer {
 public:
  /// Reads ~parameters (see launch/object_localizer.launch) and subscribes.
  ObjectLocalizer(ros::NodeHandle node, ros::NodeHandle private_node);

 private:
  void on_calibration(const geometry_msgs::PoseWithCovarianceStamped::ConstPtr& msg);
  void on_tags(const TagDetectionArray::ConstPtr& msg);
  void locate(const Detection& detection);
  /// Logs the reason (throttled per kind) and counts it on ~refusals.
  void refuse(const Refusal& refusal);

  Rig rig_;  // setup and frames (the pattern frame is unused here)
  std::string object_frame_;
  std::vector<int> tag_ids_;
  bool publish_tf_ = false;
  double tf_timeout_ = 0.5;
  /// The robot pose's covariance (choose_covariance: stated, else the calibration's model, else exact).
  ChosenCovariance robot_covariance() const;

  std::optional<Matrix6d> stated_robot_, stated_object_;  // ~robot_sigma_*, ~object_sigma_*
  std::optional<MeasurementNoise> calibration_noise_;     // the calibration file's noise model

  ros::NodeHandle node_, private_node_;
  tf2_ros::Buffer tf_buffer_;
  tf2_ros::TransformListener tf_listener_;
  tf2_ros::TransformBroadcaster tf_broadcaster_;
  ros::Subscriber calibration_sub_, detections_sub_;
  ros::Publisher object_pub_, markers_pub_, refusal_pub_;  // ~refusal: the latest reason, latched

  std::mutex mutex_;
  std::optional<PoseWithCovariance> X_;
  std::map<std::string, int> refusals_;
};

}  // namespace handeye
