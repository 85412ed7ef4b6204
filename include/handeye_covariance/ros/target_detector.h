// The target detector node: image + CameraInfo in, the target's pose with its
// covariance out as TagDetectionArray (and optionally TF camera -> pattern at
// the image stamp). Any target of core/target.h: chessboard, ChArUco, ArUco
// (one marker or a board), AprilTag (one tag or a board). The work is done by
// the ROS-free vision layer (vision/target.h, pattern_pose.h); this class is glue.
#pragma once

#include <image_transport/image_transport.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <tf2_ros/transform_broadcaster.h>

#include <memory>
#include <mutex>
#include <optional>

#include "handeye_covariance/core/target.h"
#include "handeye_covariance/vision/pattern_pose.h"
#include "handeye_covariance/vision/target.h"

namespace handeye {

class TargetDetectorNode {
 public:
  /// Reads ~parameters (see launch/target_detector.launch); throws
  /// HandEyeError for an unreadable target file or an unknown family or dictionary.
  TargetDetectorNode(ros::NodeHandle node, ros::NodeHandle private_node);

 private:
  void on_camera_info(const sensor_msgs::CameraInfo::ConstPtr& info);
  void on_image(const sensor_msgs::Image::ConstPtr& image);

  std::string pattern_frame_;
  bool publish_tf_ = false, image_is_rectified_ = false;
  TargetDetectorOptions options_;
  std::unique_ptr<TargetDetector> detector_;
  image_transport::ImageTransport transport_;
  image_transport::Subscriber image_sub_;
  ros::Subscriber info_sub_;
  ros::Publisher detections_pub_;
  tf2_ros::TransformBroadcaster broadcaster_;

  std::mutex mutex_;  // info_ and rectifier_ come from the info callback
  std::optional<sensor_msgs::CameraInfo> info_;
  std::unique_ptr<ImageRectifier> rectifier_;
  CameraModel camera_;  // the raw image's: the detections' corners are sent in its pixels
  PixelNoise pixel_noise_;
  std::string camera_error_;  // why the last CameraInfo was refused
};

}  // namespace handeye
