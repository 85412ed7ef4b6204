// The pose-level estimator (solve_joint): X and the pattern pose Y jointly, from
// absolute poses. Each sample's residual e_i = (t_P - t_P_hat, log(R_P R_P_hat^T)),
// P_hat_i = X^-1 V_i Y (rig.h; camera frame, ROS order x y z rx ry rz, m and rad), is
// weighed by S_i = c Sigma_P,i + C + D_i (Sigma_E,i + R) D_i^T, D_i = d P_hat_i / d E_i,
// its free numbers fitted by REML; robust mode: Huber's loss and a sandwich covariance.
// Output: X, Y and the 12x12 covariance of (xi_X, xi_Y), cross block included; left
// perturbations in the parent frame, X = (exp(xi_R) R_hat, t_hat + xi_t), likewise Y.
// Derivation: docs/how_it_works.md, "The two estimators", "The joint estimator's
// noise: what is given, what is estimated, what cannot be told apart", "Robust mode".
#pragma once

#include "handeye_covariance/estimation/estimator.h"

namespace handeye {

struct JointOptions {
  int max_iterations = 50;
  /// Stop when the step's squared Mahalanobis length falls below this (< 0.1 sigma): the
  /// step is taken, without a linearisation to confirm it (Gauss-Newton's error after it is
  /// second order in it, and the information moves by a negligible share within 0.1 sigma).
  double step_tolerance = 1e-2;
  int max_noise_rounds = 20;
  /// The estimated noise model by the residuals' dof (n - 2): the full 6x6 from this many,
  /// else per-axis variances from per_axis_noise_min_dof, else one translation and one rotation variance.
  int full_noise_min_dof = 60;
  int per_axis_noise_min_dof = 12;
  /// Robot noise estimated (no noise given) from this many samples' worth of residuals.
  int robot_noise_min_dof = 6;
  /// No noise given: the view-following noise (each view's planar-target shape,
  /// view_noise.h) is a candidate beside the homogeneous model, from this many
  /// samples' worth of residuals on (view_following false: the homogeneous model
  /// alone, for comparisons).
  bool view_following = true;
  int view_following_min_dof = 12;
  /// The stated noise is refused beyond this many sigma of chi2 (about the 99.9% quantile) ...
  double chi2_test_z = 3.09;
  /// ... and then its missing part is estimated (false: only a warning, the
  /// stated noise taken as true; for comparisons).
  bool estimate_missing_noise = true;
  enum class Robust { Auto, Off, On };
  /// Auto: the Huber loss and the sandwich covariance when the kurtosis test fails.
  Robust robust = Robust::Auto;
  double kurtosis_test_z = 3.09;
  double huber_threshold_squared = 10.645;  // chi2(6) 90% quantile
  int max_robust_rounds = 30;
  SolverOptions checks;  // the degeneracy checks of the start
};

/// One sample's residual and its sensitivities at (X, Y).
struct JointResidual {
  Vector6d error = Vector6d::Zero();                        // e_i, camera frame, ROS order
  Eigen::Matrix<double, 6, 12> jacobian;                    // d e_i / d (xi_X, xi_Y)
  Matrix6d d_effector = Matrix6d::Zero();                   // d P_hat_i / d xi_E (D_i)
};
JointResidual joint_residual(const Rig& rig, const PoseSample& sample, const Eigen::Isometry3d& X,
                             const Eigen::Isometry3d& Y);

/// The residual covariance S_i of each sample of `samples` under `calibration`'s
/// noise model (Calibration::residual_noise; `noise` for the pairs estimator), at
/// its X and Y: what a view's residual e_i scatters with, about the prediction
/// P_hat_i = X^-1 V_i Y (Y the mean of the loops, noise_estimation.h pattern_pose,
/// for the pairs estimator). Every sample's, in order (the rejected too).
std::vector<Matrix6d> residual_covariances(const SampleSet& samples, const Calibration& calibration);

/// X with its covariance, Y (Calibration::pattern) with its covariance, and
/// their cross block. method = Joint; both stage diagnostics hold the joint
/// solve. Throws the degeneracy errors of solve(), InvalidNoise for a singular
/// residual covariance, PoorlyConstrained beyond SolverOptions::max_rotation_sigma.
Calibration solve_joint(const SampleSet& samples, const JointOptions& options = {});


/// Method corners, after the pose-level estimate of the same samples: X and Y
/// refined from the samples' corners (corners/corner_calibration.h: corner_refiner),
/// with the session's robust setting. A hook, so that a session runs it without
/// linking Ceres or OpenCV itself.
using CornerRefiner =
    std::function<Calibration(const SampleSet& samples, const Calibration& pose_level, JointOptions::Robust robust)>;

}  // namespace handeye
