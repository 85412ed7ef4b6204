#include "handeye_covariance/ros/detection_input.h"

#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <tf2/exceptions.h>

#include <stdexcept>

namespace handeye {

DetectionInput::DetectionInput(ros::NodeHandle& node, const std::string& input, const std::string& topic,
                               std::vector<int> tag_ids, double tf_poll_rate, const tf2::BufferCore& tf, FrameNames frames,
                               OnDetection on_detection, OnNothing on_nothing)
    : tag_ids_(std::move(tag_ids)),
      tf_(tf),
      frames_(std::move(frames)),
      on_detection_(std::move(on_detection)),
      on_nothing_(std::move(on_nothing)) {
  using geometry_msgs::PoseStamped;
  using geometry_msgs::PoseWithCovarianceStamped;
  if (input == "tags") {
    subscriber_ = node.subscribe<TagDetectionArray>(topic, 50, [this](const TagDetectionArray::ConstPtr& msg) {
      std::optional<Refusal> refusal;
      if (const std::optional<Detection> detection = select_detection(*msg, tag_ids_, refusal)) {
        on_detection_(*detection);
      } else {
        on_nothing_(msg->header.stamp, refusal);
      }
    });
  } else if (input == "pose_with_covariance") {
    subscriber_ = node.subscribe<PoseWithCovarianceStamped>(
        topic, 50, [this](const PoseWithCovarianceStamped::ConstPtr& msg) { on_detection_(detection_of(*msg)); });
  } else if (input == "pose") {
    subscriber_ = node.subscribe<PoseStamped>(topic, 50,
                                              [this](const PoseStamped::ConstPtr& msg) { on_detection_(detection_of(*msg)); });
  } else if (input == "tf") {
    tf_poll_ = node.createTimer(ros::Duration(1.0 / tf_poll_rate), [this](const ros::TimerEvent&) { on_tf_poll(); });
  } else {
    throw std::invalid_argument("~detection_input must be tags, pose_with_covariance, pose or tf, not `" + input + "`");
  }
}

void DetectionInput::on_tf_poll() {
  geometry_msgs::TransformStamped latest;
  try {
    // The latest camera -> pattern transform; its own stamp is then used for the robot.
    latest = tf_.lookupTransform(frames_.camera, frames_.pattern, ros::Time(0));
  } catch (const tf2::TransformException&) {
    return;  // pattern not seen (yet)
  }
  if (latest.header.stamp <= last_tf_stamp_) return;  // nothing new
  last_tf_stamp_ = latest.header.stamp;
  on_detection_(detection_of(latest));
}

}  // namespace handeye
