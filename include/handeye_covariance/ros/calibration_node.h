// The calibration node: an adapter between ROS and a CalibrationSession.
//
//   detections (own queue and thread) -> stamp-matched observations -> the session, under a short lock
//   a worker thread                   -> estimate and next pose of each new generation of samples,
//                                        on a snapshot, outside the lock; stale results are dropped
//   services (a multi-threaded spinner) -> the session's changes, or computations on a snapshot
//
// So a detection never waits behind a solve or a ranking, and /calibrate never
// waits behind a ranking. The session writes its file before a change is
// reported (crash safety).
#pragma once

#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

#include "handeye_covariance/session/session_config.h"
#include "handeye_covariance/ros/messages.h"
#include "handeye_covariance/ros/detection_input.h"
#include "handeye_covariance/ros/observations.h"
#include "handeye_covariance/ros/static_edges.h"
#include "handeye_covariance/ros/arm_mover.h"
#include "handeye_covariance/session/calibration_session.h"

namespace handeye {

class CalibrationNode {
 public:
  /// Reads ~parameters (see config/calibration_defaults.yaml), advertises
  /// everything, starts the detection thread and the worker and, with ~resume,
  /// reloads the session file.
  CalibrationNode(ros::NodeHandle node, ros::NodeHandle private_node);
  ~CalibrationNode();
  /// Before ROS shuts down (shutdown_request.h): a move under way is held.
  void stop_for_shutdown() {
    if (mover_) mover_->stop_for_shutdown();
  }

 private:
  // Inputs, on the detection thread (detection_input.h): each gives a detection of the pattern.
  void observe(const Detection& detection);
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
  bool check_calibration(CheckCalibration::Request&, CheckCalibration::Response&);
  /// The calibration a check tests: the last /calibrate's, else the saved calibration_file
  /// (read whole: Y, the cross block, the noise model). Throws HandEyeError. Lock held.
  Calibration calibration_to_check() const;
  /// ~check: the check's state (collecting) or its finished result. Lock held.
  CalibrationCheckMsg check_message() const;

  /// After a change of the session (lock held): log it, wake the worker, publish
  /// ~status. The last analysis stays on ~status while the worker catches up only
  /// when the change `appended` a sample.
  void record(const SessionEvent& event, bool appended);
  /// The worker: analyses each new generation of samples outside the lock.
  void work();
  void publish_status();  // lock held
  /// The running estimate (~estimate) and its markers (~markers).
  void publish_estimate(const Calibration& c);
  /// The best next pose in 3D (~next_pose_markers): a ghost effector frame and the
  /// camera's frustum there; cleared when there is none. Lock held.
  void publish_next_pose();
  /// The saved calibration (~calibration_file) published again at start-up, as
  /// easy_handeye's publish.launch does: ~calibration, and X in TF.
  void republish_saved_calibration();
  /// Keeps X in TF (output_mutex_ held): at the root of the camera's own tree,
  /// which moves when a camera driver starts after us. Returns the edge
  /// ("tool0 -> camera_link") or why none was published.
  std::string refresh_tf();

  SessionConfig config_;
  ros::NodeHandle node_, private_node_, detection_node_;
  ros::CallbackQueue detection_queue_;  // detections in order, on their own thread
  std::unique_ptr<ros::AsyncSpinner> detection_spinner_;
  tf2_ros::Buffer tf_buffer_;
  tf2_ros::TransformListener tf_listener_;
  StaticEdges tf_edges_;  // X, and Y with publish_pattern_tf (output_mutex_)
  std::unique_ptr<DetectionInput> input_;
  ros::Timer status_timer_, tf_refresh_;
  ros::Publisher calibration_pub_, pattern_pub_, estimate_pub_, status_pub_, markers_pub_, next_pose_pub_, check_pub_;
  std::vector<ros::ServiceServer> services_;
  // /calibrate's outputs (the TF, the result file, calibration_) one call at a time:
  // the spinner has two threads.
  std::mutex output_mutex_;
  std::optional<Eigen::Isometry3d> tf_X_;  // the X kept in TF (output_mutex_)

  mutable std::mutex mutex_;  // guards everything below
  std::condition_variable work_;
  bool stopping_ = false;
  CalibrationSession session_;
  std::optional<Analysis> analysis_;  // of the latest generation analysed
  bool motion_ = false;                      // ~motion/enabled: the next pose is the mover's plan
  std::optional<ScoredPose> planned_view_;   // the mover's planned view (none: no plan, or a first move)
  /// The next pose shown (~status, next-pose markers): the mover's plan with motion, else the analysis's best.
  std::optional<ScoredPose> next_view() const;
  std::uint64_t last_removal_ = 0;    // generation of the last change that was not an appended sample
  struct Calibrated {
    Calibration calibration;
    SessionSnapshot snapshot;  // what it was solved from (frames and noise for the result file)
  };
  std::optional<Calibrated> calibration_;  // from the last successful /calibrate
  std::string last_event_ = "started";
  std::uint32_t detections_received_ = 0;
  std::deque<double> detection_ages_;  // s, the last kAgeWindow handled detections
  std::thread worker_;                 // starts once everything above exists
  std::unique_ptr<ArmMover> mover_;    // ~motion/enabled; last, so it stops first
};

}  // namespace handeye
