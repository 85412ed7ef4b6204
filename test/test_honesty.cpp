// The split-half check calibrated to the session (split_check.h): its simulated
// sessions, its reference on honest sessions, and what its verdict does.
#include <gtest/gtest.h>

#include <cstdio>

#include "handeye_covariance/estimation/split_check.h"
#include "handeye_covariance/session/calibration_session.h"
#include "handeye_covariance/simulation/simulation.h"

namespace handeye {
namespace {

SampleSet honest_session(int n, unsigned seed, bool noise_given) {
  Rng rng(seed);
  SimulatedSession s = simulate_session(rng, Setup::EyeInHand, typical_X(Setup::EyeInHand), n, paper_noise(1e-5));
  if (!noise_given) s.samples.noise.reset();
  return s.samples;
}

// Each simulated view scatters about the fitted prediction with the fitted
// residual covariance S_i: over many draws, the mean of the residuals is 0 and
// their covariance S_i (the robot's share in it included).
TEST(Honesty, SimulatedViewsScatterWithTheFittedResidualCovariance) {
  const SampleSet samples = honest_session(20, 4, false);
  const Calibration fitted = solve_joint(samples);
  const std::vector<Matrix6d> S = residual_covariances(samples, fitted);
  ASSERT_EQ(S.size(), samples.samples.size());
  std::mt19937_64 rng(9);
  const int draws = 4000;
  const std::size_t i = 7;
  const Eigen::Isometry3d predicted = samples.rig.predicted_view(samples.samples[i].T_base_effector, fitted.T_parent_camera,
                                                                 fitted.pattern->pose);
  Vector6d mean = Vector6d::Zero();
  Matrix6d second = Matrix6d::Zero();
  for (int k = 0; k < draws; ++k) {
    const SampleSet simulated = simulate_like(samples, fitted, S, rng);
    EXPECT_FALSE(simulated.samples[i].corners);
    const Vector6d e = pose_error(simulated.samples[i].T_camera_pattern, predicted);
    mean += e / draws;
    second += e * e.transpose() / draws;
  }
  const Matrix6d covariance = second - mean * mean.transpose();
  const Vector6d sigma = S[i].diagonal().cwiseSqrt();
  for (int a = 0; a < 6; ++a) {
    EXPECT_LT(std::abs(mean(a)), 4.0 * sigma(a) / std::sqrt(draws)) << a;
    // A variance from 4000 draws: relative 1 sigma sqrt(2 / 4000) = 2.2%.
    EXPECT_NEAR(covariance(a, a) / S[i](a, a), 1.0, 0.09) << a;
  }
}

// The reference itself: on simulated honest sessions of 8, 16 and 30 samples
// (noise estimated from the residuals, as most sessions are run), the session's
// split-half NEES over its reference averages 1.00 +- 0.05, and the verdict calls
// an honest session overconfident about as often as its 95% quantile says.
TEST(Honesty, TheReferenceAveragesOneOnHonestSessions) {
  struct Size {
    int n, sessions;
  };
  for (const Size size : {Size{8, 100}, Size{16, 60}, Size{30, 40}}) {
    double sum = 0.0, squares = 0.0;
    int checked = 0, overconfident = 0;
    for (int m = 0; m < size.sessions; ++m) {
      const SampleSet samples = honest_session(size.n, 1000u * size.n + m, false);
      SessionSettings settings = session_settings(samples);
      settings.honesty.replicates = 50;
      settings.honesty.replicate_splits = 20;
      CalibrationSession session(settings);
      session.replace(samples.samples, "simulated");
      const Calibration c = session.calibrate_checked(session.snapshot());
      ASSERT_TRUE(c.honesty);
      if (c.honesty->verdict == "not run") continue;
      ++checked;
      sum += c.honesty->ratio;
      squares += c.honesty->ratio * c.honesty->ratio;
      overconfident += c.honesty->verdict == "overconfident" ? 1 : 0;
    }
    const double mean = sum / checked, spread = std::sqrt(squares / checked - mean * mean);
    std::printf("[ figures  ] %d honest sessions of %d: ratio %.3f +- %.3f (1 sigma of the mean; per session %.3f), "
                "called overconfident %d\n",
                checked, size.n, mean, spread / std::sqrt(checked), spread, overconfident);
    EXPECT_GE(checked, size.sessions - 2);
    EXPECT_NEAR(mean, 1.0, 0.05) << size.n;
    EXPECT_LE(overconfident, std::max(3, checked / 10)) << size.n;  // about 5% expected
  }
}

// An overconfident verdict inflates X's, Y's and their cross covariance by the
// ratio and keeps the model's; --no-inflation's record keeps the model's alone.
TEST(Honesty, AnOverconfidentVerdictInflatesTheCovariances) {
  const SampleSet samples = honest_session(20, 5, true);
  const Calibration model = solve_joint(samples);
  HonestyCheck check;
  check.observed.splits = 200;
  check.observed.half_size = 10;
  check.observed.trimmed_mean_nees = 12.0;
  check.reference.replicates = 100;
  check.reference.mean = 6.0, check.reference.low = 4.5, check.reference.high = 8.0;
  check.ratio = 2.0;
  check.verdict = Honesty::Overconfident;
  check.inflation = 2.0;
  check.text = "overconfident x2: sigma is about 1.4x too small";
  Calibration inflated = model;
  record_honesty(inflated, check, true);
  ASSERT_TRUE(inflated.honesty);
  EXPECT_EQ(inflated.honesty->verdict, "overconfident");
  EXPECT_DOUBLE_EQ(inflated.honesty->inflation, 2.0);
  EXPECT_TRUE(inflated.pose_covariance.isApprox(2.0 * model.pose_covariance));
  EXPECT_TRUE(inflated.rotation_covariance.isApprox(2.0 * model.rotation_covariance));
  EXPECT_TRUE(inflated.pattern->covariance.isApprox(2.0 * model.pattern->covariance));
  EXPECT_TRUE(inflated.cross_covariance.isApprox(2.0 * model.cross_covariance));
  EXPECT_TRUE(inflated.honesty->model_pose_covariance.isApprox(model.pose_covariance));
  EXPECT_NE(inflated.warnings.front().find("the covariance is the model's x2"), std::string::npos) << inflated.warnings.front();

  Calibration reported = model;
  record_honesty(reported, check, false);
  EXPECT_DOUBLE_EQ(reported.honesty->inflation, 1.0);
  EXPECT_TRUE(reported.pose_covariance.isApprox(model.pose_covariance));

  check.verdict = Honesty::Underconfident;  // errs safe: never deflated
  check.ratio = 0.5, check.inflation = 1.0;
  Calibration cautious = model;
  record_honesty(cautious, check, true);
  EXPECT_TRUE(cautious.pose_covariance.isApprox(model.pose_covariance));
}

// A session whose stated noise is 3x too small and trusted (the pairs estimator)
// is called overconfident by about 9 in variance, and after the inflation the
// covariance covers the truth: X's NEES against the truth falls from tens to
// about its dimension.
TEST(Honesty, AnUnderstatedNoiseIsCaughtAndTheInflatedCovarianceCoversTheTruth) {
  double model_nees = 0.0, inflated_nees = 0.0, ratio = 0.0;
  const int sessions = 12;
  for (int m = 0; m < sessions; ++m) {
    Rng rng(300 + m);
    SimulatedSession s = simulate_session(rng, Setup::EyeInHand, typical_X(Setup::EyeInHand), 30, paper_noise(1e-5));
    for (PoseNoise* noise : {&s.samples.noise->camera, &s.samples.noise->robot}) {
      noise->rotation /= 9.0;
      noise->translation /= 9.0;
    }
    SessionSettings settings = session_settings(s.samples);
    settings.method = Method::Pairs;
    settings.honesty.replicates = 30;
    CalibrationSession session(settings);
    session.replace(s.samples.samples, "simulated");
    const Calibration c = session.calibrate_checked(session.snapshot());
    ASSERT_TRUE(c.honesty);
    EXPECT_EQ(c.honesty->verdict, "overconfident") << m;
    const Vector6d e = pose_error(c.T_parent_camera, s.X);
    model_nees += e.dot(c.honesty->model_pose_covariance.ldlt().solve(e)) / sessions;
    inflated_nees += e.dot(c.pose_covariance.ldlt().solve(e)) / sessions;
    ratio += c.honesty->ratio / sessions;
  }
  std::printf("[ figures  ] noise stated 3x too small (pairs), %d sessions of 30: ratio %.2f; NEES of X against the truth "
              "%.2f with the model's covariance, %.2f inflated\n",
              sessions, ratio, model_nees, inflated_nees);
  EXPECT_GT(model_nees, 30.0);
  EXPECT_GT(inflated_nees, 3.0);
  EXPECT_LT(inflated_nees, 9.0);
}

}  // namespace
}  // namespace handeye
