// Offline: simulated calibration bags, and calibrating from a bag without a
// roscore (rosbag::View + an offline tf2::BufferCore, into the node's
// CalibrationSession, so both take and refuse the same samples).
#pragma once

#include <functional>
#include <map>
#include <optional>
#include <string>

#include "handeye_covariance/core/target.h"
#include "handeye_covariance/session/session_config.h"
#include "handeye_covariance/simulation/simulation.h"
#include "handeye_covariance/session/calibration_session.h"

namespace handeye {

struct BagSimulationOptions {
  Setup setup = Setup::EyeInHand;
  int poses = 15;
  unsigned seed = 1;
  double pause = 2.0, move = 1.0;   // s at and between poses
  double tf_rate = 100.0;           // Hz, /tf
  double detection_rate = 20.0;     // Hz
  double latency = 0.05;            // s from capture (the stamp) to the recorded message
  double latency_jitter = 0.01;     // s, uniform +-
  // Detector noise in the camera frame: depth-heavy, as a monocular tag detector's.
  double lateral_noise_mm = 0.3, depth_noise_mm = 1.5;
  double tilt_noise_deg = 0.15, roll_noise_deg = 0.05;  // about camera x/y, about the optical axis
  double dropout = 0.05;            // share of frames without a detection
  double wrong_detections = 0.005;  // share of frames with a wrong (flipped) pose
  bool detection_covariance = true; // put the noise covariance in each detection
  bool robot_tf = true;             // false: a bag with a missing TF link (for tests)
  bool detections = true;           // false: a bag with no detections (for tests)
  std::string detections_topic = "/tag_detections";
  /// How detections are recorded: tags (TagDetectionArray), pose_with_covariance,
  /// pose, or tf (camera -> pattern transforms on /tf) - the node's inputs.
  std::string detection_type = "tags";
  /// images: the camera's view rendered (simulated_camera(), mono8) on `image_topic`
  /// with its CameraInfo on `camera_info_topic`, instead of detections. The target
  /// drawn is `target` (views look at its face).
  std::optional<Target> target;
  std::string image_topic = "/camera/image_raw", camera_info_topic = "/camera/camera_info";
  bool compressed = false;  // images as sensor_msgs/CompressedImage (PNG) on <image_topic>/compressed
  double start_time = 1700000000.0; // s, the first stamp
};

struct SimulatedBag {
  Eigen::Isometry3d X;  // the truth
  FrameNames frames;
  int tf_messages = 0, detections = 0, wrong_detections = 0;
  double duration = 0.0;
};

/// Writes the bag; the true X is returned (write it with io::format_pose_file).
SimulatedBag write_simulated_bag(const std::string& path, const BagSimulationOptions& options);

struct BagReplay {
  std::map<std::string, int> messages;  // per topic read
  int detections = 0;                   // detection messages of the configured input
  int observations = 0;                 // detections paired with a robot pose
  std::map<std::string, int> refusals;  // by kind: no_robot_tf, too_close, other_tags, ...
  std::map<std::string, std::string> refusal_examples;  // kind -> one full message
  std::string image_topic, camera_info_topic;  // images: where they came from
  int images = 0;                       // images: read and run through the detector
  double pixel_sigma = 0.0;             // images: pooled over every detection
  int stamps_went_back = 0;             // detections stamped before the previous one in the bag (a looping recording)
  int repeated_stamps = 0;              // detections whose stamp was already seen: used once
  SampleSet samples;                    // the session's at the end, with its noise model
  double duration = 0.0;                // s of bag
};

/// Feeds the bag's detections, in stamp order, into `session` (made from the
/// same `config`). A bag with images instead (config.image_topic, or no
/// detections topic and one image topic, raw or compressed, with its CameraInfo)
/// goes through the target detector first (config.target_file), every pose under
/// the pixel sigma pooled over all the images (images/pooled_detector.h). `progress(fraction)` is called as the detections are read,
/// for bags longer than 5 s (may be empty).
/// Throws HandEyeError: IoError (unreadable, truncated or corrupt bag) or
/// NoData (topic missing, no detections, or no sample could be taken).
BagReplay replay_bag(const std::string& path, const SessionConfig& config, CalibrationSession& session,
                     std::function<void(double)> progress = {});
/// The same into a session of its own (session_settings(config), nothing persisted).
BagReplay replay_bag(const std::string& path, const SessionConfig& config, std::function<void(double)> progress = {});

}  // namespace handeye
