// Noise estimation (eq. 64-67): on simulated sessions with known, anisotropic
// noise, each estimated covariance element must lie within 4 sigma of its
// sampling error, sqrt((S_jj S_kk + S_jk^2) / dof).
#include "handeye_covariance/estimation/noise_estimation.h"

#include "handeye_covariance/estimation/estimator.h"
#include "test_helpers.h"

namespace handeye {
namespace {

/// The noise of the paper's real camera (published version): anisotropic, correlated.
MeasurementNoise camera_like_noise(double robot_scale) {
  MeasurementNoise noise;
  noise.camera.rotation << 5.7, -2.3, -2.8, -2.3, 18.1, 3.8, -2.8, 3.8, 1.8;
  noise.camera.rotation *= 1e-6 * 0.25;
  noise.camera.translation << 0.04, 0.01, 0.0, 0.01, 0.05, 0.05, 0.0, 0.05, 0.36;  // depth dominates
  noise.camera.translation *= 1e-6;
  noise.robot.rotation = robot_scale * std::pow(0.01 * M_PI / 180, 2) * Eigen::Matrix3d::Identity();
  noise.robot.translation = robot_scale * std::pow(0.05e-3, 2) * Eigen::Matrix3d::Identity();
  return noise;
}

/// Worst |estimate - truth| over the 3x3, in units of the element's sampling
/// sigma; `spread` is the covariance of what was sampled (the truth, unless
/// other noise was in the residuals and subtracted).
double worst_z(const Eigen::Matrix3d& estimate, const Eigen::Matrix3d& truth, double dof,
               std::optional<Eigen::Matrix3d> spread = std::nullopt) {
  const Eigen::Matrix3d S = spread ? *spread : truth;
  double worst = 0.0;
  for (int j = 0; j < 3; ++j) {
    for (int k = 0; k < 3; ++k) {
      const double sigma = std::sqrt((S(j, j) * S(k, k) + S(j, k) * S(j, k)) / dof);
      worst = std::max(worst, std::abs(estimate(j, k) - truth(j, k)) / sigma);
    }
  }
  return worst;
}

TEST(NoiseEstimation, MeanPoseIsEq66And67AndHoldsNearPi) {
  const Eigen::Isometry3d centre = se3::make_pose(so3::exp(Eigen::Vector3d(0, 0, M_PI - 0.01)), Eigen::Vector3d(1, 2, 3));
  std::vector<Eigen::Isometry3d> poses;
  for (double s : {-1.0, 1.0}) {
    for (int axis = 0; axis < 3; ++axis) {
      Vector6d d = Vector6d::Zero();
      d(axis) = 0.01 * s;
      d(3 + axis) = 0.05 * s;  // symmetric spread, crossing pi about z
      poses.push_back(test::apply(centre, d));
    }
  }
  const Eigen::Isometry3d mean = mean_pose(poses);
  EXPECT_LT((mean.translation() - centre.translation()).norm(), 1e-12);
  EXPECT_LT(so3::log(mean.linear() * centre.linear().transpose()).norm(), 1e-6);
}

TEST(NoiseEstimation, ResidualsRecoverTheCameraNoiseWithXGivenOrFitted) {
  for (handeye::Setup setup : {Setup::EyeInHand, Setup::EyeToHand}) {
    Rng rng(8);
    const MeasurementNoise truth = camera_like_noise(0.0);
    const SimulatedSession session = simulate_session(rng, setup, typical_X(setup), 1000, truth);
    const NoiseEstimate given = noise_from_residuals(session.samples, session.X, false);
    SampleSet unlabelled = session.samples;
    unlabelled.noise.reset();
    const Calibration c = solve(unlabelled);
    const NoiseEstimate fitted = noise_from_residuals(session.samples, c.T_parent_camera, true);
    for (const NoiseEstimate* e : {&given, &fitted}) {
      const double zR = worst_z(e->noise.camera.rotation, truth.camera.rotation, e->dof);
      const double zt = worst_z(e->noise.camera.translation, truth.camera.translation, e->dof);
      std::printf("%s, X %s: dof %.0f, worst element |z| rotation %.2f translation %.2f\n", to_string(setup),
                  e == &given ? "given" : "fitted", e->dof, zR, zt);
      EXPECT_LT(zR, 4.0);
      EXPECT_LT(zt, 4.0);
      EXPECT_FALSE(e->robot_identified);
      EXPECT_EQ(e->noise.robot.rotation, Eigen::Matrix3d::Zero());
    }
  }
}

TEST(NoiseEstimation, ResidualsWithAGivenRobotNoiseSubtractIt) {
  Rng rng(9);
  // Robot noise 4x the usual variance: ignoring it inflates the camera's estimate.
  const MeasurementNoise truth = camera_like_noise(4.0);
  const SimulatedSession session = simulate_session(rng, Setup::EyeInHand, typical_X(Setup::EyeInHand), 1000, truth);
  const NoiseEstimate subtracted = noise_from_residuals(session.samples, session.X, false, truth.robot);
  const NoiseEstimate absorbed = noise_from_residuals(session.samples, session.X, false);
  // The residuals sampled camera + robot noise: that total sets the sampling error.
  const double z_sub = worst_z(subtracted.noise.camera.translation, truth.camera.translation, subtracted.dof,
                               absorbed.noise.camera.translation);
  const double z_sub_R = worst_z(subtracted.noise.camera.rotation, truth.camera.rotation, subtracted.dof,
                                 absorbed.noise.camera.rotation);
  const double z_abs = worst_z(absorbed.noise.camera.translation, truth.camera.translation, absorbed.dof);
  std::printf("robot subtracted: worst |z| %.2f (rotation %.2f); robot absorbed: %.2f\n", z_sub, z_sub_R, z_abs);
  EXPECT_LT(z_sub, 4.0);
  EXPECT_LT(z_sub_R, 4.0);
  EXPECT_GT(z_abs, 6.0) << "the robot's share should be visible at this level";
  EXPECT_GT(absorbed.noise.camera.translation.trace(), subtracted.noise.camera.translation.trace());
}

TEST(NoiseEstimation, RepeatedObservationsRecoverRobotAndCamera) {
  Rng rng(10);
  const MeasurementNoise truth = camera_like_noise(1.0);
  const SimulatedSession poses = simulate_session(rng, Setup::EyeInHand, typical_X(Setup::EyeInHand), 60, {});
  SampleSet samples = poses.samples;
  samples.samples.clear();
  for (const PoseSample& pose : poses.samples.samples) {  // 60 poses x 10 detections each
    for (int r = 0; r < 10; ++r) {
      PoseSample s = pose;
      s.T_base_effector = perturb(rng, pose.T_base_effector, truth.robot);
      s.T_camera_pattern = perturb(rng, pose.T_camera_pattern, truth.camera);
      samples.samples.push_back(s);
    }
  }
  const NoiseEstimate e = noise_from_repeated_observations(samples);
  EXPECT_EQ(e.groups, 60);
  EXPECT_DOUBLE_EQ(e.dof, 540.0);
  EXPECT_TRUE(e.robot_identified);
  const double z[4] = {worst_z(e.noise.camera.rotation, truth.camera.rotation, e.dof),
                       worst_z(e.noise.camera.translation, truth.camera.translation, e.dof),
                       worst_z(e.noise.robot.rotation, truth.robot.rotation, e.dof),
                       worst_z(e.noise.robot.translation, truth.robot.translation, e.dof)};
  std::printf("repeated: worst |z| camera R %.2f t %.2f, robot R %.2f t %.2f\n", z[0], z[1], z[2], z[3]);
  for (double v : z) EXPECT_LT(v, 4.0);
}

TEST(NoiseEstimation, RefusesWhatCannotBeEstimated) {
  Rng rng(11);
  const SimulatedSession session = simulate_session(rng, Setup::EyeInHand, typical_X(Setup::EyeInHand), 12,
                                                    camera_like_noise(1.0));
  try {  // every pose seen once
    noise_from_repeated_observations(session.samples);
    FAIL();
  } catch (const HandEyeError& e) {
    EXPECT_EQ(e.code(), ErrorCode::NoiseUnidentifiable);
    EXPECT_NE(std::string(e.what()).find("hold the robot still"), std::string::npos) << e.what();
  }
  SampleSet three = session.samples;
  three.samples.resize(3);
  EXPECT_THROW(noise_from_residuals(three, session.X, true), HandEyeError);
  Eigen::Isometry3d bad = session.X;
  bad.linear() *= 2.0;
  EXPECT_THROW(noise_from_residuals(session.samples, bad, false), HandEyeError);
}

}  // namespace
}  // namespace handeye
