#include "handeye_covariance/ros/calibration_publisher.h"

#include <geometry_msgs/PoseWithCovarianceStamped.h>

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/io/yaml_io.h"
#include "handeye_covariance/ros/msg_conversion.h"
#include "handeye_covariance/ros/params.h"

namespace handeye {

CalibrationPublisher::CalibrationPublisher(ros::NodeHandle node, ros::NodeHandle private_node)
    : tf_listener_(tf_buffer_) {
  const std::string path = io::expand_home(param<std::string>(private_node, "calibration_file", ""));
  if (path.empty()) {
    throw HandEyeError(ErrorCode::MissingKey, "no calibration file given", "~calibration_file",
                       "roslaunch handeye_covariance publish.launch calibration_file:=<a result YAML of "
                       "handeye_covariance or easy_handeye>");
  }
  const io::StoredCalibration stored = io::read_stored_calibration(path);

  // The setup: the file's; ~eye_on_hand when the file does not say, and checked against it when it does.
  bool eye_on_hand = true;
  const bool stated = private_node.getParam("eye_on_hand", eye_on_hand);
  if (stored.setup && stated && *stored.setup != setup_from_eye_on_hand(eye_on_hand)) {
    throw HandEyeError(ErrorCode::MalformedFile,
                       std::string("the calibration is ") + to_string(*stored.setup) + " but eye_on_hand is " +
                           (eye_on_hand ? "true" : "false"),
                       path, "drop eye_on_hand:= (the file says which), or give the other calibration file");
  }
  if (!stored.setup && !stated) {
    throw HandEyeError(ErrorCode::MissingKey, "the file does not say whether the camera is on the robot", path,
                       "add eye_on_hand:=true (camera on the effector) or eye_on_hand:=false");
  }
  rig_.setup = stored.setup ? *stored.setup : setup_from_eye_on_hand(eye_on_hand);
  // publish.launch names the namespace from eye_on_hand:= (empty: eye-on-hand), and object_localizer
  // looks there: a file of the other setup would put the calibration where nobody looks.
  const std::string ns = ros::this_node::getNamespace();
  const std::string other = rig_.eye_in_hand() ? "_eye_on_base" : "_eye_on_hand";
  if (ns.size() >= other.size() && ns.compare(ns.size() - other.size(), other.size(), other) == 0) {
    throw HandEyeError(ErrorCode::MalformedFile,
                       std::string("the calibration is ") + to_string(rig_.setup) + " but it would be published in " +
                           ns + ", where the other setup's consumers look",
                       path, std::string("give eye_on_hand:=") + (rig_.eye_in_hand() ? "true" : "false"));
  }

  // X's frames: the file's, each replaced by its parameter when that is set (easy_handeye's overrides).
  const std::string parent_key = rig_.eye_in_hand() ? "robot_effector_frame" : "robot_base_frame";
  const std::string parent = param<std::string>(private_node, parent_key, "");
  const std::string child = param<std::string>(private_node, "tracking_base_frame", "");
  rig_.camera_parent_frame() = parent.empty() ? stored.parent : parent;
  rig_.frames.camera = child.empty() ? stored.child : child;
  if (rig_.camera_parent_frame().empty() || rig_.frames.camera.empty()) {
    throw HandEyeError(ErrorCode::MissingKey, "the file does not name X's frames", path,
                       "give " + parent_key + ":=<frame> tracking_base_frame:=<camera frame>");
  }
  X_ = stored.T_parent_camera;
  inverse_ = param(private_node, "inverse", false);

  const std::string edge = inverse_ ? rig_.frames.camera + " -> " + rig_.camera_parent_frame()
                                    : rig_.camera_parent_frame() + " -> " + rig_.frames.camera;
  if (stored.has_covariance) {
    calibration_pub_ = node.advertise<geometry_msgs::PoseWithCovarianceStamped>("calibration", 1, true);
    calibration_pub_.publish(conversions::to_stamped_msg(inverse_ ? inverse(X_) : X_,  // the covariance follows the frame change
                                                         inverse_ ? rig_.frames.camera : rig_.camera_parent_frame(),
                                                         ros::Time::now()));
  } else {
    ROS_WARN("%s is %s's: it has no covariance, so only TF is published (calibrate with handeye_covariance for one)",
             path.c_str(), stored.format.c_str());
  }
  ROS_INFO("publishing X = T_%s_%s (%s, %s) from %s", rig_.camera_parent_frame().c_str(), rig_.frames.camera.c_str(),
           to_string(rig_.setup), edge.c_str(), path.c_str());
  if (inverse_) {  // easy_handeye's inverse: the camera is the parent, as the user asked
    edges_.publish(conversions::to_transform_stamped(X_.pose.inverse(), rig_.frames.camera, rig_.camera_parent_frame(),
                                                     ros::Time::now()));
    return;
  }
  // First after a second: the TF listener needs that to learn a running driver's camera tree
  // (else X would go to the camera frame first and move up a moment later).
  // Each second: X's edge at the camera tree's current root (a driver may start later).
  refresh_timer_ = node.createTimer(ros::Duration(1.0), [this](const ros::TimerEvent&) {
    edges_.publish_camera(tf_buffer_, rig_, X_.pose);
  });
}

}  // namespace handeye
