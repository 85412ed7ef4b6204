// Result files and what is read or written beside them: reports, checks, pose
// files with a covariance, stored calibrations (ours and easy_handeye's) (yaml-cpp;
// no ROS). See docs/file_formats.md.
//
//  result file:   setup, parent, child, translation, rotation, covariance {rotation, translation, pose},
//                 samples_used, transformation {x, y, z, qx, qy, qz, qw}, plus diagnostics
//
// The pose covariance is 36 numbers row-major in ROS order (x, y, z, rx, ry, rz).
// Readers throw HandEyeError naming the field.
#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "handeye_covariance/core/measurements.h"
#include "handeye_covariance/core/pose_covariance.h"
#include "handeye_covariance/estimation/calibration_check.h"
#include "handeye_covariance/estimation/calibration_report.h"
#include "handeye_covariance/estimation/estimator.h"

namespace handeye {
namespace io {

/// What the result file says besides the calibration itself.
struct ResultContext {
  std::optional<Setup> setup;  // absent for motion input without a setup key
  std::string parent, child;   // frame names, empty when unknown
  std::string pattern_parent, pattern_child;  // Y's frames (samples input)
};

ResultContext context_of(const SampleSet& samples);
ResultContext context_of(const MotionSet& motions);

std::string format_result(const Calibration& calibration, const ResultContext& context);
/// A result file's keys (format_result's text) as (path, value) pairs in its order: every
/// section as its description writes it, "honesty.reference.mean" -> "6.17", lists of
/// numbers as one value "[a, b, ...]", list entries as "key[i]". What /calibrate returns
/// beside its fields.
std::vector<std::pair<std::string, std::string>> result_entries(const std::string& result_text);

/// A check of a saved calibration (calibration_check.h) as `handeye check --output`
/// writes it: verdict (consistent | changed), p_value, changed (X | Y | both),
/// change and change_covariance (ROS order; X's when X or both changed, Y's when Y;
/// for both also pattern_change and its covariance), each hypothesis, each view.
std::string format_check(const CalibrationCheck& check, const std::string& calibration_path);

/// The calibration report's data (session/report.h), read by scripts/report.py:
/// source, setup, frames, per-sample residuals (with the rejected ones and
/// their reason), the per-axis checks in mm and degrees, the motions' rotation
/// axes in the camera frame and the advice. The calibration itself is the
/// result file beside it (format_result).
std::string format_report(const CalibrationReport& report, const ResultContext& context, const std::string& source);

/// Only the result keys (no solver diagnostics): for a known truth, or a pose
/// with covariance from elsewhere. `read_result` reads it.
std::string format_pose_file(const PoseWithCovariance& X, const ResultContext& context);

/// A result file read back: its frames, X with its covariance, the noise model when the
/// file states one, and what a check of the calibration needs as the Calibration it tests
/// (calibration_check.h): X, Y and their covariances and cross block, the samples used,
/// the noise model (`noise.model`, `noise.origin`, `noise.residual_model`,
/// `noise.estimated`), the prediction, the shared robot error and the honesty check's
/// inflation (an Overconfident honesty record when > 1). The solver's diagnostics are not read.
struct CalibrationFile {
  ResultContext context;
  std::optional<MeasurementNoise> noise;  // `noise.model` of a samples result: what the covariance assumed
  Calibration calibration;
  /// X with its covariance, as the calibration holds them.
  PoseWithCovariance T_parent_camera() const { return {calibration.T_parent_camera, calibration.pose_covariance}; }
};
CalibrationFile parse_result(const std::string& text, const std::string& source);
CalibrationFile read_result(const std::string& path);
/// Whether a saved calibration of this setup and X = T_parent_child is `rig`'s: what
/// either does not say (no setup, empty frames) is taken to agree.
bool is_calibration_of(const Rig& rig, const std::optional<Setup>& setup, const std::string& parent, const std::string& child);
/// The calibration at `path` to check new views of `rig` against: the one guard of
/// `handeye check`, `handeye images check` and the node's check. Refuses
/// (MalformedFile, naming both) a file of another setup or other frames.
Calibration read_calibration_to_check(const std::string& path, const Rig& rig);
/// The same guard on a file already read from `path`.
Calibration calibration_to_check(const CalibrationFile& file, const Rig& rig, const std::string& path);

/// A saved calibration to publish at start-up (publish.launch, the calibration
/// node): ours (a result file) or easy_handeye's, whose users switch to us:
///   {parameters: {eye_on_hand, robot_base_frame, robot_effector_frame, tracking_base_frame},
///    transformation: {x, y, z, qx, qy, qz, qw}}
/// (easy_handeye's older files have the parameters at the top level). An
/// easy_handeye file has no covariance: `has_covariance` is false and the
/// covariance is zero.
struct StoredCalibration {
  std::optional<Setup> setup;
  std::string parent, child;  // X = T_parent_child; empty when the file does not say
  PoseWithCovariance T_parent_camera;
  bool has_covariance = false;
  std::string format;  // "handeye_covariance" or "easy_handeye"
};
StoredCalibration parse_stored_calibration(const std::string& text, const std::string& source);
StoredCalibration read_stored_calibration(const std::string& path);

/// A pose with an optional covariance (a detection, a robot pose):
///   translation: [x, y, z], rotation: [qx, qy, qz, qw], parent?, child?,
///   covariance?: {pose: [36 numbers, ROS order]} or {rotation: [9], translation: [9]}
/// A result file is one too.
struct PoseFile {
  PoseWithCovariance value;
  bool has_covariance = false;
  std::string parent, child;
};
PoseFile parse_pose_file(const std::string& text, const std::string& source);
PoseFile read_pose_file(const std::string& path);

}  // namespace io
}  // namespace handeye
