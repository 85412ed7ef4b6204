// The pose-level estimator (joint_estimator.h): its Jacobians against numeric
// differences, exact recovery from noise-free poses, and the honesty of the
// covariance of X and of Y against Monte-Carlo, for both setups.
#include <gtest/gtest.h>

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/estimation/joint_estimator.h"
#include "handeye_covariance/io/noise_text.h"
#include "handeye_covariance/simulation/monte_carlo.h"
#include "test_helpers.h"

namespace handeye {
namespace {

using Eigen::Isometry3d;
using Eigen::Vector3d;

Rig rig_of(Setup setup) { return {setup, {"base_link", "tool0", "camera_optical_frame", "tag_0"}}; }

/// A detector's noise: depth-heavy, tilt coupled to depth, and a robot.
MeasurementNoise realistic_noise() {
  const double mm = 1e-3, deg = M_PI / 180.0;
  MeasurementNoise noise;
  noise.camera.translation = Vector3d(0.3 * mm, 0.3 * mm, 1.5 * mm).cwiseAbs2().asDiagonal();
  noise.camera.rotation = Vector3d(0.15 * deg, 0.15 * deg, 0.05 * deg).cwiseAbs2().asDiagonal();
  noise.camera.translation_rotation(2, 0) = 0.8 * (1.5 * mm) * (0.15 * deg);
  noise.camera.translation_rotation(0, 1) = -0.5 * (0.3 * mm) * (0.15 * deg);
  noise.robot.translation = std::pow(0.05 * mm, 2) * Eigen::Matrix3d::Identity();
  noise.robot.rotation = std::pow(0.01 * deg, 2) * Eigen::Matrix3d::Identity();
  return noise;
}

TEST(JointEstimator, ResidualJacobiansMatchNumericAtZeroTinyAndNearPi) {
  for (handeye::Setup setup : {Setup::EyeInHand, Setup::EyeToHand}) {
    const Rig rig = rig_of(setup);
    for (double angle : {0.0, 1e-6, M_PI - 1e-7}) {
      const Isometry3d X = se3::make_pose(so3::exp(angle * Vector3d(2, -1, 2).normalized()), Vector3d(0.03, -0.06, 0.1));
      const Isometry3d Y = se3::make_pose(so3::exp(Vector3d(0.1, 0.2, 0.3)), Vector3d(0.6, 0.1, 0.02));
      Rng rng(9);
      PoseSample sample;
      sample.T_base_effector = random_pose(rng, 0.5);
      // A view off the loop by a few mm and a degree: a residual that is not zero.
      sample.T_camera_pattern = test::apply(rig.predicted_view(sample.T_base_effector, X, Y),
                                            (Vector6d() << 0.003, -0.002, 0.004, 0.01, -0.02, 0.015).finished());
      const JointResidual r = joint_residual(rig, sample, X, Y);
      const std::function<Vector6d(const Eigen::Matrix<double, 12, 1>&)> f = [&](const Eigen::Matrix<double, 12, 1>& d) {
        return joint_residual(rig, sample, test::apply(X, d.head<6>()), test::apply(Y, d.tail<6>())).error;
      };
      EXPECT_LE((r.jacobian - test::numeric_jacobian<6, 12>(f)).norm(), 1e-6) << to_string(setup) << " angle " << angle;
      const std::function<Vector6d(const Vector6d&)> g = [&](const Vector6d& d) {
        return test::pose_perturbation(rig.predicted_view(test::apply(sample.T_base_effector, d), X, Y),
                                       rig.predicted_view(sample.T_base_effector, X, Y));
      };
      EXPECT_LE((r.d_effector - test::numeric_jacobian<6, 6>(g)).norm(), 1e-6) << to_string(setup) << " angle " << angle;
    }
  }
}

TEST(JointEstimator, NoiseFreePosesGiveXAndYExactlyInBothSetups) {
  for (handeye::Setup setup : {Setup::EyeInHand, Setup::EyeToHand}) {
    Rng rng(2);
    SimulatedSession s = simulate_session(rng, setup, typical_X(setup), 12, MeasurementNoise{});
    s.samples.noise = realistic_noise();
    const Calibration c = solve_joint(s.samples);
    EXPECT_EQ(c.method, Method::Joint);
    EXPECT_LE(pose_error(c.T_parent_camera, s.X).norm(), 1e-9) << to_string(setup);
    ASSERT_TRUE(c.pattern);
    EXPECT_LE(pose_error(c.pattern->pose, s.T_world_pattern).norm(), 1e-9) << to_string(setup);
    EXPECT_EQ(c.rotation_stage.dof, 6 * 12 - 12);
    EXPECT_TRUE(c.rotation_stage.converged());
  }
}

// Two detections of a 30-pose session with ten times the stated noise: the
// kurtosis test fails, Huber's loss down-weighs them, the covariance is the
// sandwich, and X is closer to the truth than the plain estimate's over 20 sessions.
TEST(JointEstimator, RobustModeTakesOverOnHeavyTailedResiduals) {
  Rng rng(61);
  double robust_error = 0.0, plain_error = 0.0;
  for (int m = 0; m < 20; ++m) {
    SimulatedSession s = simulate_session(rng, Setup::EyeInHand, typical_X(Setup::EyeInHand), 30, realistic_noise());
    MeasurementNoise wild = realistic_noise();
    wild.camera.translation *= 100.0, wild.camera.rotation *= 100.0, wild.camera.translation_rotation *= 100.0;
    for (int k : {4, 17}) {
      PoseSample& sample = s.samples.samples[static_cast<std::size_t>(k)];
      sample.T_camera_pattern = perturb(rng, sample.T_camera_pattern, wild.camera);
    }
    s.samples.noise.reset();
    const Calibration c = solve_joint(s.samples);
    JointOptions off;  // the same start (its checks as in robust mode), then the plain model
    off.robust = JointOptions::Robust::Off;
    off.checks.angle_mismatch_sigmas = 20.0;
    off.checks.min_angle_mismatch_without_noise = 5.0 * M_PI / 180.0;
    const Calibration plain = solve_joint(s.samples, off);
    ASSERT_FALSE(c.residual_checks.empty());
    EXPECT_FALSE(c.residual_checks.back().passed) << c.residual_checks.back().test << " " << c.residual_checks.back().statistic;
    EXPECT_EQ(c.loss, Loss::Huber);
    EXPECT_EQ(c.covariance_kind, CovarianceKind::Sandwich);
    EXPECT_GE(c.downweighted, 2);
    EXPECT_EQ(plain.covariance_kind, CovarianceKind::Information);
    EXPECT_TRUE(c.pose_covariance.allFinite());
    robust_error += pose_error(c.T_parent_camera, s.X).head<3>().squaredNorm();
    plain_error += pose_error(plain.T_parent_camera, s.X).head<3>().squaredNorm();
  }
  std::printf("[robust mode, 20 sessions with 2 wild detections] RMS translation error: Huber %.3f mm, plain %.3f mm\n",
              std::sqrt(robust_error / 20) * 1e3, std::sqrt(plain_error / 20) * 1e3);
  EXPECT_LT(robust_error, plain_error);
}

TEST(JointEstimator, DegenerateSessionsAreRefusedLikeThePairsEstimator) {
  Rng rng(4);
  SimulatedSession s = simulate_session(rng, Setup::EyeInHand, typical_X(Setup::EyeInHand), 6, realistic_noise());
  SampleSet translated = s.samples;
  for (std::size_t i = 0; i < translated.samples.size(); ++i) {  // the robot only translates
    PoseSample& p = translated.samples[i];
    p.T_base_effector.linear() = s.samples.samples[0].T_base_effector.linear();
    p.T_base_effector.translation() += Vector3d(0.01 * i, -0.02 * i, 0.015 * i);
    p.T_camera_pattern = translated.rig.predicted_view(p.T_base_effector, s.X, s.T_world_pattern);
  }
  try {
    solve_joint(translated);
    FAIL() << "a pure translation was solved";
  } catch (const HandEyeError& e) {
    EXPECT_EQ(e.code(), ErrorCode::PureTranslation) << e.what();
  }
  SampleSet two = s.samples;
  two.samples.resize(2);
  EXPECT_THROW(solve_joint(two), HandEyeError);
}

struct Honesty {
  MonteCarloSummary X, Y;
  double rms_translation_joint = 0, rms_translation_pairs = 0;
};

Honesty study(Setup setup, int M, int n, bool noise_given, unsigned seed) {
  MonteCarloAccumulator x, y;
  Honesty h;
  Rng rng(seed);
  for (int m = 0; m < M; ++m) {
    SimulatedSession s = simulate_session(rng, setup, typical_X(setup), n, realistic_noise());
    if (!noise_given) s.samples.noise.reset();
    const Calibration c = solve_joint(s.samples);
    x.add(pose_error(c.T_parent_camera, s.X), c.pose_covariance);
    y.add(pose_error(c.pattern->pose, s.T_world_pattern), c.pattern->covariance);
    h.rms_translation_joint += pose_error(c.T_parent_camera, s.X).head<3>().squaredNorm() / M;
    if (noise_given && m < 300) {
      h.rms_translation_pairs += pose_error(solve(s.samples).T_parent_camera, s.X).head<3>().squaredNorm() / 300;
    }
  }
  h.X = x.summary();
  h.Y = y.summary();
  return h;
}

void print(const char* label, const Honesty& h) {
  std::printf("[%s] X: NEES t %.3f R %.3f 6dof %.3f eps_t %.3f (floor %.3f) eps_R %.3f (floor %.3f) | "
              "Y: NEES t %.3f R %.3f 6dof %.3f\n",
              label, h.X.translation.nees_mean, h.X.rotation.nees_mean, h.X.pose.nees_mean, h.X.translation.epsilon,
              h.X.translation.floor, h.X.rotation.epsilon, h.X.rotation.floor, h.Y.translation.nees_mean,
              h.Y.rotation.nees_mean, h.Y.pose.nees_mean);
}

TEST(JointEstimator, CovarianceOfXAndYIsHonestWithTheNoiseGiven) {
  for (handeye::Setup setup : {Setup::EyeInHand, Setup::EyeToHand}) {
    const Honesty h = study(setup, 2000, 30, true, setup == Setup::EyeInHand ? 31u : 32u);
    print(to_string(setup), h);
    for (const MonteCarloSummary* s : {&h.X, &h.Y}) {
      EXPECT_NEAR(s->translation.nees_mean, 3.0, 0.15);
      EXPECT_NEAR(s->rotation.nees_mean, 3.0, 0.15);
      EXPECT_NEAR(s->pose.nees_mean, 6.0, 0.25);
      EXPECT_LE(s->translation.epsilon, 1.5 * s->translation.floor);
      EXPECT_LE(s->rotation.epsilon, 1.5 * s->rotation.floor);
    }
    // Weighing each pose by its own 6x6 beats the pairs' weights on the same data.
    std::printf("  RMS translation error: joint %.4f mm, pairs %.4f mm\n", std::sqrt(h.rms_translation_joint) * 1e3,
                std::sqrt(h.rms_translation_pairs) * 1e3);
    EXPECT_LT(h.rms_translation_joint, h.rms_translation_pairs);
  }
}

}  // namespace
}  // namespace handeye

namespace handeye {
namespace {

// No noise block (the common case): the camera noise is estimated from the
// residuals, with as many numbers as they support, and the covariance includes
// the estimate's own uncertainty, so the NEES of X stays about 6 (without that
// factor it would follow Hotelling's 6 nu / (nu - 7): 8.0 at 30 poses).
TEST(JointEstimator, WithTheNoiseEstimatedTheCovarianceStaysHonest) {
  struct Case {
    int n, M;
    NoiseModelChoice::Camera camera;
  };
  for (const Case& c : {Case{30, 1000, NoiseModelChoice::Camera::PerAxis}, Case{100, 400, NoiseModelChoice::Camera::Full}}) {
    MonteCarloAccumulator x, y;
    Rng rng(40 + c.n);
    std::string model;
    for (int m = 0; m < c.M; ++m) {
      SimulatedSession s = simulate_session(rng, Setup::EyeInHand, typical_X(Setup::EyeInHand), c.n, realistic_noise());
      s.samples.noise.reset();
      const Calibration cal = solve_joint(s.samples);
      EXPECT_EQ(cal.noise_origin, NoiseOrigin::EstimatedFromResiduals);
      ASSERT_TRUE(cal.noise_model);
      EXPECT_EQ(cal.noise_model->camera, c.camera);
      model = io::noise_model_text(cal);
      x.add(pose_error(cal.T_parent_camera, s.X), cal.pose_covariance);
      y.add(pose_error(cal.pattern->pose, s.T_world_pattern), cal.pattern->covariance);
    }
    const MonteCarloSummary X = x.summary(), Y = y.summary();
    std::printf("[estimated noise, %d poses, M = %d] X NEES 6dof %.3f (t %.3f R %.3f), Y NEES 6dof %.3f; model: %s\n", c.n,
                c.M, X.pose.nees_mean, X.translation.nees_mean, X.rotation.nees_mean, Y.pose.nees_mean, model.c_str());
    EXPECT_NEAR(X.pose.nees_mean, 6.0, 0.7);
    EXPECT_NEAR(Y.pose.nees_mean, 6.0, 0.7);
  }
}

}  // namespace
}  // namespace handeye
