#include "handeye_covariance/ros/calibration_monitor_node.h"

#include <filesystem>

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/core/units.h"
#include "handeye_covariance/io/yaml_io.h"
#include "handeye_covariance/ros/msg_conversion.h"
#include "handeye_covariance/ros/params.h"
#include "handeye_covariance/session/calibration_session.h"

namespace handeye {

CalibrationMonitorNode::CalibrationMonitorNode(ros::NodeHandle node, ros::NodeHandle private_node)
    : config_(node_session_config(private_node)), tf_listener_(tf_buffer_) {
  // X's frames and the pattern's parent as publish.launch publishes them: the file's, unless a
  // parameter names (renames) them; empty is not given, as for the publisher.
  const bool eye_in_hand = config_.rig.eye_in_hand();
  const auto given = [&](const char* key) { return !param<std::string>(private_node, key, "").empty(); };
  renamed_parent_ = given(eye_in_hand ? "robot_effector_frame" : "robot_base_frame");
  renamed_camera_ = given("tracking_base_frame");
  renamed_pattern_parent_ = given(eye_in_hand ? "robot_base_frame" : "robot_effector_frame");
  configured_rig_ = config_.rig;
  options_.window = param(private_node, "monitor/window", options_.window);
  options_.min_views = param(private_node, "monitor/min_views", options_.min_views);
  options_.warn_alpha = param(private_node, "monitor/warn_alpha", options_.warn_alpha);
  options_.error_alpha = param(private_node, "monitor/error_alpha", options_.error_alpha);
  options_.sampler = config_.sampler;
  name_ = "handeye_covariance: " + config_.name() + " calibration check";
  diagnostics_pub_ = node.advertise<diagnostic_msgs::DiagnosticArray>("/diagnostics", 10);
  check_pub_ = private_node.advertise<CalibrationCheckMsg>("check", 1, true);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    load_calibration();
    publish_diagnostics();
  }
  timer_ = node.createTimer(ros::Duration(1.0), [this](const ros::TimerEvent&) {
    std::lock_guard<std::mutex> lock(mutex_);
    load_calibration();
    publish_diagnostics();
  });
  input_ = std::make_unique<DetectionInput>(
      node, config_.detection_input, config_.detections_topic, config_.tag_ids, config_.tf_poll_rate, tf_buffer_,
      config_.rig.frames, [this](const Detection& d) { observe(d); },
      [](const ros::Time&, const std::optional<Refusal>& refusal) {
        if (refusal) ROS_WARN_THROTTLE(10.0, "monitor: %s", refusal->message.c_str());
      });
  ROS_INFO("calibration monitor: %s on still views of %s, windows of %d (never changes the published TF)",
           config_.calibration_file.c_str(), config_.detection_input.c_str(), options_.window);
}

void CalibrationMonitorNode::load_calibration() {
  std::error_code error;
  const auto written = std::filesystem::last_write_time(config_.calibration_file, error);
  if (error) {
    if (!monitor_) problem_ = "no calibration at " + config_.calibration_file + " yet (read again every second)";
    return;
  }
  if (monitor_ && written == loaded_) return;  // a calibration saved again is watched from then on
  loaded_ = written;
  monitor_.reset();
  try {
    const io::CalibrationFile file = io::read_result(config_.calibration_file);
    Rig rig = configured_rig_;  // each file's frames over the parameters', not over an earlier file's
    const auto adopt = [](std::string& frame, bool renamed, const std::string& saved) {
      if (!renamed && !saved.empty()) frame = saved;
    };
    adopt(rig.camera_parent_frame(), renamed_parent_, file.context.parent);
    adopt(rig.frames.camera, renamed_camera_, file.context.child);
    adopt(rig.pattern_parent_frame(), renamed_pattern_parent_, file.context.pattern_parent);
    Rig as_saved = rig;  // a renamed frame is the file's under its new name
    if (renamed_parent_) as_saved.camera_parent_frame() = file.context.parent;
    if (renamed_camera_) as_saved.frames.camera = file.context.child;
    const Calibration calibration = io::calibration_to_check(file, as_saved, config_.calibration_file);
    config_.rig = rig;
    SessionSettings settings = session_settings(config_);
    monitor_ = std::make_unique<CalibrationMonitor>(calibration, settings.rig, settings.noise, options_);
    problem_.clear();
    ROS_INFO("monitor: watching %s", config_.calibration_file.c_str());
  } catch (const HandEyeError& e) {
    problem_ = e.what();
    ROS_ERROR_THROTTLE(30.0, "monitor: %s", problem_.c_str());
  }
}

void CalibrationMonitorNode::observe(const Detection& detection) {
  Rig rig;  // the frames of the calibration watched (load_calibration sets them)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!monitor_) return;
    rig = config_.rig;
  }
  if (!detection.stamp.isZero()) {
    tf_buffer_.canTransform(rig.frames.base, rig.frames.effector, detection.stamp, ros::Duration(config_.tf_timeout));
  }
  const ObservationResult result = make_observation(tf_buffer_, rig, detection);
  if (result.refusal) {
    ROS_WARN_THROTTLE(10.0, "monitor: %s", result.refusal->message.c_str());
    return;
  }
  std::lock_guard<std::mutex> lock(mutex_);
  if (!monitor_) return;
  std::optional<MonitorVerdict> verdict;
  try {
    verdict = monitor_->observe(*result.observation);
  } catch (const HandEyeError& e) {
    problem_ = e.what();
    ROS_ERROR_THROTTLE(10.0, "monitor: %s", problem_.c_str());
    return;
  }
  if (!verdict) return;
  if (verdict->level == MonitorLevel::Error) ROS_ERROR_THROTTLE(5.0, "monitor: %s", verdict->message.c_str());
  if (verdict->check) check_pub_.publish(conversions::to_msg(*verdict->check, ros::Time::now()));
  publish_diagnostics();
}

void CalibrationMonitorNode::publish_diagnostics() {  // mutex_ held
  diagnostic_msgs::DiagnosticArray array;
  array.header.stamp = ros::Time::now();
  diagnostic_msgs::DiagnosticStatus status;
  status.name = name_;
  status.hardware_id = config_.rig.camera_parent_frame() + " -> " + config_.rig.frames.camera;
  const auto value = [&](const std::string& key, const std::string& text) {
    diagnostic_msgs::KeyValue kv;
    kv.key = key;
    kv.value = text;
    status.values.push_back(kv);
  };
  if (!monitor_) {
    status.level = diagnostic_msgs::DiagnosticStatus::WARN;
    status.message = problem_;
  } else {
    const MonitorVerdict& v = monitor_->latest();
    status.level = v.level == MonitorLevel::Error  ? diagnostic_msgs::DiagnosticStatus::ERROR
                   : v.level == MonitorLevel::Warn ? diagnostic_msgs::DiagnosticStatus::WARN
                                                   : diagnostic_msgs::DiagnosticStatus::OK;
    status.message = v.message;
    value("level", to_string(v.level));
    value("views", std::to_string(v.views));
    if (v.check) {
      value("p_value", number_text(v.check->p_value, 3));
      value("chi2_per_dof", number_text(v.check->chi2 / std::max(1, v.check->dof), 3));
      if (v.check->changed) {
        value("changed", to_string(*v.check->change.what));
        const EstimatedChange::Delta& d = v.check->change.reported();
        value("change_mm", number_text(millimetres(d.value.head<3>().norm()), 3));
        value("change_deg", number_text(degrees(d.value.tail<3>().norm()), 3));
      }
    }
  }
  array.status.push_back(status);
  diagnostics_pub_.publish(array);
}

}  // namespace handeye
