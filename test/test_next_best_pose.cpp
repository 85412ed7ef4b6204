// Next-best pose: candidates are reachable, distinct views; the ranking's
// prediction is what adding the pose gives; a plan's predicted covariance is
// honest under Monte-Carlo over noisy sessions at the planned poses.
#include "handeye_covariance/estimation/next_best_pose.h"

#include "handeye_covariance/estimation/joint_estimator.h"

#include "handeye_covariance/simulation/monte_carlo.h"
#include "test_helpers.h"

namespace handeye {
namespace {

TEST(NextBestPose, CriteriaAreTheObjectSigmaAndTheLogDeterminant) {
  Matrix6d C = Matrix6d::Zero();
  C.diagonal() << 1e-8, 4e-8, 2e-8, 1e-8, 4e-8, 9e-8;
  // A point 0.7 m along the optical axis of a camera aligned with its parent:
  // x and y pick up 0.7^2 times the variance about y and x; y is worst.
  const PoseWithCovariance aligned{Eigen::Isometry3d::Identity(), C};
  EXPECT_NEAR(object_sigma(aligned, 0.7), std::sqrt(4e-8 + 0.49e-8), 1e-12);
  EXPECT_NEAR(criterion_value(aligned, SuggestCriterion::Determinant, 0.7), std::log(C.determinant()), 1e-9);
  // A camera looking along the parent's x: the lever arm turns with X, and y
  // now picks up the rotation about z.
  const PoseWithCovariance turned{Eigen::Isometry3d(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitY())), C};
  EXPECT_NEAR(object_sigma(turned, 0.7), std::sqrt(4e-8 + 0.49 * 9e-8), 1e-12);
  EXPECT_EQ(criterion_from_string("determinant"), SuggestCriterion::Determinant);
  EXPECT_THROW(criterion_from_string("trace"), HandEyeError);
}

TEST(NextBestPose, CandidatesAreReachableDistinctViews) {
  for (handeye::Setup setup : {Setup::EyeInHand, Setup::EyeToHand}) {
    Rng rng(4);
    const SimulatedSession session = simulate_session(rng, setup, typical_X(setup), 5, test::sim_noise());
    const Calibration c = solve(session.samples);
    SuggestOptions options;
    options.max_step_translation = 0.3;
    const std::vector<Eigen::Isometry3d> candidates = sample_candidates(session.samples, c, options);
    ASSERT_EQ(static_cast<int>(candidates.size()), options.candidates) << to_string(setup);
    const Eigen::Isometry3d pattern = pattern_pose(session.samples, c.T_parent_camera);
    const Eigen::Isometry3d& current = session.samples.samples.back().T_base_effector;
    for (const Eigen::Isometry3d& E : candidates) {
      EXPECT_LE((E.translation() - current.translation()).norm(), 0.3 + 1e-12);
      EXPECT_LE(Eigen::AngleAxisd(E.linear() * current.linear().transpose()).angle(), options.max_step_rotation + 1e-12);
      // The camera sees the pattern from within the view limits.
      const Eigen::Isometry3d P = c.T_parent_camera.inverse() * (setup == Setup::EyeInHand ? E.inverse() : E) * pattern;
      EXPECT_GE(P.translation().norm(), options.views.min_distance - 0.08);
      EXPECT_LE(P.translation().norm(), options.views.max_distance + 0.08);
      EXPECT_TRUE(session.samples.rig.effector_for_view(c.T_parent_camera, pattern, P).isApprox(E, 1e-9));
    }
    // Deterministic for a seed.
    EXPECT_TRUE(sample_candidates(session.samples, c, options).front().isApprox(candidates.front()));
  }
}

TEST(NextBestPose, RankingPredictsWhatAddingThePoseGives) {
  Rng rng(5);
  const SimulatedSession session = simulate_session(rng, Setup::EyeInHand, typical_X(Setup::EyeInHand), 6, test::sim_noise());
  const Calibration c = solve(session.samples);
  SuggestOptions options;
  options.candidates = 40;
  const Suggestion s = rank_candidates(session.samples, c, sample_candidates(session.samples, c, options), options);
  ASSERT_EQ(s.considered, 40);
  ASSERT_EQ(static_cast<int>(s.ranked.size()) + s.refused, 40);
  for (std::size_t i = 1; i < s.ranked.size(); ++i) EXPECT_LE(s.ranked[i - 1].score, s.ranked[i].score);
  const ScoredPose& best = s.ranked.front();
  const ScoredPose& worst = s.ranked.back();
  EXPECT_LT(best.object_sigma, s.current_object_sigma);
  EXPECT_LT(best.object_sigma, 0.9 * worst.object_sigma) << "the candidates should differ in value";
  // Adding the best pose's noise-free sample and solving gives its prediction.
  SampleSet more = session.samples;
  PoseSample added;
  added.T_base_effector = best.T_base_effector;
  added.T_camera_pattern = best.T_camera_pattern;
  more.samples.push_back(added);
  const Calibration after = solve(more);
  EXPECT_TRUE(after.pose_covariance.isApprox(best.predicted_covariance, 1e-6));
  EXPECT_THROW(rank_candidates(session.samples, c, {}, options), HandEyeError);
}

// A target is reached on an estimated noise only from kTargetMinimumSamplesEstimatedNoise
// samples (its Monte-Carlo, the arm stopping where it reaches one: test_motion); a stated
// noise reaches it at any count; a plan plans at least the samples still needed.
TEST(NextBestPose, AnEstimatedNoiseReachesATargetOnlyFromEnoughSamples) {
  Rng rng(7);
  const SimulatedSession session = simulate_session(rng, Setup::EyeInHand, typical_X(Setup::EyeInHand), 4, test::sim_noise());
  ASSERT_TRUE(session.samples.noise);
  SampleSet unstated = session.samples;
  unstated.noise.reset();
  const Calibration stated = solve(session.samples), estimated = solve(unstated);
  ASSERT_EQ(stated.noise_origin, NoiseOrigin::Given);
  ASSERT_EQ(estimated.noise_origin, NoiseOrigin::EstimatedFromResiduals);
  const double far = 1.0;  // m: any sigma is within it
  EXPECT_TRUE(target_progress(stated, far, 0.7).reached);
  EXPECT_EQ(samples_short_of_target(stated, 4), 0);
  const TargetProgress short_of = target_progress(estimated, far, 0.7);
  EXPECT_FALSE(short_of.reached);
  EXPECT_NE(short_of.why_not.find("residuals of 4 samples"), std::string::npos) << short_of.why_not;
  EXPECT_EQ(samples_short_of_target(estimated, 4), kTargetMinimumSamplesEstimatedNoise - 4);
  EXPECT_EQ(samples_short_of_target(estimated, kTargetMinimumSamplesEstimatedNoise), 0);
  const TargetProgress beyond = target_progress(estimated, 1e-9, 0.7);  // not within: no reason but the sigma
  EXPECT_FALSE(beyond.reached);
  EXPECT_TRUE(beyond.why_not.empty());
  EXPECT_GT(beyond.object_sigma, 1e-9);
  SuggestOptions options;
  options.candidates = 30;
  EXPECT_EQ(plan_poses(session.samples, stated, far, 10, options).poses.size(), 0u);
  const Plan plan = plan_poses(unstated, estimated, far, 10, options);
  EXPECT_TRUE(plan.reached);
  EXPECT_EQ(static_cast<int>(plan.poses.size()), kTargetMinimumSamplesEstimatedNoise - 4);
  EXPECT_EQ(plan.poses_for_the_noise, kTargetMinimumSamplesEstimatedNoise - 4);
  EXPECT_EQ(poses_for_the_noise_text(plan), "; at least 3, as the noise is estimated: a target counts from 7 samples");
  EXPECT_EQ(poses_for_the_noise_text(plan_poses(session.samples, stated, far, 10, options)), "");
  // A stated noise far too small: the joint estimator estimates its missing part, and the rule
  // holds, said as such (`solve` above is the paper's pairs: a samples count from its motions).
  SampleSet understated = session.samples;
  understated.noise->camera.translation *= 1e-4;
  understated.noise->camera.rotation *= 1e-4;
  const Calibration mended = solve_joint(understated);
  ASSERT_EQ(mended.noise_origin, NoiseOrigin::Given);
  const TargetProgress mended_progress = target_progress(mended, far, 0.7);
  EXPECT_FALSE(mended_progress.reached);
  EXPECT_NE(mended_progress.why_not.find("the stated noise is too small"), std::string::npos) << mended_progress.why_not;
  // The corners method clears the pose-level components: a stated pixel sigma with the
  // robot's noise estimated from the corners is held to the rule by its corner fit.
  Calibration corners = stated;
  corners.corner_fit = Calibration::CornerFit{};
  corners.corner_fit->pixel_sigma_estimated = false;
  EXPECT_TRUE(target_progress(corners, far, 0.7).reached);
  corners.corner_fit->robot_noise_estimated = true;
  const TargetProgress corners_progress = target_progress(corners, far, 0.7);
  EXPECT_FALSE(corners_progress.reached);
  EXPECT_NE(corners_progress.why_not.find("the robot's noise is estimated from the residuals of 4 samples"),
            std::string::npos) << corners_progress.why_not;
  EXPECT_NE(corners_progress.why_not.find("or state the robot's noise"), std::string::npos) << corners_progress.why_not;
  EXPECT_EQ(samples_short_of_target(corners, 4), kTargetMinimumSamplesEstimatedNoise - 4);
}

TEST(NextBestPose, APlansPredictedCovarianceIsHonestUnderMonteCarlo) {
  // Plan 6 poses from 3, then measure M noisy sessions at the 9 poses: the
  // covariance predicted before any of them was measured must match the errors.
  for (handeye::Setup setup : {Setup::EyeInHand, Setup::EyeToHand}) {
    const MeasurementNoise noise = test::sim_noise();
    Rng rng(6);
    const Eigen::Isometry3d X = typical_X(setup);
    const SimulatedSession start = simulate_session(rng, setup, X, 3, noise);
    SuggestOptions options;
    options.candidates = 60;
    const Plan plan = plan_poses(start.samples, solve(start.samples), 0.0, 6, options);
    ASSERT_EQ(plan.poses.size(), 6u);
    for (std::size_t i = 1; i < plan.poses.size(); ++i) EXPECT_LT(plan.poses[i].object_sigma, plan.poses[i - 1].object_sigma);
    const Matrix6d predicted = plan.poses.back().predicted_covariance;
    std::vector<Eigen::Isometry3d> E;
    for (const PoseSample& s : start.samples.samples) E.push_back(s.T_base_effector);
    for (const ScoredPose& p : plan.poses) E.push_back(p.T_base_effector);
    MonteCarloAccumulator planned, solved;
    for (int m = 0; m < 1000; ++m) {
      SampleSet session = start.samples;
      session.samples.clear();
      for (const Eigen::Isometry3d& e : E) {
        PoseSample s;
        s.T_base_effector = perturb(rng, e, noise.robot);
        s.T_camera_pattern = perturb(
            rng, X.inverse() * (setup == Setup::EyeInHand ? e.inverse() : e) * start.T_world_pattern, noise.camera);
        session.samples.push_back(s);
      }
      const Calibration c = solve(session);
      const Vector6d error = pose_error(c.T_parent_camera, X);
      planned.add(error, predicted);
      solved.add(error, c.pose_covariance);
  }
  const MonteCarloSummary p = planned.summary(), s = solved.summary();
  std::printf("%s plan: object sigma %.3f -> %.3f mm in 6 poses; NEES of the planned covariance R %.2f t %.2f 6-dof %.2f "
              "(each solve's: %.2f)\n", to_string(setup), plan.start_object_sigma * 1e3, plan.poses.back().object_sigma * 1e3,
              p.rotation.nees_mean, p.translation.nees_mean, p.pose.nees_mean, s.pose.nees_mean);
  EXPECT_NEAR(p.pose.nees_mean, 6.0, 0.4);
  EXPECT_NEAR(p.rotation.nees_mean, 3.0, 0.25);
  EXPECT_NEAR(p.translation.nees_mean, 3.0, 0.25);
  }
}

}  // namespace
}  // namespace handeye
