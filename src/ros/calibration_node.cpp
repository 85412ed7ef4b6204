#include "handeye_covariance/ros/calibration_node.h"

#include <sys/resource.h>
#include <sys/syscall.h>
#include <tf2/exceptions.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <fstream>

#include "handeye_covariance/core/statistics.h"
#include "handeye_covariance/core/units.h"
#include "handeye_covariance/corners/corner_calibration.h"
#include "handeye_covariance/estimation/split_check.h"
#include "handeye_covariance/io/summary.h"
#include "handeye_covariance/io/warning_text.h"
#include "handeye_covariance/io/yaml_io.h"
#include "handeye_covariance/ros/covariance_markers.h"
#include "handeye_covariance/ros/msg_conversion.h"
#include "handeye_covariance/ros/params.h"
#include "handeye_covariance/session/report.h"

namespace handeye {

namespace {

constexpr std::size_t kAgeWindow = 300;  // detections: 10 s at 30 Hz

/// The session's settings, with the corner estimator for method corners.
SessionSettings node_session_settings(const SessionConfig& config) {
  SessionSettings settings = session_settings(config);
  settings.refine_corners = corner_refiner();
  return settings;
}

geometry_msgs::PoseStamped stamped(const Eigen::Isometry3d& E, const std::string& frame) {
  geometry_msgs::PoseStamped pose;
  pose.header.stamp = ros::Time::now();
  pose.header.frame_id = frame;
  pose.pose = conversions::to_pose_msg(E);
  return pose;
}

}  // namespace

CalibrationNode::CalibrationNode(ros::NodeHandle node, ros::NodeHandle private_node)
    : config_(node_session_config(private_node)),
      node_(node),
      private_node_(private_node),
      detection_node_(node),
      tf_listener_(tf_buffer_),
      session_(node_session_settings(config_)) {
  if (config_.resume) {
    const SessionEvent resumed = session_.resume();
    ROS_INFO("%s (%s)", resumed.message.c_str(), session_.settings().session_file.c_str());
    if (resumed.success) last_event_ = resumed.message;
  }

  calibration_pub_ = private_node_.advertise<geometry_msgs::PoseWithCovarianceStamped>("calibration", 1, true);
  pattern_pub_ = private_node_.advertise<geometry_msgs::PoseWithCovarianceStamped>("pattern", 1, true);
  status_pub_ = private_node_.advertise<CalibrationStatus>("status", 10, true);
  markers_pub_ = private_node_.advertise<visualization_msgs::MarkerArray>("markers", 1, true);
  next_pose_pub_ = private_node_.advertise<visualization_msgs::MarkerArray>("next_pose_markers", 1, true);
  check_pub_ = private_node_.advertise<CalibrationCheckMsg>("check", 1, true);
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
      node_.advertiseService("check_calibration", &CalibrationNode::check_calibration, this),
  };

  detection_node_.setCallbackQueue(&detection_queue_);
  input_ = std::make_unique<DetectionInput>(
      detection_node_, config_.detection_input, config_.detections_topic, config_.tag_ids, config_.tf_poll_rate,
      tf_buffer_, config_.rig.frames, [this](const Detection& d) { observe(d); },
      [this](const ros::Time& stamp, const std::optional<Refusal>& refusal) {
        if (refusal) {
          ROS_WARN_THROTTLE(2.0, "sample refused: %s", refusal->message.c_str());
          std::lock_guard<std::mutex> lock(mutex_);
          last_event_ = "refused: " + refusal->message;
        }
        record_handled(stamp);
      });
  status_timer_ = node_.createTimer(ros::Duration(1.0), [this](const ros::TimerEvent&) {
    std::lock_guard<std::mutex> lock(mutex_);
    publish_status();
  });
  republish_saved_calibration();
  // The TF listener needs a moment to learn the camera's tree before X is hung from its root.
  tf_refresh_ = node_.createTimer(ros::Duration(1.0), [this](const ros::TimerEvent&) {
    std::lock_guard<std::mutex> outputs(output_mutex_);
    refresh_tf();
  });
  if (param(private_node_, "motion/enabled", false)) {  // the robot moving itself (ros/arm_mover.h)
    SessionAccess access;
    access.session = &session_;
    access.snapshot = [this] {
      std::lock_guard<std::mutex> lock(mutex_);
      return session_.snapshot();
    };
    access.samples = [this] {
      std::lock_guard<std::mutex> lock(mutex_);
      return session_.samples().size();
    };
    access.take_sample = [this](double now) {
      std::lock_guard<std::mutex> lock(mutex_);
      const SessionEvent event = session_.take_sample(now);
      record(event, true);
      return event;
    };
    access.progress = [this](double target) -> std::pair<bool, std::optional<TargetProgress>> {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!analysis_ || analysis_->generation != session_.generation()) return {false, std::nullopt};
      if (!analysis_->estimate) return {true, std::nullopt};
      return {true, target_progress(*analysis_->estimate, target, config_.working_distance)};
    };
    access.analysis = [this]() -> std::optional<Analysis> {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!analysis_ || analysis_->generation != session_.generation()) return std::nullopt;
      return analysis_;
    };
    access.show_plan = [this](const std::optional<ScoredPose>& view) {
      std::lock_guard<std::mutex> lock(mutex_);
      planned_view_ = view;
      publish_next_pose();
      publish_status();
    };
    motion_ = true;
    mover_ = std::make_unique<ArmMover>(node_, private_node_, std::move(access));
  }
  worker_ = std::thread(&CalibrationNode::work, this);  // last: nothing below may throw
  detection_spinner_ = std::make_unique<ros::AsyncSpinner>(1, &detection_queue_);
  detection_spinner_->start();
  const Rig& rig = config_.rig;
  ROS_INFO("handeye calibration (%s): X = T_%s_%s; pattern from %s (%s); %zu samples", to_string(rig.setup),
           rig.camera_parent_frame().c_str(), rig.frames.camera.c_str(), config_.detection_input.c_str(),
           config_.detection_input == "tf" ? rig.frames.pattern.c_str() : config_.detections_topic.c_str(), session_.samples().size());
  if (session_.settings().rig.symmetric_face) {
    ROS_WARN("the target (%s) looks the same turned by 180 degrees: each view's pose is one of two candidates, "
             "decided from the robot's motion on /calibrate (views that cannot be decided are left out and named). A "
             "board with one even and one odd number of inner corners avoids this decision.",
             config_.target_file.c_str());
  }
}

CalibrationNode::~CalibrationNode() {
  if (detection_spinner_) detection_spinner_->stop();
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  work_.notify_all();
  if (worker_.joinable()) worker_.join();
}

// ------------------------------------------------------------------ inputs (detection thread)

void CalibrationNode::observe(const Detection& detection) {
  // TF is filled live: wait (up to tf_timeout) for it to reach the detection's stamp.
  if (!detection.stamp.isZero()) {
    tf_buffer_.canTransform(config_.rig.frames.base, config_.rig.frames.effector, detection.stamp,
                            ros::Duration(config_.tf_timeout));
  }
  const ObservationResult result = make_observation(tf_buffer_, config_.rig, detection);
  if (result.refusal) ROS_WARN_THROTTLE(2.0, "sample refused: %s", result.refusal->message.c_str());
  if (!result.corners_dropped.empty() && session_.settings().method == Method::Corners) {
    ROS_WARN_THROTTLE(10.0, "%s", result.corners_dropped.c_str());
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);  // the short lock: the sampler, and a file write when a sample is taken
    if (result.refusal) {
      last_event_ = "refused: " + result.refusal->message;
    } else if (const std::optional<SessionEvent> event = session_.observe(*result.observation)) {
      if (!event->success) ROS_WARN("%s", event->message.c_str());
      record(*event, true);
    }
  }
  record_handled(detection.stamp);
}

void CalibrationNode::record_handled(const ros::Time& stamp) {
  const double age = stamp.isZero() ? 0.0 : (ros::Time::now() - stamp).toSec();
  std::lock_guard<std::mutex> lock(mutex_);
  ++detections_received_;
  detection_ages_.push_back(age);
  if (detection_ages_.size() > kAgeWindow) detection_ages_.pop_front();
}

// ------------------------------------------------------------------ the session's changes and the worker

void CalibrationNode::record(const SessionEvent& event, bool appended) {  // lock held
  last_event_ = event.message;
  if (event.check) {
    ROS_INFO("%s", event.message.c_str());
    check_pub_.publish(check_message());
  }
  if (event.changed && !appended) {  // the analysis describes samples that are gone
    analysis_.reset();
    last_removal_ = session_.generation();
  }
  if (event.changed) {
    ROS_INFO("%s (%zu samples)", event.message.c_str(), session_.samples().size());
    work_.notify_one();
    publish_next_pose();  // cleared until the worker has analysed the new samples
  }
  if (!event.persist_error.empty()) {
    ROS_ERROR("could not save the session: %s", event.persist_error.c_str());
    last_event_ += "; the session file could not be written: " + event.persist_error;
  }
  publish_status();
}

void CalibrationNode::work() {
  // Below the detection thread: on two cores a ranking must not take the CPU from the inputs.
  setpriority(PRIO_PROCESS, static_cast<id_t>(::syscall(SYS_gettid)), 10);
  std::unique_lock<std::mutex> lock(mutex_);
  std::uint64_t analysed = session_.samples().empty() ? session_.generation() : ~std::uint64_t{0};
  while (true) {
    work_.wait(lock, [&] { return stopping_ || session_.generation() != analysed; });
    if (stopping_) return;
    const SessionSnapshot snapshot = session_.snapshot();
    analysed = snapshot.generation;
    lock.unlock();
    Analysis analysis;
    try {
      analysis = session_.analyse(snapshot);  // const, reads only the immutable settings
    } catch (const std::exception& e) {       // analyse reports HandEyeErrors itself; anything else is a bug
      analysis.generation = snapshot.generation;
      analysis.samples = snapshot.samples.samples.size();
      analysis.problem = std::string("internal error in the analysis: ") + e.what();
      ROS_ERROR("%s", analysis.problem.c_str());
    }
    lock.lock();
    // Samples removed since the snapshot make it stale; samples only appended do not
    // (it is shown until the next analysis, with estimate_samples saying how many).
    if (analysis.generation < last_removal_) continue;
    analysis_ = std::move(analysis);
    if (analysis_->estimate) publish_estimate(*analysis_->estimate);
    publish_next_pose();
    publish_status();
  }
}

std::optional<ScoredPose> CalibrationNode::next_view() const {  // lock held
  // With the robot moving itself, the next pose is where the arm goes: the mover's plan.
  if (motion_) return planned_view_;
  return analysis_ ? analysis_->next_pose : std::nullopt;
}

void CalibrationNode::publish_next_pose() {  // lock held
  std::optional<Eigen::Isometry3d> pose;
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  std::string label;
  // Drawn only while it is of the current samples, as ~status's has_suggestion.
  const std::optional<ScoredPose> next = next_view();
  if (analysis_ && analysis_->generation == session_.generation() && analysis_->estimate && next) {
    pose = next->T_base_effector;
    X = analysis_->estimate->T_parent_camera;
    // ASCII: rviz's text markers draw no Greek letters or arrows.
    label = "next pose: object " +
            number_text(millimetres(object_sigma({X, analysis_->estimate->pose_covariance}, config_.working_distance)), 3) +
            " -> " + number_text(millimetres(next->object_sigma), 3) + " mm (1 sigma)";
  }
  next_pose_pub_.publish(next_pose_markers(config_.rig, pose, X, config_.working_distance, label,
                                           config_.rig.frames.base, ros::Time::now()));
}

void CalibrationNode::publish_status() {  // lock held
  CalibrationStatus status;
  status.header.stamp = ros::Time::now();
  status.samples = static_cast<int>(session_.samples().size());
  status.samples_needed = CalibrationSession::kMinimumSamples;
  status.last_event = last_event_;
  status.state = to_string(session_.state());
  status.parent_frame = config_.rig.camera_parent_frame();
  status.child_frame = config_.rig.frames.camera;
  status.working_distance = config_.working_distance;
  status.target_tolerance_mm = config_.target_tolerance_mm;
  status.detections_received = detections_received_;
  const std::vector<double> ages(detection_ages_.begin(), detection_ages_.end());
  status.detection_age_median_ms = milliseconds(linear_quantile(ages, 0.5));
  status.detection_age_p99_ms = milliseconds(linear_quantile(ages, 0.99));
  status.detection_age_max_ms = ages.empty() ? 0.0 : milliseconds(*std::max_element(ages.begin(), ages.end()));
  // The latest analysis: of the current samples, or of fewer while the worker
  // catches up with a new one (estimate_samples says which).
  const bool current = analysis_ && analysis_->generation == session_.generation();
  if (current && !analysis_->problem.empty()) status.last_event += "; " + analysis_->problem;
  if (analysis_ && analysis_->estimate) {
    status.estimate_samples = static_cast<int>(analysis_->samples);
    const Calibration& c = *analysis_->estimate;
    const PoseWithCovariance X{c.T_parent_camera, c.pose_covariance};
    status.has_estimate = true;
    status.estimate = conversions::to_msg(X);
    for (int i = 0; i < 3; ++i) {
      status.sigma_translation_mm[i] = millimetres(std::sqrt(std::max(0.0, X.covariance(i, i))));
      status.sigma_rotation_deg[i] = degrees(std::sqrt(std::max(0.0, X.covariance(i + 3, i + 3))));
    }
    // An object on the optical axis at the working distance (the paper's 0.05 deg -> 0.6 mm at 70 cm).
    const TargetProgress progress = target_progress(c, metres(config_.target_tolerance_mm), config_.working_distance);
    status.object_error_mm = millimetres(progress.object_sigma);
    status.target_reached = progress.reached;
    if (!progress.why_not.empty()) status.last_event += "; " + progress.why_not;
    for (const auto& r : c.rejected) {
      status.rejected_samples.push_back(r.index);
      status.rejected_reasons.push_back(io::rejected_text(r));
    }
  }
  if (current) {
    for (const SampleFit& fit : analysis_->fits) {
      status.sample_residual_mm.push_back(millimetres(fit.translation));
      status.sample_residual_deg.push_back(degrees(fit.rotation));
      status.sample_residual_sigma.push_back(fit.sigmas);
    }
  }
  if (const std::optional<ScoredPose> next = current ? next_view() : std::nullopt) {
    status.has_suggestion = true;
    status.next_pose = stamped(next->T_base_effector, config_.rig.frames.base);
    status.next_pose.header.stamp = status.header.stamp;
    status.next_pose_object_error_mm = millimetres(next->object_sigma);
  }
  status_pub_.publish(status);
}

void CalibrationNode::publish_estimate(const Calibration& c) {
  const geometry_msgs::PoseWithCovarianceStamped estimate = conversions::to_stamped_msg(
      {c.T_parent_camera, c.pose_covariance}, config_.rig.camera_parent_frame(), ros::Time::now());
  estimate_pub_.publish(estimate);
  try {
    markers_pub_.publish(covariance_markers({c.T_parent_camera, c.pose_covariance}, config_.rig.camera_parent_frame(),
                                            estimate.header.stamp));
  } catch (const HandEyeError& e) {
    ROS_WARN("cannot draw the covariance: %s", e.what());
  }
}

// ------------------------------------------------------------------ TF

std::string CalibrationNode::refresh_tf() {
  if (!config_.publish_tf || !tf_X_) return "";
  return tf_edges_.publish_camera(tf_buffer_, config_.rig, *tf_X_);
}

void CalibrationNode::republish_saved_calibration() {
  const std::string& path = config_.calibration_file;
  if (!std::ifstream(path)) {
    ROS_INFO("no saved calibration at %s yet", path.c_str());
    return;
  }
  io::StoredCalibration stored;
  try {
    stored = io::read_stored_calibration(path);
  } catch (const HandEyeError& e) {
    ROS_WARN("the saved calibration is not published: %s", e.what());
    return;
  }
  const Rig& rig = config_.rig;
  if (!io::is_calibration_of(rig, stored.setup, stored.parent, stored.child)) {
    ROS_WARN("the saved calibration %s is T_%s_%s (%s), this node calibrates T_%s_%s (%s): not published; "
             "/calibrate replaces it", path.c_str(), stored.parent.c_str(), stored.child.c_str(),
             stored.setup ? to_string(*stored.setup) : "setup not given", rig.camera_parent_frame().c_str(),
             rig.frames.camera.c_str(), to_string(rig.setup));
    return;
  }
  if (stored.has_covariance) {
    calibration_pub_.publish(conversions::to_stamped_msg(stored.T_parent_camera, rig.camera_parent_frame(), ros::Time::now()));
  }
  {
    std::lock_guard<std::mutex> outputs(output_mutex_);
    tf_X_ = stored.T_parent_camera.pose;
  }
  std::lock_guard<std::mutex> lock(mutex_);
  last_event_ = "published the saved calibration " + path + (stored.has_covariance ? "" : " (TF only: it has no covariance)");
  ROS_INFO("%s", last_event_.c_str());
}

// ------------------------------------------------------------------ services

bool CalibrationNode::calibrate(Calibrate::Request&, Calibrate::Response& res) {
  SessionSnapshot snapshot;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    snapshot = session_.snapshot();
  }
  Calibration c;
  try {
    c = session_.calibrate_checked(snapshot);  // on the snapshot: no lock, no wait behind the worker
  } catch (const HandEyeError& e) {
    res.success = false;
    res.message = e.what();
    res.samples_used = static_cast<int>(snapshot.samples.samples.size());
    ROS_WARN("calibrate: %s", e.what());
    return true;
  }
  res.success = true;
  res.calibration =
      conversions::to_stamped_msg({c.T_parent_camera, c.pose_covariance}, config_.rig.camera_parent_frame(), ros::Time::now());
  res.rotation_covariance = conversions::to_msg_array(c.rotation_covariance);
  res.translation_covariance = conversions::to_msg_array(c.translation_covariance);
  res.samples_used = c.samples_used;
  res.rotation_iterations = c.rotation_stage.iterations;
  res.translation_iterations = c.translation_stage.iterations;
  res.rotation_stop_reason = to_string(c.rotation_stage.stop_reason);
  res.translation_stop_reason = to_string(c.translation_stage.stop_reason);
  res.rotation_chi2_per_dof = c.rotation_stage.chi2 / std::max(1, c.rotation_stage.dof);
  res.translation_chi2_per_dof = c.translation_stage.chi2 / std::max(1, c.translation_stage.dof);
  res.noise_origin = to_string(c.noise_origin);
  res.method = to_string(c.method);
  if (c.corner_fit) {
    res.corner_pixel_sigma = c.corner_fit->pixel_sigma;
    res.corner_rms_px = c.corner_fit->rms_px;
    res.corners_used = c.corner_fit->corners;
  }
  if (c.pattern) {
    res.pattern = conversions::to_stamped_msg(*c.pattern, config_.rig.pattern_parent_frame(), res.calibration.header.stamp);
    const std::array<double, 36> cross = to_row_major_6x6(c.cross_covariance);
    std::copy(cross.begin(), cross.end(), res.cross_covariance.begin());
  }
  res.turned_samples = c.turned;
  if (c.honesty) {
    const Calibration::Honesty& h = *c.honesty;
    res.honesty = to_string(h.verdict);
    res.honesty_text = h.text;
    res.split_half_nees = h.split_half_nees;
    res.honest_nees = h.reference.mean;
    res.honest_nees_band = {h.reference.low, h.reference.high};
    res.covariance_inflation = h.inflation;
  }
  res.shared_robot_error = io::shared_error_state(c.shared_robot_error);
  res.warnings = io::warning_texts(c.warnings);
  for (const auto& r : c.rejected) {
    res.rejected_samples.push_back(r.index);
    res.rejected_reasons.push_back(io::rejected_text(r));
  }
  res.message = io::one_line_summary(c, config_.rig.camera_parent_frame(), config_.rig.frames.camera);
  std::lock_guard<std::mutex> outputs(output_mutex_);  // one /calibrate's outputs at a time
  calibration_pub_.publish(res.calibration);
  if (c.pattern) pattern_pub_.publish(res.pattern);
  publish_estimate(c);
  tf_X_ = c.T_parent_camera;
  res.published_tf = refresh_tf();
  if (config_.publish_pattern_tf && c.pattern) {
    tf_edges_.publish(conversions::to_transform_stamped(c.pattern->pose, res.pattern.header.frame_id,
                                                        config_.rig.frames.pattern, res.pattern.header.stamp));
  }
  const std::string result_text = io::format_result(c, io::context_of(snapshot.samples));
  for (const auto& [key, value] : io::result_entries(result_text)) {
    diagnostic_msgs::KeyValue entry;
    entry.key = key;
    entry.value = value;
    res.result.push_back(entry);
  }
  try {
    io::write_file_atomically(config_.calibration_file, result_text);
    res.calibration_file = config_.calibration_file;
  } catch (const HandEyeError& e) {
    res.message += "; but the result file could not be written: " + std::string(e.what());
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    calibration_ = Calibrated{c, std::move(snapshot)};
  }
  ROS_INFO("calibrate: %s", res.message.c_str());
  return true;
}

bool CalibrationNode::take_sample(TakeSample::Request&, TakeSample::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  const SessionEvent event = session_.take_sample(ros::Time::now().toSec());
  record(event, true);
  res.success = event.success;
  res.message = event.message;
  res.samples = static_cast<int>(session_.samples().size());
  return true;
}

bool CalibrationNode::remove_sample(RemoveSample::Request& req, RemoveSample::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  const SessionEvent event = session_.remove(req.index);
  if (event.success) record(event, false);
  res.success = event.success;
  res.message = event.message;
  res.samples = static_cast<int>(session_.samples().size());
  return true;
}

bool CalibrationNode::list_samples(ListSamples::Request&, ListSamples::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  for (const PoseSample& s : session_.samples()) {
    res.effector_poses.push_back(conversions::to_pose_msg(s.T_base_effector));
    res.pattern_poses.push_back(conversions::to_pose_msg(s.T_camera_pattern));
    res.stamps.push_back(s.stamp.value_or(0.0));
  }
  res.samples = static_cast<int>(session_.samples().size());
  return true;
}

bool CalibrationNode::reset(Reset::Request&, Reset::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  const SessionEvent event = session_.reset();
  record(event, false);
  res.success = event.success;
  res.message = "all samples dropped";
  return true;
}

bool CalibrationNode::save_samples(SaveSamples::Request& req, SaveSamples::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  const SessionEvent event = session_.save(req.path);
  res.success = event.success;
  res.message = event.message;
  return true;
}

bool CalibrationNode::load_samples(LoadSamples::Request& req, LoadSamples::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  const SessionEvent event = session_.load(req.path);
  if (event.success) record(event, false);
  res.success = event.success;
  res.message = event.message;
  res.samples = static_cast<int>(session_.samples().size());
  return true;
}

bool CalibrationNode::save_calibration(SaveCalibration::Request& req, SaveCalibration::Response& res) {
  std::unique_lock<std::mutex> outputs(output_mutex_);  // not while /calibrate writes the same file
  std::optional<Calibrated> calibrated;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    calibrated = calibration_;
  }
  res.path = req.path.empty() ? config_.calibration_file : req.path;
  if (!calibrated) {
    res.success = false;
    res.message = "no calibration yet: call calibrate first";
    return true;
  }
  try {
    io::write_file_atomically(res.path, io::format_result(calibrated->calibration, io::context_of(calibrated->snapshot.samples)));
    res.success = true;
    res.message = "saved to " + res.path;
  } catch (const HandEyeError& e) {
    res.success = false;
    res.message = e.what();
    return true;
  }
  outputs.unlock();  // the report takes seconds (leave-one-out, split-half, figures): /calibrate need not wait
  if (!req.report_directory.empty()) {
    // The report of the samples /calibrate solved, of the X it gave: as `handeye report` makes it.
    // The calibration is saved whatever becomes of the report: a failing report is said, not fatal.
    try {
      const CalibrationReport report = make_report(session_, calibrated->snapshot, calibrated->calibration);
      const ReportFiles files = write_report(req.report_directory, report, calibrated->snapshot.samples,
                                             "the node " + ros::this_node::getName() + " (/save_calibration)");
      res.report = files.html;
      res.message += files.problem.empty() ? "; report in " + files.html : "; no report page: " + files.problem;
    } catch (const HandEyeError& e) {
      res.message += std::string("; no report: ") + e.what();
    }
  }
  return true;
}

Calibration CalibrationNode::calibration_to_check() const {  // lock held
  if (calibration_) return calibration_->calibration;
  const std::string& path = config_.calibration_file;
  if (!std::ifstream(path)) {
    throw HandEyeError(ErrorCode::IoError, "no calibration to check: none was solved here and none is saved", path,
                       "calibrate first (/calibrate), or set ~calibration_file to the saved result file");
  }
  return io::read_calibration_to_check(path, config_.rig);
}

CalibrationCheckMsg CalibrationNode::check_message() const {  // lock held
  const CalibrationSession::CheckState state = session_.check_state();
  CalibrationCheckMsg msg;
  if (state.collecting) {
    msg.header.stamp = ros::Time::now();
    msg.state = "collecting";
    msg.views_taken = state.taken;
    msg.views_needed = state.needed;
    msg.text = "collecting views for the check: " + std::to_string(state.taken) + " of " + std::to_string(state.needed) +
               " (move the robot to new poses, the board in view)";
  } else if (state.result) {
    msg = conversions::to_msg(*state.result, ros::Time::now());
  } else {
    msg.header.stamp = ros::Time::now();
    msg.state = "failed";
    msg.text = last_event_;
  }
  return msg;
}

bool CalibrationNode::check_calibration(CheckCalibration::Request& req, CheckCalibration::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  SessionEvent event;
  if (req.cancel) {
    event = session_.cancel_check();
  } else {
    try {
      event = session_.start_check(calibration_to_check(), req.views > 0 ? req.views : 5);
    } catch (const HandEyeError& e) {
      event = {false, false, std::string("check not started: ") + e.what(), "", true};
    }
  }
  record(event, false);
  res.success = event.success;
  res.message = event.message;
  res.check = check_message();
  return true;
}

bool CalibrationNode::suggest_pose(SuggestPose::Request& req, SuggestPose::Response& res) {
  SessionSnapshot snapshot;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    snapshot = session_.snapshot();
  }
  try {
    SuggestRequest request;
    request.criterion = req.criterion;
    request.count = req.count;
    request.target_object_sigma = metres(req.target_mm);
    const SuggestResult r = session_.suggest(snapshot, request);  // outside the lock: it may take a while
    const std::string& base = config_.rig.frames.base;
    for (int i = 0; i < r.count && i < static_cast<int>(r.suggestion.ranked.size()); ++i) {
      res.poses.push_back(stamped(r.suggestion.ranked[i].T_base_effector, base));
      res.predicted_object_error_mm.push_back(millimetres(r.suggestion.ranked[i].object_sigma));
    }
    for (const ScoredPose& p : r.plan.poses) res.plan.push_back(stamped(p.T_base_effector, base));
    res.current_object_error_mm = millimetres(r.suggestion.current_object_sigma);
    res.poses_to_target = r.plan.reached ? static_cast<int>(r.plan.poses.size()) : -1;
    res.success = true;
    const std::string target = number_text(millimetres(r.target_object_sigma));
    res.message = r.plan.reached ? std::to_string(r.plan.poses.size()) + " more pose(s) reach " + target + " mm (predicted)"
                                 : "the target " + target + " mm is not reached within " +
                                       std::to_string(session_.settings().max_plan_poses) + " more poses";
    if (r.plan.reached) res.message += poses_for_the_noise_text(r.plan);
  } catch (const HandEyeError& e) {
    res.message = e.what();
  }
  return true;
}

}  // namespace handeye
