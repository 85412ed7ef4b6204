// Judging a predicted covariance against Monte-Carlo (paper section IV-A).
//
// Error of an estimate against the truth, in ROS order (x, y, z, rx, ry, rz):
//   xi_t = t_hat - t_bar,  xi_R = log(R_hat R_bar^T)  (the paper's definitions).
// Metrics:
//   epsilon (eq. 63) = ||Sigma_PR - Sigma_MC||_F / ||Sigma_MC||_F;
//   its sampling floor: even a perfect prediction scores about
//   sqrt((1 + tr(Sigma)^2 / ||Sigma||_F^2) / M), the Frobenius spread of a
//   sample covariance of M Gaussian draws with known mean;
//   NEES = xi^T Sigma^-1 xi, whose mean is the dimension when Sigma is honest;
//   coverage: the share of errors inside the predicted 95% ellipsoid.
#pragma once

#include "handeye_covariance/core/pose_covariance.h"

namespace handeye {

/// Eq. (63).
double relative_frobenius_error(const Eigen::MatrixXd& predicted, const Eigen::MatrixXd& monte_carlo);

/// sqrt((1 + tr(S)^2 / ||S||_F^2) / M).
double sampling_floor(const Eigen::MatrixXd& covariance, int M);

struct BlockAgreement {
  double epsilon = 0.0;         // eq. (63), predicted (mean over datasets) vs Monte-Carlo
  double floor = 0.0;           // the sampling floor for this M
  double nees_mean = 0.0;       // expected: dimension
  double coverage_95 = 0.0;     // expected: 0.95
};

struct MonteCarloSummary {
  int datasets = 0;
  Matrix6d monte_carlo_covariance = Matrix6d::Zero();  // (1/M) sum xi xi^T, eq. (61-62)
  Matrix6d mean_predicted_covariance = Matrix6d::Zero();
  BlockAgreement translation, rotation, pose;  // 3, 3 and 6 dof
};

/// Accumulates (error, predicted covariance) pairs, one per dataset.
class MonteCarloAccumulator {
 public:
  void add(const Vector6d& error, const Matrix6d& predicted_covariance);
  MonteCarloSummary summary() const;

 private:
  struct Draw {
    Vector6d error;
    Matrix6d predicted;
  };
  std::vector<Draw> draws_;
};

}  // namespace handeye
