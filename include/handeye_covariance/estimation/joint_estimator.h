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
// Noise: as given (per sample, else the global block). With none given, the
// camera noise is estimated as one full 6x6 in the camera frame (where depth
// dominates), iterated with the solve: Sigma_c = sum e e^T / (n - 2) (12
// parameters absorb 2 samples' worth of the 6n residuals); the robot is taken
// as exact, its noise then part of the camera's. The model has as many numbers as
// the residuals' dof nu = n - 2 support: the full 6x6 from nu >= 60, the 6
// per-axis variances from nu >= 12 (depth stays apart from lateral), else one
// translation and one rotation variance. A noise estimated from nu dof is itself
// uncertain: the covariance of (X, Y) is the expected one over that uncertainty,
// the point value times nu / (nu - 7) (full: the inverse-Wishart mean), nu / (nu - 2)
// (per axis: the inverse-gamma mean), or 3 nu / (3 nu - 2) (pooled), so that the
// NEES of X stays about 6 (Monte-Carlo in test_joint_estimator).
#pragma once

#include "handeye_covariance/estimation/estimator.h"

namespace handeye {

struct JointOptions {
  int max_iterations = 50;
  /// Stop when the step's squared Mahalanobis length falls below this (< 1e-4 sigma).
  double step_tolerance = 1e-8;
  /// Noise estimation: stop when the estimated 6x6 changes by less than this (relative, Frobenius).
  double noise_tolerance = 1e-4;
  int max_noise_rounds = 20;
  /// The estimated noise model by the residuals' dof (n - 2): the full 6x6 from this many,
  /// else per-axis variances from 6, else one translation and one rotation variance.
  int full_noise_min_dof = 60;
  int per_axis_noise_min_dof = 12;
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

/// X with its covariance, Y (Calibration::pattern) with its covariance, and
/// their cross block. method = Joint; both stage diagnostics hold the joint
/// solve. Throws the degeneracy errors of solve(), InvalidNoise for a singular
/// residual covariance, PoorlyConstrained beyond SolverOptions::max_rotation_sigma.
Calibration solve_joint(const SampleSet& samples, const JointOptions& options = {});

/// Pose samples by either estimator: solve_joint, or solve (the paper's pairs).
Calibration estimate(const SampleSet& samples, Method method);

}  // namespace handeye
