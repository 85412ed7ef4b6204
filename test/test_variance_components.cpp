// The REML variance-component fit (variance_components.h): it recovers known
// components from simulated residuals, and its own covariance matches their
// spread over repeated draws.
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <array>
#include <limits>
#include <random>

#include "handeye_covariance/estimation/variance_components.h"
#include "handeye_covariance/simulation/simulation.h"

namespace handeye {
namespace {

/// n residuals e_i ~ N(0, S_i): camera per-axis variances (shared entries) and a
/// robot rotation variance seen through a random pose's rotation and lever arm
/// (an isotropic robot translation would be isotropic in every frame, and so
/// indistinguishable from the camera's: joint_estimator.h).
struct Draw {
  VarianceComponentData data;
  std::vector<VarianceComponent> components;
};

Draw draw(Rng& rng, int n, const Eigen::VectorXd& truth) {
  Draw d;
  for (int a = 0; a < 6; ++a) add_entry_component(d.data, a, a), d.components.push_back({"camera", 1e-18});
  add_factor_component(d.data, 3), d.components.push_back({"robot rotation", 0.0});
  std::normal_distribution<double> normal(0.0, 1.0);
  for (int i = 0; i < n; ++i) {
    const Eigen::Isometry3d pose = random_pose(rng, 0.5);
    Eigen::Matrix<double, 6, 3> D;  // a rotation about a point 0-0.9 m away
    D << -so3::hat(pose.translation()) * pose.linear(), pose.linear();
    d.data.factors.push_back(D);
    d.data.fixed.push_back(Matrix6d::Zero());
    const Matrix6d S = component_covariance(d.data, d.data.fixed.size() - 1, truth);
    const Eigen::LLT<Matrix6d> llt(S);
    Vector6d z;
    for (int k = 0; k < 6; ++k) z[k] = normal(rng);
    const Vector6d e = llt.matrixL() * z;
    d.data.scatter.push_back(e * e.transpose());  // no fitted parameters: M = e e^T
  }
  return d;
}

TEST(VarianceComponents, RecoverCameraAndRobotNoiseWithAnHonestCovariance) {
  const double mm = 1e-3, deg = M_PI / 180.0;
  Eigen::VectorXd truth(7);
  truth << std::pow(0.3 * mm, 2), std::pow(0.3 * mm, 2), std::pow(1.5 * mm, 2), std::pow(0.15 * deg, 2),
      std::pow(0.15 * deg, 2), std::pow(0.05 * deg, 2), std::pow(0.1 * deg, 2);
  Rng rng(5);
  const int M = 400, n = 60;
  Eigen::VectorXd mean = Eigen::VectorXd::Zero(7), z2 = Eigen::VectorXd::Zero(7);
  std::array<int, 7> at_bound{}, counted{};
  std::array<double, 7> spread{}, predicted{};
  for (int m = 0; m < M; ++m) {
    const Draw d = draw(rng, n, truth);
    const VarianceComponentFit from_above = fit_variance_components(d.components, d.data, truth * 3.0);
    const VarianceComponentFit from_below = fit_variance_components(d.components, d.data, truth * 0.3);
    ASSERT_TRUE(from_above.converged && from_below.converged);
    // One maximum, whatever the start.
    EXPECT_NEAR(from_above.log_likelihood, from_below.log_likelihood, 1e-6 * std::abs(from_above.log_likelihood));
    for (int k = 0; k < 7; ++k) {
      mean[k] += from_above.theta[k] / truth[k] / M;
      if (from_above.at_bound[k]) {  // the draw does not support it: held at 0, no covariance
        ++at_bound[k];
        continue;
      }
      ASSERT_GT(from_above.covariance(k, k), 0.0) << k;
      z2[k] += std::pow(from_above.theta[k] - truth[k], 2) / from_above.covariance(k, k);
      spread[k] += std::pow(from_above.theta[k] - truth[k], 2);
      predicted[k] += from_above.covariance(k, k);
      ++counted[k];
    }
  }
  for (int k = 0; k < 7; ++k) z2[k] /= counted[k];
  std::printf("[variance components, n = %d, M = %d]\n  mean theta / truth: ", n, M);
  for (int k = 0; k < 7; ++k) std::printf("%.3f ", mean[k]);
  std::printf("\n  mean z^2 under the fit's covariance: ");
  for (int k = 0; k < 7; ++k) std::printf("%.3f ", z2[k]);
  std::printf("\n  Monte-Carlo variance / mean predicted variance: ");
  for (int k = 0; k < 7; ++k) std::printf("%.3f ", spread[k] / predicted[k]);
  std::printf("\n");
  for (int k = 0; k < 7; ++k) {
    EXPECT_NEAR(mean[k], 1.0, 0.1) << k;  // ML is biased low by O(1/n) only
    // The fit's covariance describes its own spread (on average: a draw with a small
    // theta_hat also has a small predicted variance, so z^2 itself runs high for
    // the components that the others swamp, up to 3 for camera y here).
    EXPECT_GT(spread[k] / predicted[k], 0.75) << k;
    EXPECT_LT(spread[k] / predicted[k], 1.33) << k;
    EXPECT_LE(at_bound[k], M / 20) << k;  // a true component is rarely unsupported
  }
}

// A step taken without a confirming evaluation (confirm_last_step = false, as the
// joint estimator's rounds take their last one) never leaves the positive definite
// S_i, nor lands on a variance's bound: with a full camera 6x6 the off-diagonal
// entries are unbounded, and the AI-REML step overshoots into an indefinite matrix
// or past a variance's bound (clamped there, S_i is nearly singular).
TEST(VarianceComponents, AnUnconfirmedStepStaysPositiveDefinite) {
  Rng rng(7);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> uniform(-0.95, 0.95);
  int moved = 0;
  for (int trial = 0; trial < 200; ++trial) {
    // Camera x and y correlated at -0.9 (a full 6x6's entry), the other axes independent.
    VarianceComponentData data;
    std::vector<VarianceComponent> components;
    for (int a = 0; a < 6; ++a) add_entry_component(data, a, a), components.push_back({"camera", 1e-18});
    add_entry_component(data, 0, 1), components.push_back({"camera xy", -std::numeric_limits<double>::infinity()});
    Eigen::VectorXd truth(7), start(7);
    truth << 1.0, 1.0, 4.0, 0.5, 0.5, 0.2, -0.9;
    for (int i = 0; i < 12; ++i) {
      data.factors.push_back(ComponentFactors(6, 0));
      data.fixed.push_back(Matrix6d::Zero());
      const Eigen::LLT<Matrix6d> llt(component_covariance(data, data.fixed.size() - 1, truth));
      Vector6d z;
      for (int k = 0; k < 6; ++k) z[k] = normal(rng);
      const Vector6d e = llt.matrixL() * z;
      data.scatter.push_back(e * e.transpose());
    }
    start << 1.0, 1.0, 4.0, 0.5, 0.5, 0.2, uniform(rng);  // any start inside: |correlation| < 1
    VarianceComponentOptions one;
    one.max_iterations = 1;
    one.confirm_last_step = false;
    const VarianceComponentFit fit = fit_variance_components(components, data, start, one);
    ASSERT_EQ(Eigen::LLT<Matrix6d>(component_covariance(data, 0, fit.theta)).info(), Eigen::Success)
        << "trial " << trial << ": theta " << fit.theta.transpose();
    // Nor onto a variance's bound, where S_i would be nearly singular (unseen without an evaluation).
    for (int k = 0; k < 6; ++k) ASSERT_GT(fit.theta[k], 1e-18) << "trial " << trial << ", number " << k;
    moved += !(fit.theta - start).isZero(0.0);
  }
  EXPECT_GE(moved, 190);  // a step is taken (shortened where it must be), not refused
}

// inverse_cholesky (written out by fixed-size blocks): L^-1 S L^-T = I with L^-1
// lower triangular and a positive diagonal, over covariances whose scales differ by
// 1e10 (mm^2 beside rad^2 of 0.01 deg); a matrix that is not positive definite is refused.
TEST(VarianceComponents, InverseCholeskyWhitensAndRefusesIndefinite) {
  std::mt19937_64 rng(11);
  std::normal_distribution<double> normal;
  for (int trial = 0; trial < 200; ++trial) {
    Matrix6d F;
    for (int r = 0; r < 6; ++r) for (int c = 0; c < 6; ++c) F(r, c) = normal(rng);
    Vector6d scale;
    scale << 1e-3, 1e-3, 3e-3, 2e-4, 2e-4, 1e-4;
    const Matrix6d S = scale.asDiagonal() * (F * F.transpose() + 0.1 * Matrix6d::Identity()) * scale.asDiagonal();
    Matrix6d L_inverse;
    ASSERT_TRUE(inverse_cholesky(S, L_inverse)) << "trial " << trial;
    EXPECT_LE((L_inverse * S * L_inverse.transpose() - Matrix6d::Identity()).norm(), 1e-9) << "trial " << trial;
    EXPECT_EQ(L_inverse.triangularView<Eigen::StrictlyUpper>().toDenseMatrix().norm(), 0.0);
    EXPECT_GT(L_inverse.diagonal().minCoeff(), 0.0);
  }
  Matrix6d indefinite = Matrix6d::Identity();
  indefinite(4, 4) = -1e-12;
  Matrix6d L_inverse;
  EXPECT_FALSE(inverse_cholesky(indefinite, L_inverse));
  EXPECT_FALSE(inverse_cholesky(Matrix6d::Zero(), L_inverse));
}

}  // namespace
}  // namespace handeye
