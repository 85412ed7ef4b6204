#include "handeye_covariance/simulation/monte_carlo.h"
#include "handeye_covariance/core/statistics.h"

#include <Eigen/Cholesky>

namespace handeye {

double relative_frobenius_error(const Eigen::MatrixXd& predicted, const Eigen::MatrixXd& monte_carlo) {
  return (predicted - monte_carlo).norm() / monte_carlo.norm();
}

double sampling_floor(const Eigen::MatrixXd& covariance, int M) {
  const double trace = covariance.trace();
  return std::sqrt((1.0 + trace * trace / covariance.squaredNorm()) / M);
}

void MonteCarloAccumulator::add(const Vector6d& error, const Matrix6d& predicted_covariance) {
  draws_.push_back({error, predicted_covariance});
}

namespace {

template <int N>
BlockAgreement agreement(const std::vector<Eigen::Matrix<double, N, 1>>& errors,
                         const std::vector<Eigen::Matrix<double, N, N>>& predicted) {
  using Matrix = Eigen::Matrix<double, N, N>;
  const int M = static_cast<int>(errors.size());
  Matrix monte_carlo = Matrix::Zero(), mean_predicted = Matrix::Zero();
  BlockAgreement a;
  int inside = 0;
  for (int m = 0; m < M; ++m) {
    monte_carlo += errors[m] * errors[m].transpose();
    mean_predicted += predicted[m];
    const double nees = errors[m].dot(predicted[m].ldlt().solve(errors[m]));
    a.nees_mean += nees;
    inside += nees <= chi2_quantile(N, 0.95) ? 1 : 0;
  }
  monte_carlo /= M;
  mean_predicted /= M;
  a.nees_mean /= M;
  a.coverage_95 = static_cast<double>(inside) / M;
  a.epsilon = relative_frobenius_error(mean_predicted, monte_carlo);
  a.floor = sampling_floor(mean_predicted, M);
  return a;
}

}  // namespace

MonteCarloSummary MonteCarloAccumulator::summary() const {
  MonteCarloSummary s;
  s.datasets = static_cast<int>(draws_.size());
  if (draws_.empty()) return s;
  std::vector<Eigen::Vector3d> et, eR;
  std::vector<Eigen::Matrix3d> Pt, PR;
  std::vector<Vector6d> e6;
  std::vector<Matrix6d> P6;
  for (const Draw& d : draws_) {
    et.push_back(d.error.head<3>());
    eR.push_back(d.error.tail<3>());
    Pt.push_back(d.predicted.topLeftCorner<3, 3>());
    PR.push_back(d.predicted.bottomRightCorner<3, 3>());
    e6.push_back(d.error);
    P6.push_back(d.predicted);
    s.monte_carlo_covariance += d.error * d.error.transpose();
    s.mean_predicted_covariance += d.predicted;
  }
  s.monte_carlo_covariance /= s.datasets;
  s.mean_predicted_covariance /= s.datasets;
  s.translation = agreement<3>(et, Pt);
  s.rotation = agreement<3>(eR, PR);
  s.pose = agreement<6>(e6, P6);
  return s;
}

}  // namespace handeye
