// The settings of a calibration session, shared by the node (ROS parameters) and
// the offline bag replay (a YAML file): one table of keys, so both read the same
// names in the same units. See config/calibration_defaults.yaml.
#pragma once

#include <string>
#include <vector>

#include "handeye_covariance/core/units.h"
#include "handeye_covariance/session/sampler.h"

namespace handeye {

struct SessionConfig {
  Rig rig{Setup::EyeInHand, {"base_link", "tool0", "camera_optical_frame", "tag_0"}};  // eye_on_hand and the frames
  std::string detection_input = "tags";  // tags | pose_with_covariance | pose | tf
  std::string detections_topic = "/tag_detections";
  std::vector<int> tag_ids;              // empty: a lone detection is taken
  std::string target_file;  // the target the detector sees (io::read_target): where new views look (Rig::T_pattern_face)
  // The bag replay: images instead of detections (the target detector runs on them).
  std::string image_topic;        // empty: the bag's one image topic when it has no detections topic
  std::string camera_info_topic;  // empty: camera_info beside the image topic, or the bag's one CameraInfo topic
  std::string noise_config;              // YAML with a `noise:` block; empty: estimated
  bool publish_tf = true;
  bool publish_pattern_tf = false;  // also TF <pattern parent> -> tracking_marker_frame for Y (joint)
  bool resume = false;
  std::string namespace_prefix = "handeye";
  std::string calibration_file, session_file;  // empty: ~/.ros/handeye_covariance/<namespace>[_samples].yaml
  double tf_timeout = 0.5;               // s
  double tf_poll_rate = 30.0;            // Hz
  double working_distance = 0.7;         // m
  double target_tolerance_mm = 1.0;
  bool reject_outliers = true;  // outliers.h: consensus + residual gating before the covariance
  std::string method = "joint";  // joint (X and the pattern pose from the poses) | pairs (the paper's AX = XB)
  std::string robust = "auto";   // joint: Huber + sandwich when the residuals are heavy-tailed (auto) | on | off
  // The calibrated honesty check (split_check.h) on /calibrate and /save_calibration:
  // random halves, simulated honest sessions, and whether an overconfident
  // verdict inflates the covariance (the default) or is only reported.
  int honesty_splits = 200;    // 0: no check
  int honesty_sessions = 100;
  int honesty_run_length = 0;  // the second look's runs (split_check.h): 0 auto, 1 none, k runs of k
  bool inflate_when_overconfident = true;
  // A robot error shared by nearby poses (shared_robot_error.h): use | advice | off.
  std::string shared_robot_error = "use";
  // Next-best pose (/suggest_pose and ~status): criterion, sampled candidates
  // within one move of the last pose, or a file of candidate effector poses.
  std::string suggest_criterion = "object_sigma";  // object_sigma | determinant
  int suggest_candidates = 150;
  double reach_translation = 0.5;                  // m
  double reach_rotation = radians(90.0);     // rad
  std::string candidate_poses_file;                // empty: sampled
  SamplerOptions sampler;

  /// <namespace_prefix>_eye_on_hand or _eye_on_base, as easy_handeye names it.
  std::string name() const { return namespace_prefix + (rig.eye_in_hand() ? "_eye_on_hand" : "_eye_on_base"); }
};

/// Calls `visit(key, member, scale)` for every setting: the value under `key`
/// (in the units its name says: _mm, _deg, s, m) times `scale` is the member's
/// SI value. Member types: bool, int, double, std::string, std::vector<int>, and
/// Setup, which is read as easy_handeye's bool `eye_on_hand` (setup_from_eye_on_hand).
template <typename Visitor>
void for_each_setting(SessionConfig& c, Visitor&& visit) {
  constexpr double mm = kMetresPerMillimetre, deg = kRadiansPerDegree;
  visit("eye_on_hand", c.rig.setup, 1.0);
  visit("robot_base_frame", c.rig.frames.base, 1.0);
  visit("robot_effector_frame", c.rig.frames.effector, 1.0);
  visit("tracking_base_frame", c.rig.frames.camera, 1.0);
  visit("tracking_marker_frame", c.rig.frames.pattern, 1.0);
  visit("detection_input", c.detection_input, 1.0);
  visit("detections_topic", c.detections_topic, 1.0);
  visit("tag_ids", c.tag_ids, 1.0);
  visit("target_file", c.target_file, 1.0);
  visit("image_topic", c.image_topic, 1.0);
  visit("camera_info_topic", c.camera_info_topic, 1.0);
  visit("noise_config", c.noise_config, 1.0);
  visit("publish_tf", c.publish_tf, 1.0);
  visit("publish_pattern_tf", c.publish_pattern_tf, 1.0);
  visit("resume", c.resume, 1.0);
  visit("namespace_prefix", c.namespace_prefix, 1.0);
  visit("calibration_file", c.calibration_file, 1.0);
  visit("session_file", c.session_file, 1.0);
  visit("tf_timeout", c.tf_timeout, 1.0);
  visit("tf_poll_rate", c.tf_poll_rate, 1.0);
  visit("working_distance", c.working_distance, 1.0);
  visit("target_tolerance_mm", c.target_tolerance_mm, 1.0);
  visit("reject_outliers", c.reject_outliers, 1.0);
  visit("method", c.method, 1.0);
  visit("robust", c.robust, 1.0);
  visit("honesty_splits", c.honesty_splits, 1.0);
  visit("honesty_sessions", c.honesty_sessions, 1.0);
  visit("honesty_run_length", c.honesty_run_length, 1.0);
  visit("inflate_when_overconfident", c.inflate_when_overconfident, 1.0);
  visit("shared_robot_error", c.shared_robot_error, 1.0);
  visit("suggest_criterion", c.suggest_criterion, 1.0);
  visit("suggest_candidates", c.suggest_candidates, 1.0);
  visit("reach_translation_mm", c.reach_translation, mm);
  visit("reach_rotation_deg", c.reach_rotation, deg);
  visit("candidate_poses_file", c.candidate_poses_file, 1.0);
  visit("auto_sample", c.sampler.auto_sample, 1.0);
  visit("still_window", c.sampler.still_window, 1.0);
  visit("still_translation_mm", c.sampler.still_translation, mm);
  visit("still_rotation_deg", c.sampler.still_rotation, deg);
  visit("pattern_still_translation_mm", c.sampler.pattern_still_translation, mm);
  visit("pattern_still_rotation_deg", c.sampler.pattern_still_rotation, deg);
  visit("max_gap", c.sampler.max_gap, 1.0);
  visit("max_age", c.sampler.max_age, 1.0);
  visit("min_translation_mm", c.sampler.min_translation, mm);
  visit("min_rotation_deg", c.sampler.min_rotation, deg);
}

/// Session settings from a YAML file with the node's parameter names (the
/// keys of config/calibration_defaults.yaml and calibrate.launch); keys absent
/// from the file keep their value in `config`. Unknown keys are refused (typos).
void read_session_config(const std::string& path, SessionConfig& config);

}  // namespace handeye
