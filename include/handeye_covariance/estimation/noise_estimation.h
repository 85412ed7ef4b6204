// Measuring the measurement noise instead of guessing it (paper section IV-B,
// eq. 64-67), from absolute pose samples. Two sources:
//
//  * Repeated observations: the robot holds a pose while the camera sees the
//    pattern several times. Within each such group the scatter of the pattern
//    poses about their mean is the camera's noise, and the scatter of the
//    reported effector poses is the robot's (its reading noise at rest; a
//    robot's repeatability from different approach paths is not seen).
//  * Residuals against a calibration: with X known, every sample predicts the
//    pattern's fixed pose Y (eq. 68's chain); Y's mean (eq. 66-67) gives each
//    sample's expected pattern pose, and the residuals (eq. 64-65) give the
//    camera noise. The robot's noise is not separable from the camera's there:
//    a given robot noise is subtracted, otherwise the camera absorbs it.
//
// Errors are left perturbations in the parent frame, as everywhere:
//   xi_R = log(R R_bar^T), xi_t = t - t_bar (eq. 64-65).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "handeye_covariance/core/measurements.h"
#include "handeye_covariance/core/units.h"

namespace handeye {

enum class NoiseSource { RepeatedObservations, Residuals };
const char* to_string(NoiseSource source);  // "repeated_observations" / "residuals"

struct NoiseEstimate {
  NoiseSource source = NoiseSource::Residuals;
  MeasurementNoise noise;          // robot: estimated, or as given, or zero (see robot_identified)
  bool robot_identified = false;   // true only from repeated observations
  int samples_used = 0;
  int groups = 0;                  // repeated observations: poses seen more than once
  /// Degrees of freedom of each variance estimate: its relative 1-sigma
  /// sampling error is sqrt(2 / dof).
  double dof = 0.0;
  std::vector<std::string> notes;  // what was assumed, what was clipped
};

struct RepeatedObservationOptions {
  /// Samples whose effector poses are this close to a group's first sample
  /// belong to the group (the robot held the pose).
  double group_translation = 1e-3;              // m
  double group_rotation = radians(0.1);   // rad
};

/// Throws NoiseUnidentifiable when no pose was seen at least twice, or fewer
/// than 4 degrees of freedom result.
NoiseEstimate noise_from_repeated_observations(const SampleSet& samples, const RepeatedObservationOptions& options = {});

/// Eq. (64-67) on samples. `X_fitted_to_these_samples` adds X's 6 parameters
/// to the dof correction. `robot_noise`, when given, is subtracted through
/// each sample's Jacobian. Throws NoiseUnidentifiable with fewer than 4 samples.
NoiseEstimate noise_from_residuals(const SampleSet& samples, const Eigen::Isometry3d& X, bool X_fitted_to_these_samples,
                                   const std::optional<PoseNoise>& robot_noise = std::nullopt);

/// One sample's pattern pose against the pattern's fixed pose `pattern`
/// (eq. 64-65 about P_bar = X^-1 E^-1 pattern, or X^-1 E pattern eye-to-hand),
/// and its first-order sensitivity to the effector pose's noise.
struct SampleResidual {
  Vector6d error = Vector6d::Zero();                 // ROS order, camera frame
  Matrix6d d_effector = Matrix6d::Zero();            // d error / d effector perturbation
};
SampleResidual sample_residual(const Rig& rig, const PoseSample& sample, const Eigen::Isometry3d& X,
                               const Eigen::Isometry3d& pattern);

}  // namespace handeye
