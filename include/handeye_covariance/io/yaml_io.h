// The package's file formats (yaml-cpp; no ROS). See docs/file_formats.md.
//
//  samples file:  setup, frames?, noise? {effector, pattern}, samples: [{effector, pattern, stamp?, noise?}]
//  motions file:  setup?, noise? {A, B}, motions: [{A, B, noise?}]
//  result file:   setup, parent, child, translation, rotation, covariance {rotation, translation, pose},
//                 samples_used, transformation {x, y, z, qx, qy, qz, qw}, plus diagnostics
//
// Poses are {translation: [x, y, z], rotation: [qx, qy, qz, qw]}; covariances are
// 9 numbers row-major (rad^2, m^2); the pose covariance is 36 numbers row-major in
// ROS order (x, y, z, rx, ry, rz). Readers throw HandEyeError naming the field.
#pragma once

#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "handeye_covariance/estimation/calibration_report.h"
#include "handeye_covariance/estimation/calibration_check.h"
#include "handeye_covariance/estimation/estimator.h"
#include "handeye_covariance/estimation/next_best_pose.h"
#include "handeye_covariance/estimation/noise_estimation.h"
#include "handeye_covariance/session/session_config.h"
#include "handeye_covariance/core/tag_layout.h"
#include "handeye_covariance/core/target.h"

namespace handeye {
namespace io {

/// Parse from text; `source` names the file in error messages.
SampleSet parse_samples(const std::string& text, const std::string& source);
MotionSet parse_motions(const std::string& text, const std::string& source);

SampleSet read_samples(const std::string& path);

/// A file whose `noise:` block is a samples file's ({effector: ..., pattern: ...}),
/// as the node's ~noise_config. Throws MissingKey when there is no such block.
MeasurementNoise read_noise_file(const std::string& path);
MotionSet read_motions(const std::string& path);

/// A tag pattern layout (config/tag_board_2x2.yaml shows the format):
///   family: tag36h11
///   tags:   # each tag's centre pose in the pattern frame; x/y/z and q default to the identity
///     - {id: 0, size: 0.06, x: -0.04, y: 0.04, z: 0.0, qw: 1, qx: 0, qy: 0, qz: 0}
/// Throws HandEyeError naming the file and the entry.
TagLayout parse_tag_layout(const std::string& text, const std::string& source);
TagLayout read_tag_layout(const std::string& path);

/// A calibration target file (its kind by `type`; a file with `tags:` is a layout):
///   {type: chessboard, inner_corners: [columns, rows], square: 0.0236}
///   {type: charuco, squares: [columns, rows], square: 0.036, marker: 0.018, dictionary: DICT_6X6_250}
///   {type: aruco, dictionary: DICT_4X4_50, id: 7, marker: 0.05}
///   {type: aruco_board, dictionary: DICT_4X4_50, markers: [columns, rows], marker: 0.06, separation: 0.015[, first_id: 0]}
///   {type: apriltag, family: tag36h11, id: 10, size: 0.048}
///   a tag layout (parse_tag_layout; `family` may be an ArUco dictionary)
/// Lengths in m. Throws HandEyeError naming the file and key. Whether a
/// dictionary or family exists is checked by the detector (vision/target.h).
Target parse_target(const std::string& text, const std::string& source);
Target read_target(const std::string& path);

/// A ROS camera_info YAML (camera_calibration writes one): image_width,
/// image_height, camera_matrix: {data: [9 numbers]}, distortion_coefficients:
/// {data: [...]} (optional). Numbers checked (finite; sizes whole pixels); whether K
/// is a usable pinhole matrix is the vision layer's check (check_camera_model).
/// The sizes are 0 when not given.
CameraModel parse_camera_info(const std::string& text, const std::string& source);

/// A file holding either samples or motions (told apart by its top-level key).
using Input = std::variant<SampleSet, MotionSet>;
Input read_input(const std::string& path);

std::string format_samples(const SampleSet& samples);

/// Candidate effector poses (T_base_effector) for the next-best-pose
/// suggestions: `candidates: [{translation: [x, y, z], rotation: [qx, qy, qz, qw]}, ...]`.
std::vector<Eigen::Isometry3d> parse_candidate_poses(const std::string& text, const std::string& source);
std::vector<Eigen::Isometry3d> read_candidate_poses(const std::string& path);

/// What `handeye suggest` writes: the ranked next poses and the plan to the
/// target. Its `suggestions` list has the `candidates` format's pose keys.
std::string format_suggestions(const Suggestion& suggestion, int count, const Plan& plan, double target_object_sigma,
                               const SuggestOptions& options);

/// The file `handeye noise` writes: a `noise: {effector, pattern}` block, which
/// read_noise_file, the node's ~noise_config and `solve --noise` accept, and an
/// `estimate:` block saying how it was measured (source, dof, 1 sigma per axis).
std::string format_noise_estimate(const NoiseEstimate& estimate);
std::string format_motions(const MotionSet& motions);

/// What the result file says besides the calibration itself.
struct ResultContext {
  std::optional<Setup> setup;  // absent for motion input without a setup key
  std::string parent, child;   // frame names, empty when unknown
  std::string pattern_parent, pattern_child;  // Y's frames (samples input)
};

ResultContext context_of(const SampleSet& samples);
ResultContext context_of(const MotionSet& motions);

std::string format_result(const Calibration& calibration, const ResultContext& context);

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

/// A result file read back: X with its covariance and the frames.
struct CalibrationFile {
  ResultContext context;
  PoseWithCovariance T_parent_camera;
  int samples_used = 0;
  std::optional<MeasurementNoise> noise;  // `noise.model` of a samples result: what the covariance assumed
  NoiseOrigin noise_origin = NoiseOrigin::Given;  // `noise.origin`
  /// A joint result's Y (`pattern`), Cov(X, Y) (`cross_covariance`), the noise model its
  /// covariance was computed with (`noise.residual_model`) and the honesty check's
  /// inflation (1 when none): what a check of the calibration needs.
  std::optional<PoseWithCovariance> pattern;
  Matrix6d cross_covariance = Matrix6d::Zero();
  std::optional<Calibration::ResidualNoise> residual_noise;
  std::vector<Calibration::NoiseComponent> noise_components;  // `noise.estimated`: how well each number is known
  std::optional<Calibration::Prediction> prediction;  // `prediction`: the leave-one-out scale
  double inflation = 1.0;
};
CalibrationFile parse_result(const std::string& text, const std::string& source);
CalibrationFile read_result(const std::string& path);
/// The file as the Calibration a check tests (calibration_check.h): X, Y, their
/// covariances and cross block, the noise model and the inflation.
Calibration calibration_of(const CalibrationFile& file);

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

/// A robot pose file, one per image (T_base_effector in m), in any format users
/// keep next to their images:
///   YAML or JSON {matrix: [16 numbers, row-major]} or {translation: [x, y, z], rotation: [qx, qy, qz, qw]};
///   ViSP's vpPoseVector YAML {rows: 6, cols: 1, data: [[tx], [ty], [tz], [tux], [tuy], [tuz]]}
///     (theta-u: the rotation axis times its angle, rad);
///   a plain-text 4x4 matrix (16 numbers; whitespace, commas or semicolons between them).
/// Throws HandEyeError naming the file and what is wrong.
Eigen::Isometry3d parse_robot_pose(const std::string& text, const std::string& source);
Eigen::Isometry3d read_robot_pose(const std::string& path);

/// One CSV of robot poses for a folder of images: `image,tx,ty,tz,qx,qy,qz,qw`
/// per line (m, unit quaternion), a header line skipped, blank lines ignored.
/// `image` is the file name or its stem. Throws HandEyeError naming the line.
struct PoseTableRow {
  std::string image;
  Eigen::Isometry3d T_base_effector;
  std::string where;  // "poses.csv line 3"
};
std::vector<PoseTableRow> parse_pose_table(const std::string& text, const std::string& source);

/// Session settings from a YAML file with the node's parameter names (the
/// keys of config/calibration_defaults.yaml and calibrate.launch); keys absent
/// from the file keep their value in `config`. Unknown keys are refused (typos).
void read_session_config(const std::string& path, SessionConfig& config);

/// Write to `path.tmp-<pid>` then rename, so a reader never sees half a file
/// and a failure leaves no file behind. Creates missing parent directories.
void write_file_atomically(const std::string& path, const std::string& content);

/// Whole file as text; HandEyeError(IoError) when it cannot be read.
std::string read_file(const std::string& path);

/// `~/rest` as $HOME/rest (a path from a launch file or a parameter); any other path as it is.
std::string expand_home(const std::string& path);

}  // namespace io
}  // namespace handeye
