// The detections of the configured input, for the nodes that take them (the calibration
// node, the calibration monitor): ~detection_input tags (TagDetectionArray, the pattern
// picked by ~tag_ids), pose_with_covariance, pose, or tf (the camera -> pattern transform,
// polled). Each detection is handed over in order on the queue of the node handle given;
// a message without the pattern (or with a refusal) is reported with its stamp.
#pragma once

#include <ros/ros.h>
#include <tf2/buffer_core.h>

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "handeye_covariance/core/rig.h"
#include "handeye_covariance/ros/observations.h"

namespace handeye {

class DetectionInput {
 public:
  using OnDetection = std::function<void(const Detection&)>;
  /// No detection in a message: its stamp, and the refusal when there was one.
  using OnNothing = std::function<void(const ros::Time& stamp, const std::optional<Refusal>& refusal)>;

  /// Throws std::invalid_argument for an unknown `input`.
  DetectionInput(ros::NodeHandle& node, const std::string& input, const std::string& topic, std::vector<int> tag_ids,
                 double tf_poll_rate, const tf2::BufferCore& tf, FrameNames frames, OnDetection on_detection,
                 OnNothing on_nothing);

 private:
  void on_tf_poll();

  std::vector<int> tag_ids_;
  const tf2::BufferCore& tf_;
  FrameNames frames_;
  OnDetection on_detection_;
  OnNothing on_nothing_;
  ros::Subscriber subscriber_;
  ros::Timer tf_poll_;
  ros::Time last_tf_stamp_;  // the poll's thread only
};

}  // namespace handeye
