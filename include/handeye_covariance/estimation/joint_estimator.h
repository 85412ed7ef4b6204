// The pose-level estimator: X and the pattern pose Y jointly, from the absolute
// poses, each weighed by its own covariance.
//
// Every sample i closes the loop of rig.h, Y = V_i^-1 X P_i, so the camera should
// see the predicted view  P_hat_i = X^-1 V_i Y. The residual is P_i against it,
//     e_i = (t_P - t_P_hat, log(R_P R_P_hat^T))        (ROS order, camera frame),
// with covariance S_i = Sigma_P,i + D_i Sigma_E,i D_i^T: the detection's full 6x6
// (cross block included) and the robot pose's, carried through the chain by
// D_i = d P_hat_i / d E_i. Samples are independent, so minimising sum e^T S^-1 e
// by Gauss-Newton on the manifold is the maximum-likelihood estimate (to first
// order in the robot's noise), and the inverse of the 12x12 information
// sum H^T S^-1 H is the covariance of (X, Y): no motion pairs, no sandwich over
// correlated motions, O(n) time and memory.
//
// Perturbations are left perturbations in the parent frame, ROS order, as
// everywhere: X = (exp(xi_R) R_hat, t_hat + xi_t), likewise Y; the unknown is
// (xi_X, xi_Y), 12 numbers.
//
// Start: the degeneracy checks and Park-Martin of estimator.h on consecutive
// motions (O(n)), then Y from the mean of the loop closures.
//
// Noise (joint_estimator.cpp, variance_components.h). Each sample's residual
// covariance is
//     S_i = c Sigma_P,i + C + D_i (Sigma_E,i + R) D_i^T,
// the stated detector noise Sigma_P,i (scaled by c, 1 when trusted), an estimated
// camera noise C (camera frame, where depth dominates), the stated robot noise
// Sigma_E,i and an estimated robot noise R (isotropic: one translation and one
// rotation variance), carried into the camera by D_i. What is estimated:
//   - no noise given: C with as many numbers as the residuals' dof nu = n - 2
//     support (the full 6x6 from nu >= 60, the 6 per-axis variances from 12, else
//     one for translation and one for rotation), and the robot's rotation noise
//     from nu >= 6, told from the camera's by the lever arms D_i that change from
//     pose to pose. An isotropic robot translation noise is isotropic in every
//     frame, so it is the camera's under another name: it is not fitted.
//     From nu >= 12 a second model is a candidate: the same numbers and a view's
//     shape, v G_i, G_i the planar target's pose covariance at view i for unit
//     image noise (view_noise.h; the depth of a far view is known far worse than a
//     near one's). The one with the better BIC (the restricted log-likelihood
//     less log(6n - 12) / 2 per number) is used (Calibration::noise_candidates); the
//     second is fitted only when a one-pass screen (a score bound, and the shape
//     alone at its own solution) says it may win;
//   - noise given, and the residuals pass chi2 at 99.9%: nothing;
//   - noise given, and they fail: the missing part, c and R (C when no camera
//     noise was stated). A warning says so.
// The numbers are fitted by REML, alternating with the solve until a REML step
// from the last fit on the new solve's residuals is under 0.1 sigma of each
// number, or would move X_hat by under 0.1 sigma and Sigma_X by under 0.1 of the
// spread the noise estimate's error gives it (NoisePass::settled; a solve is one
// Gauss-Newton step, the first from the AX = XB start, a later one when it moves
// by under 1 sigma), and reported with
// their uncertainty (Calibration::noise_components); one at its bound (0) is one
// the residuals do not support, and a robot number whose sigma the camera's
// numbers inflate tenfold is dropped as not separable. A noise estimated from
// few residuals is itself uncertain: X's covariance is multiplied by 1 / (1 - q_x),
// q_x the second-order excess of the NEES of X over the noise estimate's error (its
// spread and the bias of Sigma_X(theta_hat); noise_pass; numbers within 1 sigma of
// their bound left out, as the expansion overstates them), exactly 2 / nu
// for one scale from nu dof, so the NEES of X stays about 6; Y's by its own
// 1 / (1 - q_y), the same figure for Y, and the X-Y block by their geometric mean
// (one factor for both left Y's NEES at 6.50, above its F bound 6.43).
//
// Robust mode. The Mahalanobis residuals d_i (leverage-corrected, so each is
// chi2(6) under the model) are tested for heavy tails (Mardia's kurtosis, z
// beyond 3.09). When they fail (or robust mode is on): Huber's loss by iteratively
// reweighted least squares (weight min(1, k s / d_i), k^2 the chi2(6) 90% quantile,
// s^2 the robust scale median(d^2) / 5.348), and the model-robust sandwich
// covariance A^-1 B A^-1 (A the Hessian of the robust cost, B the sum of the
// samples' score outer products, each residual leverage-corrected, HC2), times
// n / (n - 7): Hotelling's mean for a 6x6 estimated from n samples' scores (HC2
// leaves them about n dof; Monte-Carlo in test_systematic).
// The result says which test ran, its figure and what was used.
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
  /// else per-axis variances from 6, else one translation and one rotation variance.
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
