// Inputs to the estimator: absolute pose samples (what a robot and a camera
// produce) or independent motion pairs (A_i, B_i) (the paper's experiments).
//
// Frames and setups: rig.h.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "handeye_covariance/core/camera.h"
#include "handeye_covariance/core/pose_covariance.h"
#include "handeye_covariance/core/rig.h"

namespace handeye {

/// Noise of the two measured poses, each a full 6x6 covariance (PoseNoise: rad^2,
/// m^2, and the cross block; rotation as a left perturbation in the parent frame).
///   samples: robot = T_base_effector, camera = T_camera_pattern
///   motions: robot = A,               camera = B
struct MeasurementNoise {
  PoseNoise robot;
  PoseNoise camera;
};

struct PoseSample {
  Eigen::Isometry3d T_base_effector = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d T_camera_pattern = Eigen::Isometry3d::Identity();
  std::optional<double> stamp;             // seconds
  std::optional<MeasurementNoise> noise;   // overrides SampleSet::noise for this sample
  /// The corners T_camera_pattern was detected from, when the detector gave them
  /// (`--method corners`); shared, as observations are copied at the camera's rate.
  std::shared_ptr<const TargetCorners> corners;
};

/// One stamp-matched observation: the pattern's pose as detected and the robot's
/// pose looked up at the detection's stamp (what the sampler turns into samples).
struct Observation {
  double stamp = 0.0;                               // s, the detection's stamp
  Eigen::Isometry3d T_base_effector = Eigen::Isometry3d::Identity();  // looked up at `stamp`
  Eigen::Isometry3d T_camera_pattern = Eigen::Isometry3d::Identity();
  std::optional<PoseNoise> pattern_noise;  // the detector's full 6x6 in the camera frame, when it gives one
  std::shared_ptr<const TargetCorners> corners;  // the detection's corners, when it gives them
};

struct SampleSet {
  Rig rig;  // the setup and the frame names
  std::optional<MeasurementNoise> noise;  // absent: estimated from the residuals
  std::vector<PoseSample> samples;
};

/// The set as the session solves it: detections with their own covariance and no
/// global noise block get the mean of their camera covariances as the block, which
/// the samples without one take. Unchanged when it has a block or none has its own.
SampleSet with_default_noise(SampleSet samples);

/// The pattern's fixed pose Y as the samples and X see it (eq. 68's chain,
/// rig.pattern_pose of each sample, averaged by mean_pose).
Eigen::Isometry3d pattern_pose(const SampleSet& samples, const Eigen::Isometry3d& X);

struct MotionPair {
  Eigen::Isometry3d A = Eigen::Isometry3d::Identity();  // robot motion
  Eigen::Isometry3d B = Eigen::Isometry3d::Identity();  // camera motion, A X = X B
  std::optional<MeasurementNoise> noise;                 // overrides MotionSet::noise
};

struct MotionSet {
  std::optional<MeasurementNoise> noise;  // absent: estimated from the residuals
  std::vector<MotionPair> motions;
};

/// The motion pair between two samples i -> j, per the paper's eq. (2):
/// A = rig.robot_motion(E_i, E_j), B = T_camera_pattern_j T_camera_pattern_i^-1.
MotionPair motion_between(const Rig& rig, const PoseSample& from, const PoseSample& to);

}  // namespace handeye
