#include "handeye_covariance/ros/calibration_node.h"

#include <tf2/exceptions.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <set>

#include "handeye_covariance/core/outliers.h"
#include "handeye_covariance/io/yaml_io.h"
#include "handeye_covariance/ros/covariance_markers.h"
#include "handeye_covariance/ros/msg_conversion.h"
#include "handeye_covariance/ros/observations.h"
#include "handeye_covariance/ros/params.h"

namespace handeye {

namespace {

constexpr double kDeg = M_PI / 180.0;
constexpr std::size_t kAgeWindow = 300;  // detections: 10 s at 30 Hz

/// The q-quantile (0..1) of `values`, by the nearest rank.
double quantile(std::vector<double> values, double q) {
  if (values.empty()) return 0.0;
  const auto k = static_cast<std::size_t>(std::min<double>(values.size() - 1, std::floor(q * values.size())));
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
  return values[k];
}

std::string expand_home(const std::string& path) {
  if (path.rfind("~/", 0) != 0) return path;
  const char* home = std::getenv("HOME");
  return std::string(home ? home : ".") + path.substr(1);
}

}  // namespace

CalibrationNode::CalibrationNode(ros::NodeHandle node, ros::NodeHandle private_node)
    : node_(node), private_node_(private_node), detection_node_(node), tf_listener_(tf_buffer_) {
  load_session_config(private_node_, config_);
  sampler_ = Sampler(config_.sampler);
  if (config_.calibration_file.empty()) config_.calibration_file = "~/.ros/handeye_covariance/" + config_.name() + ".yaml";
  if (config_.session_file.empty()) config_.session_file = "~/.ros/handeye_covariance/" + config_.name() + "_samples.yaml";
  config_.calibration_file = expand_home(config_.calibration_file);
  config_.session_file = expand_home(config_.session_file);
  if (!config_.noise_config.empty()) noise_ = io::read_noise_file(expand_home(config_.noise_config));
  criterion_from_string(config_.suggest_criterion);  // refuse a typo at start, not at the first sample
  if (!config_.candidate_poses_file.empty()) {
    candidate_poses_ = io::read_candidate_poses(expand_home(config_.candidate_poses_file));
  }

  if (config_.resume && std::filesystem::exists(config_.session_file)) {
    sampler_.set_samples(io::read_samples(config_.session_file).samples);
    ROS_INFO("resumed %zu samples from %s", sampler_.samples().size(), config_.session_file.c_str());
    last_event_ = "resumed " + std::to_string(sampler_.samples().size()) + " samples";
  }

  calibration_pub_ = private_node_.advertise<geometry_msgs::PoseWithCovarianceStamped>("calibration", 1, true);
  status_pub_ = private_node_.advertise<CalibrationStatus>("status", 10, true);
  markers_pub_ = private_node_.advertise<visualization_msgs::MarkerArray>("markers", 1, true);
  estimate_pub_ = private_node_.advertise<geometry_msgs::PoseWithCovarianceStamped>("estimate", 1, true);
  services_ = {
      node_.advertiseService("calibrate", &CalibrationNode::calibrate, this),
      node_.advertiseService("take_sample", &CalibrationNode::take_sample, this),
      node_.advertiseService("remove_sample", &CalibrationNode::remove_sample, this),
      node_.advertiseService("list_samples", &CalibrationNode::list_samples, this),
      node_.advertiseService("reset", &CalibrationNode::reset, this),
      node_.advertiseService("save_samples", &CalibrationNode::save_samples, this),
      node_.advertiseService("load_samples", &CalibrationNode::load_samples, this),
      node_.advertiseService("save_calibration", &CalibrationNode::save_calibration, this),
      node_.advertiseService("suggest_pose", &CalibrationNode::suggest_pose, this),
  };

  detection_node_.setCallbackQueue(&detection_queue_);
  const std::string& topic = config_.detections_topic;
  using geometry_msgs::PoseStamped;
  using geometry_msgs::PoseWithCovarianceStamped;
  if (config_.detection_input == "tags") {
    detections_ = detection_node_.subscribe(topic, 50, &CalibrationNode::on_tags, this);
  } else if (config_.detection_input == "pose_with_covariance") {
    detections_ = detection_node_.subscribe<PoseWithCovarianceStamped>(
        topic, 50, [this](const PoseWithCovarianceStamped::ConstPtr& msg) { observe(detection_of(*msg)); });
  } else if (config_.detection_input == "pose") {
    detections_ = detection_node_.subscribe<PoseStamped>(
        topic, 50, [this](const PoseStamped::ConstPtr& msg) { observe(detection_of(*msg)); });
  } else if (config_.detection_input == "tf") {
    tf_poll_ = detection_node_.createTimer(ros::Duration(1.0 / config_.tf_poll_rate), &CalibrationNode::on_tf_poll, this);
  } else {
    throw std::invalid_argument("~detection_input must be tags, pose_with_covariance, pose or tf, not `" +
                                config_.detection_input + "`");
  }
  detection_spinner_ = std::make_unique<ros::AsyncSpinner>(1, &detection_queue_);
  detection_spinner_->start();
  status_timer_ = node_.createTimer(ros::Duration(1.0), [this](const ros::TimerEvent&) {
    std::lock_guard<std::mutex> lock(mutex_);
    publish_status();
  });

  std::lock_guard<std::mutex> lock(mutex_);
  if (sampler_.samples().size() >= 3) samples_changed(last_event_);
  ROS_INFO("handeye calibration (%s): X = T_%s_%s; pattern from %s (%s); %zu samples",
           to_string(config_.rig.setup), config_.rig.camera_parent_frame().c_str(), config_.rig.frames.camera.c_str(),
           config_.detection_input.c_str(), config_.detection_input == "tf" ? config_.rig.frames.pattern.c_str() : topic.c_str(),
           sampler_.samples().size());
}

CalibrationNode::~CalibrationNode() {
  if (detection_spinner_) detection_spinner_->stop();
}

// ------------------------------------------------------------------ inputs

void CalibrationNode::on_tags(const TagDetectionArray::ConstPtr& msg) {
  std::optional<Refusal> refusal;
  const std::optional<Detection> detection = select_detection(*msg, config_.tag_ids, refusal);
  if (refusal) refuse(refusal->message);
  if (detection) {
    observe(*detection);
  } else {
    record_handled(msg->header.stamp);
  }
}

void CalibrationNode::on_tf_poll(const ros::TimerEvent&) {
  geometry_msgs::TransformStamped latest;
  try {
    // The latest camera -> pattern transform; its own stamp is then used for the robot.
    latest = tf_buffer_.lookupTransform(config_.rig.frames.camera, config_.rig.frames.pattern, ros::Time(0));
  } catch (const tf2::TransformException&) {
    return;  // pattern not seen (yet)
  }
  if (latest.header.stamp <= last_tf_stamp_) return;  // nothing new
  last_tf_stamp_ = latest.header.stamp;
  observe(detection_of(latest));
}

void CalibrationNode::observe(const Detection& detection) {
  handle(detection);
  record_handled(detection.stamp);
}

void CalibrationNode::record_handled(const ros::Time& stamp) {
  const double age = stamp.isZero() ? 0.0 : (ros::Time::now() - stamp).toSec();
  std::lock_guard<std::mutex> lock(mutex_);
  ++detections_received_;
  detection_ages_.push_back(age);
  if (detection_ages_.size() > kAgeWindow) detection_ages_.pop_front();
}

void CalibrationNode::handle(const Detection& detection) {
  // TF is filled live: wait (up to tf_timeout) for it to reach the detection's stamp.
  if (!detection.stamp.isZero()) {
    tf_buffer_.canTransform(config_.rig.frames.base, config_.rig.frames.effector, detection.stamp,
                            ros::Duration(config_.tf_timeout));
  }
  const ObservationResult result = make_observation(tf_buffer_, config_, detection);
  if (result.refusal) return refuse(result.refusal->message);

  std::lock_guard<std::mutex> lock(mutex_);
  const std::optional<SampleOutcome> outcome = sampler_.observe(*result.observation);
  if (!outcome) return;
  if (outcome->accepted) {
    samples_changed(outcome->message);
  } else {
    ROS_WARN("%s", outcome->message.c_str());
    last_event_ = outcome->message;
    publish_status();
  }
}

void CalibrationNode::refuse(const std::string& reason) {
  ROS_WARN_THROTTLE(2.0, "sample refused: %s", reason.c_str());
  std::lock_guard<std::mutex> lock(mutex_);
  last_event_ = "refused: " + reason;
}

// ------------------------------------------------------------------ state

SampleSet CalibrationNode::sample_set() const {
  return make_sample_set(config_.rig, noise_, sampler_.samples());
}

void CalibrationNode::samples_changed(const std::string& event) {
  last_event_ = event;
  ROS_INFO("%s (%zu samples)", event.c_str(), sampler_.samples().size());
  try {
    io::write_file_atomically(config_.session_file, io::format_samples(sample_set()));
  } catch (const HandEyeError& e) {
    ROS_ERROR("could not save the session: %s", e.what());
  }
  estimate_.reset();
  next_pose_.reset();
  if (sampler_.samples().size() >= 3) {
    try {
      const SampleSet set = sample_set();
      estimate_ = solve_samples(set, config_.reject_outliers);
      publish_estimate(*estimate_);
      const SampleSet kept = without_rejected(set, *estimate_);
      const SuggestOptions options = suggest_options(config_.suggest_criterion);
      const Suggestion s = rank_candidates(kept, *estimate_, candidates(kept, options), options);
      if (!s.ranked.empty()) next_pose_ = s.ranked.front();
    } catch (const HandEyeError& e) {
      last_event_ = event + (estimate_ ? "; no next pose: " : "; no estimate yet: ") + e.what();
    }
  }
  publish_status();
}

void CalibrationNode::publish_status() {  // called with mutex_ held
  CalibrationStatus status;
  status.header.stamp = ros::Time::now();
  status.samples = static_cast<int>(sampler_.samples().size());
  status.samples_needed = 3;
  status.last_event = last_event_;
  status.state = to_string(sampler_.state());
  status.parent_frame = config_.rig.camera_parent_frame();
  status.child_frame = config_.rig.frames.camera;
  status.working_distance = config_.working_distance;
  status.target_tolerance_mm = config_.target_tolerance_mm;
  status.detections_received = detections_received_;
  const std::vector<double> ages(detection_ages_.begin(), detection_ages_.end());
  status.detection_age_median_ms = quantile(ages, 0.5) * 1e3;
  status.detection_age_p99_ms = quantile(ages, 0.99) * 1e3;
  status.detection_age_max_ms = ages.empty() ? 0.0 : *std::max_element(ages.begin(), ages.end()) * 1e3;
  if (estimate_) {
    const PoseWithCovariance X{estimate_->T_parent_camera, estimate_->pose_covariance};
    status.has_estimate = true;
    status.estimate = conversions::to_msg(X);
    for (int i = 0; i < 3; ++i) {
      status.sigma_translation_mm[i] = std::sqrt(std::max(0.0, X.covariance(i, i))) * 1e3;
      status.sigma_rotation_deg[i] = std::sqrt(std::max(0.0, X.covariance(i + 3, i + 3))) / kDeg;
    }
    // An object on the optical axis at the working distance (the paper's 0.05 deg -> 0.6 mm at 70 cm).
    status.object_error_mm = object_sigma(X, config_.working_distance) * 1e3;
    status.target_reached = status.object_error_mm <= config_.target_tolerance_mm;
    for (const auto& r : estimate_->rejected) {
      status.rejected_samples.push_back(r.index);
      status.rejected_reasons.push_back(r.reason);
    }
  }
  if (next_pose_) {
    status.has_suggestion = true;
    status.next_pose.header.stamp = status.header.stamp;
    status.next_pose.header.frame_id = config_.rig.frames.base;
    status.next_pose.pose = conversions::to_pose_msg(next_pose_->T_base_effector);
    status.next_pose_object_error_mm = next_pose_->object_sigma * 1e3;
  }
  status_pub_.publish(status);
}

void CalibrationNode::publish_estimate(const Calibration& c) {
  geometry_msgs::PoseWithCovarianceStamped estimate;
  estimate.header.stamp = ros::Time::now();
  estimate.header.frame_id = config_.rig.camera_parent_frame();
  estimate.pose = conversions::to_msg(PoseWithCovariance{c.T_parent_camera, c.pose_covariance});
  estimate_pub_.publish(estimate);
  try {
    markers_pub_.publish(covariance_markers({c.T_parent_camera, c.pose_covariance}, config_.rig.camera_parent_frame(), ros::Time::now()));
  } catch (const HandEyeError& e) {
    ROS_WARN("cannot draw the covariance: %s", e.what());
  }
}

// ------------------------------------------------------------------ services

bool CalibrationNode::calibrate(Calibrate::Request&, Calibrate::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  const SampleSet set = sample_set();
  try {
    calibration_ = solve_samples(set, config_.reject_outliers);
  } catch (const HandEyeError& e) {
    res.success = false;
    res.message = e.what();
    res.samples_used = static_cast<int>(set.samples.size());
    ROS_WARN("calibrate: %s", e.what());
    return true;
  }
  const Calibration& c = *calibration_;
  res.success = true;
  res.calibration.header.stamp = ros::Time::now();
  res.calibration.header.frame_id = config_.rig.camera_parent_frame();
  res.calibration.pose = conversions::to_msg(PoseWithCovariance{c.T_parent_camera, c.pose_covariance});
  res.rotation_covariance = conversions::to_msg_array(c.rotation_covariance);
  res.translation_covariance = conversions::to_msg_array(c.translation_covariance);
  res.samples_used = c.samples_used;
  res.rotation_iterations = c.rotation_stage.iterations;
  res.translation_iterations = c.translation_stage.iterations;
  res.rotation_stop_reason = to_string(c.rotation_stage.stop_reason);
  res.translation_stop_reason = to_string(c.translation_stage.stop_reason);
  res.rotation_chi2_per_dof = c.rotation_stage.chi2 / std::max(1, c.rotation_stage.dof);
  res.translation_chi2_per_dof = c.translation_stage.chi2 / std::max(1, c.translation_stage.dof);
  res.noise_origin = c.noise_origin == NoiseOrigin::Given ? "given" : "estimated_from_residuals";
  res.warnings = c.warnings;
  for (const auto& r : c.rejected) {
    res.rejected_samples.push_back(r.index);
    res.rejected_reasons.push_back(r.reason);
  }
  res.message = "X = T_" + config_.rig.camera_parent_frame() + "_" + config_.rig.frames.camera + " from " + std::to_string(c.samples_used) +
                " samples; worst-axis 1 sigma " + number_text(max_sigma(c.translation_covariance) * 1e3) + " mm, " +
                number_text(max_sigma(c.rotation_covariance) / kDeg) + " deg";

  calibration_pub_.publish(res.calibration);
  publish_estimate(c);
  if (config_.publish_tf) {
    geometry_msgs::TransformStamped tf;
    tf.header = res.calibration.header;
    tf.child_frame_id = config_.rig.frames.camera;
    tf.transform = conversions::to_transform_msg(c.T_parent_camera);
    static_broadcaster_.sendTransform(tf);
  }
  try {
    io::write_file_atomically(config_.calibration_file, io::format_result(c, io::context_of(set)));
    res.calibration_file = config_.calibration_file;
  } catch (const HandEyeError& e) {
    res.message += "; but the result file could not be written: " + std::string(e.what());
  }
  ROS_INFO("calibrate: %s", res.message.c_str());
  return true;
}

bool CalibrationNode::take_sample(TakeSample::Request&, TakeSample::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  const SampleOutcome outcome = sampler_.take_sample(ros::Time::now().toSec());
  res.success = outcome.accepted;
  res.message = outcome.message;
  if (outcome.accepted) {
    samples_changed(outcome.message);
  } else {
    last_event_ = outcome.message;
  }
  res.samples = static_cast<int>(sampler_.samples().size());
  return true;
}

bool CalibrationNode::remove_sample(RemoveSample::Request& req, RemoveSample::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  const std::size_t count = sampler_.samples().size();
  res.success = req.index >= 0 && sampler_.remove(static_cast<std::size_t>(req.index));
  res.message = res.success ? "removed sample " + std::to_string(req.index)
                            : "no sample " + std::to_string(req.index) + ": valid indices are 0.." +
                                  std::to_string(static_cast<long>(count) - 1) + " (see list_samples)";
  if (res.success) samples_changed(res.message);
  res.samples = static_cast<int>(sampler_.samples().size());
  return true;
}

bool CalibrationNode::list_samples(ListSamples::Request&, ListSamples::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  for (const PoseSample& s : sampler_.samples()) {
    res.effector_poses.push_back(conversions::to_pose_msg(s.T_base_effector));
    res.pattern_poses.push_back(conversions::to_pose_msg(s.T_camera_pattern));
    res.stamps.push_back(s.stamp.value_or(0.0));
  }
  res.samples = static_cast<int>(sampler_.samples().size());
  return true;
}

bool CalibrationNode::reset(Reset::Request&, Reset::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  sampler_.reset();
  samples_changed("reset: all samples dropped");
  res.success = true;
  res.message = "all samples dropped";
  return true;
}

bool CalibrationNode::save_samples(SaveSamples::Request& req, SaveSamples::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  try {
    io::write_file_atomically(expand_home(req.path), io::format_samples(sample_set()));
    res.success = true;
    res.message = "saved " + std::to_string(sampler_.samples().size()) + " samples to " + expand_home(req.path);
  } catch (const HandEyeError& e) {
    res.success = false;
    res.message = e.what();
  }
  return true;
}

bool CalibrationNode::load_samples(LoadSamples::Request& req, LoadSamples::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  try {
    const SampleSet loaded = io::read_samples(expand_home(req.path));
    if (loaded.rig.setup != config_.rig.setup) {
      throw HandEyeError(ErrorCode::MalformedFile,
                         std::string("the file is ") + to_string(loaded.rig.setup) + " but this node is " +
                             to_string(config_.rig.setup),
                         req.path, "load a file recorded with the same setup");
    }
    sampler_.set_samples(loaded.samples);
    res.success = true;
    res.message = "loaded " + std::to_string(loaded.samples.size()) + " samples from " + req.path;
    samples_changed(res.message);
  } catch (const HandEyeError& e) {
    res.success = false;
    res.message = e.what();  // the current samples are kept
  }
  res.samples = static_cast<int>(sampler_.samples().size());
  return true;
}

bool CalibrationNode::save_calibration(SaveCalibration::Request& req, SaveCalibration::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  res.path = req.path.empty() ? config_.calibration_file : expand_home(req.path);
  if (!calibration_) {
    res.success = false;
    res.message = "no calibration yet: call calibrate first";
    return true;
  }
  try {
    io::write_file_atomically(res.path, io::format_result(*calibration_, io::context_of(sample_set())));
    res.success = true;
    res.message = "saved to " + res.path;
  } catch (const HandEyeError& e) {
    res.success = false;
    res.message = e.what();
  }
  return true;
}

}  // namespace handeye

namespace handeye {

SuggestOptions CalibrationNode::suggest_options(const std::string& criterion) const {
  SuggestOptions options;
  options.criterion = criterion_from_string(criterion.empty() ? config_.suggest_criterion : criterion);
  options.working_distance = config_.working_distance;
  options.candidates = config_.suggest_candidates;
  options.max_step_translation = config_.reach_translation;
  options.max_step_rotation = config_.reach_rotation;
  options.min_translation = config_.sampler.min_translation;
  options.min_rotation = config_.sampler.min_rotation;
  options.seed = static_cast<unsigned>(sampler_.samples().size());  // fresh candidates after each sample
  return options;
}

std::vector<Eigen::Isometry3d> CalibrationNode::candidates(const SampleSet& set, const SuggestOptions& options) const {
  return candidate_poses_.empty() ? sample_candidates(set, *estimate_, options) : candidate_poses_;
}

bool CalibrationNode::suggest_pose(SuggestPose::Request& req, SuggestPose::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!estimate_) {
    res.message = "no estimate yet: " + std::to_string(sampler_.samples().size()) +
                  " sample(s); take at least 3 (rotating about different axes) first";
    return true;
  }
  try {
    const SampleSet set = without_rejected(sample_set(), *estimate_);
    const SuggestOptions options = suggest_options(req.criterion);
    const Suggestion s = rank_candidates(set, *estimate_, candidates(set, options), options);
    if (s.ranked.empty()) {
      throw HandEyeError(ErrorCode::NoData, "every candidate was refused by the prediction", "candidates",
                         "give candidates that rotate about new axes, or raise reach_translation_mm/reach_rotation_deg");
    }
    const double target = (req.target_mm > 0.0 ? req.target_mm : config_.target_tolerance_mm) * 1e-3;
    const Plan plan = plan_poses(set, *estimate_, target, 30, options, candidate_poses_);
    const auto stamped = [&](const Eigen::Isometry3d& E) {
      geometry_msgs::PoseStamped pose;
      pose.header.stamp = ros::Time::now();
      pose.header.frame_id = config_.rig.frames.base;
      pose.pose = conversions::to_pose_msg(E);
      return pose;
    };
    const int count = req.count > 0 ? req.count : 5;
    for (int i = 0; i < count && i < static_cast<int>(s.ranked.size()); ++i) {
      res.poses.push_back(stamped(s.ranked[i].T_base_effector));
      res.predicted_object_error_mm.push_back(s.ranked[i].object_sigma * 1e3);
    }
    for (const ScoredPose& p : plan.poses) res.plan.push_back(stamped(p.T_base_effector));
    res.current_object_error_mm = s.current_object_sigma * 1e3;
    res.poses_to_target = plan.reached ? static_cast<int>(plan.poses.size()) : -1;
    res.success = true;
    res.message = plan.reached ? std::to_string(plan.poses.size()) + " more pose(s) reach " +
                                     number_text(target * 1e3) + " mm (predicted)"
                               : "the target " + number_text(target * 1e3) + " mm is not reached within 30 more poses";
  } catch (const HandEyeError& e) {
    res.message = e.what();
  }
  return true;
}

}  // namespace handeye
