#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include "handeye_covariance/estimation/estimator.h"
#include "handeye_covariance/simulation/monte_carlo.h"
#include "test_helpers.h"

namespace handeye {
namespace {

using Eigen::Isometry3d;
using Eigen::Matrix3d;
using Eigen::Vector3d;

MeasurementNoise zero_noise() { return {}; }

void expect_recovers(const Isometry3d& estimate, const Isometry3d& truth, double tolerance) {
  const Vector6d e = pose_error(estimate, truth);
  EXPECT_LE(e.head<3>().norm(), tolerance) << "translation error " << e.head<3>().transpose();
  EXPECT_LE(e.tail<3>().norm(), tolerance) << "rotation error " << e.tail<3>().transpose();
}

void expect_valid_covariance(const Calibration& c) {
  EXPECT_TRUE(c.pose_covariance.allFinite());
  EXPECT_LE((c.pose_covariance - c.pose_covariance.transpose()).norm(), 1e-12 * c.pose_covariance.norm());
  const Eigen::SelfAdjointEigenSolver<Matrix6d> eig(c.pose_covariance);
  EXPECT_GE(eig.eigenvalues().minCoeff(), -1e-12 * eig.eigenvalues().maxCoeff());
  EXPECT_EQ(c.translation_covariance, Matrix3d(c.pose_covariance.topLeftCorner<3, 3>()));
  EXPECT_EQ(c.rotation_covariance, Matrix3d(c.pose_covariance.bottomRightCorner<3, 3>()));
}

TEST(Estimator, NoiseFreeMotionsRecoverXTo1e9) {
  Rng rng(1);
  const Isometry3d X = random_pose(rng, 0.5);
  MotionSet set = simulate_motions(rng, X, 30, zero_noise());
  set.noise = paper_noise(1e-5);  // the data is exact; the weights still need a noise model
  const Calibration c = solve(set);
  expect_recovers(c.T_parent_camera, X, 1e-9);
  expect_recovers(park_martin(set.motions), X, 1e-9);
  EXPECT_TRUE(c.rotation_stage.converged());
  EXPECT_TRUE(c.translation_stage.converged());
  expect_valid_covariance(c);
}

TEST(Estimator, NoiseFreeSamplesRecoverXTo1e9InBothSetups) {
  for (handeye::Setup setup : {Setup::EyeInHand, Setup::EyeToHand}) {
    Rng rng(2);
    SimulatedSession session = simulate_session(rng, setup, typical_X(setup), 20, zero_noise());
    session.samples.noise = paper_noise(1e-6);
    const Calibration c = solve(session.samples);
    expect_recovers(c.T_parent_camera, session.X, 1e-9);
    EXPECT_EQ(c.samples_used, 20);
    EXPECT_EQ(c.motions_used, 190);  // all pairs: 20 samples are within the default window
    SolverOptions consecutive;
    consecutive.pair_window = 1;
    const Calibration c1 = solve(session.samples, consecutive);
    EXPECT_EQ(c1.motions_used, 19);
    expect_recovers(c1.T_parent_camera, session.X, 1e-9);
    SolverOptions windowed;
    windowed.pair_window = 3;
    EXPECT_EQ(solve(session.samples, windowed).motions_used, 17 * 3 + 2 + 1);
  }
}

TEST(Estimator, NoiseFreeWithoutNoiseBlockGivesNearZeroCovariance) {
  Rng rng(3);
  SimulatedSession session = simulate_session(rng, Setup::EyeInHand, typical_X(Setup::EyeInHand), 15, zero_noise());
  session.samples.noise.reset();
  const Calibration c = solve(session.samples);
  expect_recovers(c.T_parent_camera, session.X, 1e-9);
  EXPECT_EQ(c.noise_origin, NoiseOrigin::EstimatedFromResiduals);
  EXPECT_LE(max_sigma(c.translation_covariance), 1e-9);
  EXPECT_LE(max_sigma(c.rotation_covariance), 1e-9);
  expect_valid_covariance(c);
}

TEST(Estimator, MotionsAtAndNearPiAreHandled) {
  // Rotations of exactly pi (axis sign of the log arbitrary) and pi - 1e-6.
  Rng rng(4);
  const Isometry3d X = random_pose(rng, 0.3);
  MotionSet set;
  set.noise = paper_noise(1e-6);
  const double angles[] = {M_PI, M_PI - 1e-6, M_PI, 0.7, M_PI - 1e-6, 1.3};
  for (int i = 0; i < 6; ++i) {
    const Vector3d axis = sample_gaussian(rng, Matrix3d::Identity()).normalized();
    const Isometry3d A = se3::make_pose(so3::exp(angles[i] * axis), sample_gaussian(rng, 0.1 * Matrix3d::Identity()));
    set.motions.push_back({A, X.inverse() * A * X, std::nullopt});
  }
  const Calibration c = solve(set);
  expect_recovers(c.T_parent_camera, X, 1e-9);
}

TEST(Estimator, ConvergesOnEveryDatasetFromLambda1e6To1e3) {
  // The reference implementation fails on 7-12% at 1e-5..1e-4.
  int failures = 0, datasets = 0;
  for (double lambda : {1e-6, 1e-5, 1e-4, 1e-3}) {
    Rng rng(5);
    const Isometry3d X = random_pose(rng, 0.5);
    for (int m = 0; m < 250; ++m, ++datasets) {
      const Calibration c = solve(simulate_motions(rng, X, 30, paper_noise(lambda)));
      failures += (c.rotation_stage.converged() && c.translation_stage.converged()) ? 0 : 1;
      EXPECT_LE(c.rotation_stage.iterations, 20);
    }
  }
  EXPECT_EQ(failures, 0) << "of " << datasets;
}

TEST(Estimator, WeightedSolutionBeatsParkMartin) {
  // The paper's point: weighting by the noise lowers the error of X.
  Rng rng(6);
  const Isometry3d X = random_pose(rng, 0.5);
  double ours = 0, closed_form = 0;
  for (int m = 0; m < 300; ++m) {
    const Calibration c = solve(simulate_motions(rng, X, 30, paper_noise(1e-4)));
    ours += pose_error(c.T_parent_camera, X).squaredNorm();
    closed_form += pose_error(c.initial_guess, X).squaredNorm();
  }
  EXPECT_LT(ours, 0.9 * closed_form);
}

TEST(Estimator, EstimatesUnknownNoiseFromResiduals) {
  // Isotropic pattern noise, exact robot: the estimate must find its level.
  const double sigma_R = 0.001, sigma_t = 0.0005;  // rad, m
  MeasurementNoise truth;
  truth.camera.rotation = sigma_R * sigma_R * Matrix3d::Identity();
  truth.camera.translation = sigma_t * sigma_t * Matrix3d::Identity();
  Rng rng(7);
  double sum_R = 0, sum_t = 0;
  const int runs = 40;
  MonteCarloAccumulator acc;
  for (int m = 0; m < runs; ++m) {
    SimulatedSession s = simulate_session(rng, Setup::EyeInHand, typical_X(Setup::EyeInHand), 30, truth);
    s.samples.noise.reset();
    const Calibration c = solve(s.samples);
    ASSERT_EQ(c.noise_origin, NoiseOrigin::EstimatedFromResiduals);
    sum_R += c.noise.camera.rotation(0, 0);
    sum_t += c.noise.camera.translation(0, 0);
    acc.add(pose_error(c.T_parent_camera, s.X), c.pose_covariance);
  }
  // 40 runs of 87 dof each: the mean variance is known to about 3%.
  EXPECT_NEAR(std::sqrt(sum_R / runs) / sigma_R, 1.0, 0.1);
  EXPECT_NEAR(std::sqrt(sum_t / runs) / sigma_t, 1.0, 0.1);
}

TEST(Estimator, WarnsWhenStatedNoiseIsFarTooSmall) {
  Rng rng(8);
  const Isometry3d X = random_pose(rng, 0.5);
  MotionSet set = simulate_motions(rng, X, 30, paper_noise(1e-4));
  set.noise = paper_noise(1e-6);  // 100x too small
  const Calibration c = solve(set);
  ASSERT_FALSE(c.warnings.empty());
  EXPECT_EQ(c.warnings.front().kind, Warning::Kind::StageAboveStatedNoise);
  EXPECT_GT(c.warnings.front().chi2_per_dof, 3.0);
  set.noise = paper_noise(1e-4);
  EXPECT_TRUE(solve(set).warnings.empty());
}

TEST(Estimator, PerSampleNoiseOverrideChangesTheWeights) {
  Rng rng(9);
  SimulatedSession s = simulate_session(rng, Setup::EyeInHand, typical_X(Setup::EyeInHand), 12, paper_noise(1e-5));
  const Calibration before = solve(s.samples);
  s.samples.samples[3].noise = paper_noise(1e-2);  // one sample declared very noisy
  const Calibration after = solve(s.samples);
  EXPECT_GT((after.pose_covariance - before.pose_covariance).norm(), 1e-3 * before.pose_covariance.norm());
}

}  // namespace
}  // namespace handeye
