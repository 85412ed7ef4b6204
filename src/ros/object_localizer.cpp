#include "handeye_covariance/ros/object_localizer.h"

#include <std_msgs/String.h>
#include <tf2/exceptions.h>

#include "handeye_covariance/core/units.h"
#include "handeye_covariance/core/validation.h"
#include "handeye_covariance/io/yaml_io.h"
#include "handeye_covariance/ros/covariance_markers.h"
#include "handeye_covariance/ros/msg_conversion.h"
#include "handeye_covariance/ros/params.h"

namespace handeye {


ObjectLocalizer::ObjectLocalizer(ros::NodeHandle node, ros::NodeHandle private_node)
    : node_(node), private_node_(private_node), tf_listener_(tf_buffer_) {
  rig_.setup = setup_from_eye_on_hand(param(private_node_, "eye_on_hand", true));
  rig_.frames.base = param<std::string>(private_node_, "robot_base_frame", "base_link");
  rig_.frames.effector = param<std::string>(private_node_, "robot_effector_frame", "tool0");
  rig_.frames.camera = param<std::string>(private_node_, "tracking_base_frame", "camera_optical_frame");
  object_frame_ = param<std::string>(private_node_, "object_frame", "object");
  tag_ids_ = param(private_node_, "object_tag_ids", std::vector<int>{});
  publish_tf_ = param(private_node_, "publish_tf", false);
  tf_timeout_ = param(private_node_, "tf_timeout", 0.5);

  // X from a result file when given; the calibration topic replaces it on every /calibrate.
  const std::string calibration_file = param<std::string>(private_node_, "calibration_file", "");
  if (!calibration_file.empty()) {
    const io::CalibrationFile file = io::read_result(calibration_file);
    if (file.context.setup && *file.context.setup != rig_.setup) {
      throw HandEyeError(ErrorCode::MalformedFile,
                         std::string("the calibration is ") + to_string(*file.context.setup) +
                             " but ~eye_on_hand says " + to_string(rig_.setup),
                         calibration_file, "set ~eye_on_hand to match, or give the other calibration");
    }
    X_ = file.T_parent_camera();
    calibration_noise_ = file.noise;
    ROS_INFO("X from %s (%s)", calibration_file.c_str(), sigma_label(*X_).c_str());
  }

  // Stated 1 sigmas; which covariance each pose gets is choose_covariance's rule.
  if (private_node_.hasParam("robot_sigma_mm") || private_node_.hasParam("robot_sigma_deg")) {
    stated_robot_ = isotropic_covariance(metres(param(private_node_, "robot_sigma_mm", 0.0)),
                                         radians(param(private_node_, "robot_sigma_deg", 0.0)));
  }
  if (private_node_.hasParam("object_sigma_mm") || private_node_.hasParam("object_sigma_deg")) {
    stated_object_ = isotropic_covariance(metres(param(private_node_, "object_sigma_mm", 0.0)),
                                          radians(param(private_node_, "object_sigma_deg", 0.0)));
  }
  if (rig_.eye_in_hand() && robot_covariance().origin == CovarianceOrigin::None) {
    ROS_WARN("no ~robot_sigma_mm/~robot_sigma_deg and no noise model in the calibration: the robot pose is "
             "taken as exact, which understates the object's covariance");
  }

  object_pub_ = private_node_.advertise<geometry_msgs::PoseWithCovarianceStamped>("object_pose", 10);
  markers_pub_ = private_node_.advertise<visualization_msgs::MarkerArray>("markers", 1);
  refusal_pub_ = private_node_.advertise<std_msgs::String>("refusal", 10, true);
  calibration_sub_ = node_.subscribe("calibration", 1, &ObjectLocalizer::on_calibration, this);
  const std::string input = param<std::string>(private_node_, "object_input", "pose_with_covariance");
  const std::string topic = param<std::string>(private_node_, "object_topic", "object_detections");
  if (input == "tags") {
    detections_sub_ = node_.subscribe(topic, 10, &ObjectLocalizer::on_tags, this);
  } else if (input == "pose_with_covariance") {
    detections_sub_ = node_.subscribe<geometry_msgs::PoseWithCovarianceStamped>(
        topic, 10, [this](const geometry_msgs::PoseWithCovarianceStamped::ConstPtr& msg) { locate(detection_of(*msg)); });
  } else {
    throw std::invalid_argument("~object_input must be tags or pose_with_covariance, not `" + input + "`");
  }
}

ChosenCovariance ObjectLocalizer::robot_covariance() const {
  return choose_covariance(std::nullopt, stated_robot_,
                           calibration_noise_ ? std::optional<PoseNoise>(calibration_noise_->robot) : std::nullopt);
}

void ObjectLocalizer::on_calibration(const geometry_msgs::PoseWithCovarianceStamped::ConstPtr& msg) {
  const std::string& parent = rig_.camera_parent_frame();
  if (msg->header.frame_id != parent) {
    refuse({"calibration_frame", "a calibration in frame `" + msg->header.frame_id + "` was ignored: X must be T_" +
                                     parent + "_camera. Check ~eye_on_hand and the frame parameters"});
    return;
  }
  const PoseWithCovariance X = conversions::to_core(msg->pose);
  std::lock_guard<std::mutex> lock(mutex_);
  X_ = X;
  ROS_INFO("X updated from the calibration topic (%s)", sigma_label(X).c_str());
}

void ObjectLocalizer::on_tags(const TagDetectionArray::ConstPtr& msg) {
  std::optional<Refusal> refusal;
  const std::optional<Detection> detection = select_detection(*msg, tag_ids_, refusal);
  if (refusal) refuse(*refusal);
  if (detection) locate(*detection);
}

void ObjectLocalizer::locate(const Detection& detection) {
  std::optional<PoseWithCovariance> X;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    X = X_;
  }
  if (!X) {
    refuse({"no_calibration", "no calibration yet: call /calibrate on the calibration node, or set ~calibration_file"});
    return;
  }
  if (!detection.frame.empty() && detection.frame != rig_.frames.camera) {
    refuse({"detection_frame", "a detection in frame `" + detection.frame + "` was ignored; X is calibrated for `" +
                                   rig_.frames.camera + "` (set ~tracking_base_frame)"});
    return;
  }
  try {  // to_eigen would quietly normalise a wrong quaternion; refuse it, as make_observation does
    const geometry_msgs::Quaternion& q = detection.pose.orientation;
    checked_unit_quaternion(Eigen::Quaterniond(q.w, q.x, q.y, q.z), "the detection's orientation");
  } catch (const HandEyeError& e) {
    refuse({"invalid_input", e.what()});
    return;
  }
  ObjectPoseInput input;
  input.rig = rig_;
  input.X = *X;
  input.T_camera_object.pose = conversions::to_eigen(detection.pose);
  const ChosenCovariance detection_covariance = choose_covariance(
      detection.covariance, stated_object_,
      calibration_noise_ ? std::optional<PoseNoise>(calibration_noise_->camera) : std::nullopt);
  input.T_camera_object.covariance = detection_covariance.covariance;  // a message's full 6x6, cross block included
  if (detection_covariance.origin == CovarianceOrigin::None) {
    refuse({"no_detection_covariance", "a detection without a covariance was ignored: set ~object_sigma_mm and "
                                       "~object_sigma_deg, or use a calibration file with a noise model"});
    return;
  }
  if (rig_.eye_in_hand()) {
    try {  // the robot pose when the image was taken, never the latest
      input.T_base_effector = {
          conversions::to_eigen(tf_buffer_.lookupTransform(rig_.frames.base, rig_.frames.effector, detection.stamp,
                                                           ros::Duration(tf_timeout_)).transform),
          robot_covariance().covariance};
    } catch (const tf2::TransformException& e) {
      refuse({"no_robot_tf", "no TF " + rig_.frames.base + " -> " + rig_.frames.effector + " at the detection stamp " +
                                 std::to_string(detection.stamp.toSec()) + ": " + e.what()});
      return;
    }
  }
  ObjectPose object;
  try {
    object = object_in_base(input);
  } catch (const HandEyeError& e) {
    refuse({"invalid_input", e.what()});
    return;
  }
  object_pub_.publish(conversions::to_stamped_msg(object.T_base_object, rig_.frames.base, detection.stamp));
  markers_pub_.publish(covariance_markers(object.T_base_object, rig_.frames.base, detection.stamp, {3.0, 0.05, object_frame_}));
  if (publish_tf_) {
    tf_broadcaster_.sendTransform(
        conversions::to_transform_stamped(object.T_base_object.pose, rig_.frames.base, object_frame_, detection.stamp));
  }
}

void ObjectLocalizer::refuse(const Refusal& refusal) {
  int count = 0;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    count = ++refusals_[refusal.kind];
  }
  std_msgs::String msg;
  msg.data = refusal.kind + ": " + refusal.message;
  refusal_pub_.publish(msg);
  // The first of each kind in full, then every 100th, so a steady stream does not flood the log.
  if (count == 1 || count % 100 == 0) ROS_WARN("object_localizer (%d x %s): %s", count, refusal.kind.c_str(), refusal.message.c_str());
}

}  // namespace handeye
