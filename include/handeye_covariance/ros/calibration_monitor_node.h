// The calibration monitor (publish.launch monitor:=true): the published calibration
// checked continuously on still views of the target (session/calibration_monitor.h: a
// sliding window of the last ~monitor/window views), while a detector runs. It publishes
// diagnostic_msgs/DiagnosticArray on /diagnostics (OK / WARN / ERROR, the p-value, the
// estimated change) once a second and on each new view, and the latest check latched on
// ~check (CalibrationCheck.msg). It never changes the published TF. A calibration file
// that is not there yet is waited for, and one saved again is watched from then on
// (its time looked at every second).
#pragma once

#include <diagnostic_msgs/DiagnosticArray.h>
#include <ros/ros.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include <filesystem>
#include <memory>
#include <mutex>
#include <string>

#include "handeye_covariance/ros/detection_input.h"
#include "handeye_covariance/session/calibration_monitor.h"
#include "handeye_covariance/session/session_config.h"

namespace handeye {

class CalibrationMonitorNode {
 public:
  /// The node's settings as the calibration node's (frames, detection input, stillness,
  /// calibration_file), and ~monitor/window, ~monitor/min_views, ~monitor/warn_alpha,
  /// ~monitor/error_alpha.
  CalibrationMonitorNode(ros::NodeHandle node, ros::NodeHandle private_node);

 private:
  void observe(const Detection& detection);
  /// Reads the calibration file when the monitor has none yet or the file was written
  /// again since (the window starts over); `problem_` says why there is none. The robot
  /// and camera frames are the file's unless a parameter renames them (publish.launch's
  /// arguments, as the publisher), and a file of the other setup is refused.
  void load_calibration();  // mutex_ held
  void publish_diagnostics();  // mutex_ held

  SessionConfig config_;  // its rig's frames follow the calibration read (mutex_)
  Rig configured_rig_;  // the parameters' (or the defaults') frames
  bool renamed_parent_ = false, renamed_camera_ = false, renamed_pattern_parent_ = false;
  MonitorOptions options_;
  std::string name_;  // the diagnostic's name
  tf2_ros::Buffer tf_buffer_;
  tf2_ros::TransformListener tf_listener_;
  ros::Publisher diagnostics_pub_, check_pub_;
  ros::Timer timer_;
  std::mutex mutex_;
  std::unique_ptr<CalibrationMonitor> monitor_;
  std::string problem_;  // why there is no monitor yet
  std::filesystem::file_time_type loaded_;  // the file's time when it was read
  std::unique_ptr<DetectionInput> input_;
};

}  // namespace handeye
