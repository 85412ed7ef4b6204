// The calibration node: TF + pattern detections in, stamp-matched samples,
// /calibrate out as PoseWithCovarianceStamped, a static TF and a YAML file.
// The logic lives in the ROS-free core (Sampler, solve); this class is glue.
#pragma once

#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <tf2_ros/transform_listener.h>

#include <memory>
#include <cstdint>
#include <deque>
#include <mutex>
#include <optional>

#include "handeye_covariance/core/estimator.h"
#include "handeye_covariance/core/next_best_pose.h"
#include "handeye_covariance/core/session_config.h"
#include "handeye_covariance/ros/messages.h"
#include "handeye_covariance/ros/observations.h"
#include "handeye_covariance/core/sampler.h"
#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>

namespace handeye {

class CalibrationNode {
 public:
  /// Reads ~parameters (see config/calibration_defaults.yaml), advertises
  /// everything and, with ~resume, reloads the session file.
  explicit CalibrationNode(ros::NodeHandle node, ros::NodeHandle private_node);
  ~CalibrationNode();

 private:
  // Inputs: each gives a detection of the pattern (observations.h).
  void on_tags(const TagDetectionArray::ConstPtr& msg);
  void on_tf_poll(const ros::TimerEvent&);
  void observe(const Detection& detection);
  void handle(const Detection& detection);
  /// Counts a handled detection and its age (now - stamp) for ~status.
  void record_handled(const ros::Time& stamp);

  bool calibrate(Calibrate::Request&, Calibrate::Response&);
  bool take_sample(TakeSample::Request&, TakeSample::Response&);
  bool remove_sample(RemoveSample::Request&, RemoveSample::Response&);
  bool list_samples(ListSamples::Request&, ListSamples::Response&);
  bool reset(Reset::Request&, Reset::Response&);
  bool save_samples(SaveSamples::Request&, SaveSamples::Response&);
  bool load_samples(LoadSamples::Request&, LoadSamples::Response&);
  bool save_calibration(SaveCalibration::Request&, SaveCalibration::Response&);
  bool suggest_pose(SuggestPose::Request&, SuggestPose::Response&);
  /// The options and candidates for a suggestion (lock held; needs estimate_).
  SuggestOptions suggest_options(const std::string& criterion) const;
  std::vector<Eigen::Isometry3d> candidates(const SampleSet& set, const SuggestOptions& options) const;

  /// After the samples changed (lock held): persist, re-estimate, publish status.
  void samples_changed(const std::string& event);
  void refuse(const std::string& reason);
  void publish_status();
  /// The running estimate (~estimate) and its markers (~markers).
  void publish_estimate(const Calibration& c);
  SampleSet sample_set() const;

  SessionConfig config_;
  std::optional<MeasurementNoise> noise_;  // from config_.noise_config
  ros::NodeHandle node_, private_node_, detection_node_;
  ros::CallbackQueue detection_queue_;  // detections in order, on their own thread
  std::unique_ptr<ros::AsyncSpinner> detection_spinner_;
  tf2_ros::Buffer tf_buffer_;
  tf2_ros::TransformListener tf_listener_;
  tf2_ros::StaticTransformBroadcaster static_broadcaster_;
  ros::Subscriber detections_;
  ros::Timer tf_poll_, status_timer_;
  ros::Publisher calibration_pub_, estimate_pub_, status_pub_, markers_pub_;
  std::vector<ros::ServiceServer> services_;

  mutable std::mutex mutex_;  // guards everything below
  Sampler sampler_;
  std::optional<Calibration> estimate_;    // from the accepted samples, for ~status
  std::optional<Calibration> calibration_; // from the last successful /calibrate
  std::optional<ScoredPose> next_pose_;    // the best next pose for the current samples, for ~status
  std::vector<Eigen::Isometry3d> candidate_poses_;  // from config_.candidate_poses_file
  std::string last_event_ = "started";
  ros::Time last_tf_stamp_;
  std::uint32_t detections_received_ = 0;
  std::deque<double> detection_ages_;  // s, the last kAgeWindow handled detections
};

}  // namespace handeye
