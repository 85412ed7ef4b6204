// The covariance is the product: every claim about it is checked against
// Monte-Carlo. epsilon (eq. 63) is judged against its sampling floor, and the
// NEES mean against the dimension (3 for rotation and for translation).
#include <gtest/gtest.h>

#include <functional>

#include "handeye_covariance/core/estimator.h"
#include "handeye_covariance/core/monte_carlo.h"
#include "test_helpers.h"

namespace handeye {
namespace {

using Eigen::Isometry3d;
using Eigen::Matrix3d;


struct Study {
  MonteCarloSummary ours;       // the full first-order covariance
  MonteCarloSummary per_pair;   // eq. (35) and (56) as printed
  int not_converged = 0;
};

/// One dataset: returns the truth and the calibration.
using Draw = std::function<std::pair<Isometry3d, Calibration>(Rng&)>;

Study run(const Draw& draw, unsigned seed, int datasets = 2000) {
  Rng rng(seed);
  MonteCarloAccumulator ours, per_pair;
  Study study;
  for (int m = 0; m < datasets; ++m) {
    const auto [truth, c] = draw(rng);
    const Vector6d error = pose_error(c.T_parent_camera, truth);
    ours.add(error, c.pose_covariance);
    per_pair.add(error, c.per_pair_covariance.as_pose_covariance());
    study.not_converged += (c.rotation_stage.converged() && c.translation_stage.converged()) ? 0 : 1;
  }
  study.ours = ours.summary();
  study.per_pair = per_pair.summary();
  return study;
}

void expect_honest(const Study& study, const std::string& label) {
  const MonteCarloSummary& s = study.ours;
  SCOPED_TRACE(label);
  EXPECT_LE(s.rotation.epsilon, 1.5 * s.rotation.floor) << "rotation epsilon vs floor";
  EXPECT_LE(s.translation.epsilon, 1.5 * s.translation.floor) << "translation epsilon vs floor";
  EXPECT_GE(s.rotation.nees_mean, 2.8);
  EXPECT_LE(s.rotation.nees_mean, 3.2);
  EXPECT_GE(s.translation.nees_mean, 2.8);
  EXPECT_LE(s.translation.nees_mean, 3.2);
  EXPECT_NEAR(s.rotation.coverage_95, 0.95, 0.02);
  EXPECT_NEAR(s.translation.coverage_95, 0.95, 0.02);
  std::printf("[%s] eps_R %.3f (floor %.3f)  eps_t %.3f (floor %.3f)  NEES R %.3f t %.3f 6dof %.3f"
              "  | eq. (35)/(56) NEES R %.2f t %.2f\n",
              label.c_str(), s.rotation.epsilon, s.rotation.floor, s.translation.epsilon, s.translation.floor,
              s.rotation.nees_mean, s.translation.nees_mean, s.pose.nees_mean, study.per_pair.rotation.nees_mean,
              study.per_pair.translation.nees_mean);
}

Draw paper_pairs(double lambda, double translation_extent = 0.5, double translation_noise_scale = 1.0) {
  return [=](Rng& rng) {
    static const Isometry3d X = [] { Rng r(77); return random_pose(r, 0.5); }();
    MeasurementNoise noise = paper_noise(lambda);
    noise.robot.translation *= translation_noise_scale;
    noise.camera.translation *= translation_noise_scale;
    return std::make_pair(X, solve(simulate_motions(rng, X, 30, noise, translation_extent)));
  };
}

Draw pose_stream(Setup setup, double lambda) {
  return [=](Rng& rng) {
    const SimulatedSession s = simulate_session(rng, setup, typical_X(setup), 31, paper_noise(lambda));
    return std::make_pair(s.X, solve(s.samples));
  };
}

TEST(MonteCarlo, PaperProtocolIndependentPairs) {
  for (double lambda : {1e-5, 1e-4, 1e-3}) {
    const Study study = run(paper_pairs(lambda), 11);
    expect_honest(study, "pairs lambda=" + std::to_string(lambda));
    EXPECT_EQ(study.not_converged, 0);
  }
}

TEST(MonteCarlo, PoseStreamEyeInHand) {
  const Study study = run(pose_stream(Setup::EyeInHand, 1e-5), 12);
  expect_honest(study, "stream eye_in_hand");
  // Treating consecutive motions as independent is overconfident (NEES well above 3):
  // this is what the pose-level noise propagation fixes.
  EXPECT_GT(study.per_pair.rotation.nees_mean, 3.6);
}

TEST(MonteCarlo, PoseStreamEyeToHand) {
  const Study study = run(pose_stream(Setup::EyeToHand, 1e-5), 13);
  expect_honest(study, "stream eye_to_hand");
  EXPECT_GT(study.per_pair.rotation.nees_mean, 3.6);
}

TEST(MonteCarlo, RotationDominatedTranslation) {
  // |t_B| ~ 1 m and tiny translation noise: the rotation estimate's error,
  // shared by every pair, dominates t. Eq. (56) as printed is overconfident here.
  // Here the translation NEES has a slightly heavier tail than chi2(3), so short
  // runs scatter (M = 4000 stretches gave NEES 2.96-3.13); M = 20000 measures
  // it to +-0.02 (three seeds: 3.02, 3.03, 2.96).
  const Study study = run(paper_pairs(1e-5, 1.0, 1e-3), 14, 20000);
  expect_honest(study, "rotation-dominated");
  EXPECT_GT(study.per_pair.translation.nees_mean, 4.0);
}

}  // namespace
}  // namespace handeye
