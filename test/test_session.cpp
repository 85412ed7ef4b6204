// CalibrationSession without ROS: sampling, changes and their persistence, the
// noise model, and the computations the node runs on a worker (estimate, next
// pose, suggestions) on snapshots.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/simulation/monte_carlo.h"
#include "handeye_covariance/io/check_text.h"
#include "handeye_covariance/io/yaml_io.h"
#include "handeye_covariance/session/calibration_monitor.h"
#include "handeye_covariance/session/calibration_session.h"
#include "test_helpers.h"

namespace handeye {
namespace {

using Eigen::Isometry3d;

std::string temp(const std::string& name) {
  const std::string dir = ::testing::TempDir() + "/session_test";
  std::filesystem::create_directories(dir);
  return dir + "/" + name;
}

SessionSettings settings(const std::string& session_file = "") {
  SessionSettings s;
  s.rig = {Setup::EyeInHand, {"base_link", "tool0", "camera_optical_frame", "tag_0"}};
  s.sampler.still_window = 0.5;
  s.suggest.candidates = 40;
  // calibrate_checked's honesty check at its least (its figures are test_honesty's and
  // test_real_data's): the same code, a fifth of the simulated sessions, which under
  // the sanitizers (test/sanitize) was most of this program's two minutes.
  s.honesty.replicates = 20;
  s.honesty.replicate_splits = 20;
  s.session_file = session_file;
  return s;
}

/// Observations of a robot that holds each pose of a simulated session for 1 s
/// (20 Hz), with the noisy pattern poses; `covariance` is sent with each.
std::vector<Observation> observations(const SimulatedSession& s, const std::optional<PoseNoise>& covariance = {}) {
  std::vector<Observation> out;
  double t = 0.0;
  for (const PoseSample& sample : s.samples.samples) {
    for (int k = 0; k < 20; ++k, t += 0.05) {
      Observation o;
      o.stamp = t;
      o.T_base_effector = sample.T_base_effector;
      o.T_camera_pattern = sample.T_camera_pattern;
      o.pattern_noise = covariance;
      out.push_back(o);
    }
    t += 1.0;  // moving: no detections
  }
  return out;
}

SimulatedSession simulated(int n, unsigned seed = 4) {
  Rng rng(seed);
  return simulate_session(rng, Setup::EyeInHand, typical_X(Setup::EyeInHand), n, test::sim_noise());
}

TEST(Session, AutoSamplesPersistsEachChangeAndMovesTheGeneration) {
  const std::string file = temp("auto.yaml");
  std::filesystem::remove(file);
  CalibrationSession session(settings(file));
  const SimulatedSession sim = simulated(6);
  int accepted = 0;
  std::uint64_t generation = session.generation();
  for (const Observation& o : observations(sim)) {
    if (const auto event = session.observe(o)) {
      ASSERT_TRUE(event->success) << event->message;
      EXPECT_TRUE(event->changed);
      EXPECT_TRUE(event->persist_error.empty()) << event->persist_error;
      EXPECT_GT(session.generation(), generation);
      generation = session.generation();
      ++accepted;
      // Written before the change is reported: the file holds exactly these samples.
      EXPECT_EQ(io::read_samples(file).samples.size(), session.samples().size());
    }
  }
  EXPECT_EQ(accepted, 6);
  EXPECT_EQ(session.samples().size(), 6u);
  EXPECT_EQ(session.state(), SamplerState::WaitingForMotion);

  // A second session with the same file resumes where the first stopped.
  CalibrationSession resumed(settings(file));
  const SessionEvent event = resumed.resume();
  ASSERT_TRUE(event.success) << event.message;
  EXPECT_EQ(event.message, "resumed 6 samples");
  ASSERT_EQ(resumed.samples().size(), 6u);
  EXPECT_TRUE(resumed.samples()[5].T_camera_pattern.isApprox(session.samples()[5].T_camera_pattern, 1e-15));
}

// A check of a saved calibration collects its own views through the sampler's rules,
// leaves the samples and the generation alone, and runs when it has its views: the
// same rig's views fit, views after the camera moved 3 mm do not (X named).
TEST(Session, ChecksCollectTheirOwnViewsAndLeaveTheSamplesAlone) {
  CalibrationSession session(settings());
  const SimulatedSession sim = simulated(20);
  for (const Observation& o : observations(sim)) session.observe(o);
  ASSERT_EQ(session.samples().size(), 20u);
  const Calibration calibration = session.calibrate_checked(session.snapshot());
  ASSERT_TRUE(calibration.prediction);
  const std::uint64_t generation = session.generation();

  Calibration pairs = calibration;
  pairs.residual_noise.reset();
  EXPECT_FALSE(session.start_check(pairs).success);
  EXPECT_FALSE(session.check_state().collecting);

  for (const double moved_mm : {0.0, 3.0}) {
    ASSERT_TRUE(session.start_check(calibration, 5).success);
    Rng rng(8);
    Isometry3d X = typical_X(Setup::EyeInHand);
    X.translation() += X.linear() * Eigen::Vector3d(moved_mm * 1e-3, 0.0, 0.0);
    const SimulatedSession later = simulate_session(rng, Setup::EyeInHand, X, 5, test::sim_noise());
    int taken = 0;
    std::string last;
    for (const Observation& o : observations(later)) {
      if (const auto event = session.observe(o)) {
        EXPECT_FALSE(event->changed);  // the samples are not touched
        if (event->success) ++taken;
        last = event->message;
      }
    }
    EXPECT_EQ(taken, 5);
    EXPECT_EQ(session.samples().size(), 20u);
    EXPECT_EQ(session.generation(), generation);
    const CalibrationSession::CheckState state = session.check_state();
    EXPECT_FALSE(state.collecting);
    ASSERT_TRUE(state.result);
    EXPECT_EQ(state.result->views.size(), 5u);
    EXPECT_EQ(state.result->changed, moved_mm > 0.0) << io::check_verdict(*state.result);
    if (moved_mm > 0.0) {
      EXPECT_EQ(state.result->change.what, ChangedPose::X) << io::check_verdict(*state.result);
    }
    EXPECT_NE(last.find(io::check_verdict(*state.result)), std::string::npos) << last;
  }
  ASSERT_TRUE(session.start_check(calibration, 5).success);
  EXPECT_TRUE(session.check_state().collecting);
  EXPECT_TRUE(session.cancel_check().success);
  EXPECT_FALSE(session.check_state().collecting);
  EXPECT_FALSE(session.cancel_check().success);
}

// The monitor (session/calibration_monitor.h) on a stream of still views: 200 views of an
// unchanged rig give no ERROR; after the camera moves 3 mm on its mount, ERROR comes
// within 10 still views, naming X; the calibration it watches is never changed.
Calibration monitored_calibration() {
  CalibrationSession session(settings());
  const SimulatedSession sim = simulated(20);
  for (const Observation& o : observations(sim)) session.observe(o);
  return session.calibrate_checked(session.snapshot());
}

MonitorOptions monitor_options() {
  MonitorOptions options;
  options.sampler = settings().sampler;  // the session's stillness rule (0.5 s), as the monitor node takes the node's
  return options;
}

// Still views of an unchanged rig (camera at X): none may give ERROR.
void expect_no_error(CalibrationMonitor& monitor, const SimulatedSession& unchanged, int expected_views) {
  int views = 0, errors = 0, warnings = 0;
  for (const Observation& o : observations(unchanged)) {
    if (const auto verdict = monitor.observe(o)) {
      ++views;
      errors += verdict->level == MonitorLevel::Error;
      warnings += verdict->level == MonitorLevel::Warn;
      EXPECT_LE(verdict->views, 10);
    }
  }
  EXPECT_EQ(errors, 0) << "of " << views << " views";
  // WARN is p < 1%: over 200 checks Binomial(200, 0.01), mean 2, 99.5% point 6 (the windows
  // overlap, so the checks are not independent; the bound is a regression guard, not a test).
  EXPECT_LE(warnings, 6) << "of " << views << " views";
  EXPECT_EQ(views, expected_views);
  std::printf("[monitor] %d views of an unchanged rig: %d WARN, %d ERROR\n", views, warnings, errors);
}

TEST(Monitor, NoErrorOver200StillViewsOfAnUnchangedRig) {
  const Calibration calibration = monitored_calibration();
  CalibrationMonitor monitor(calibration, settings().rig, std::nullopt, monitor_options());
  EXPECT_EQ(monitor.latest().level, MonitorLevel::Waiting);
  Rng rng(21);
  expect_no_error(monitor, simulate_session(rng, Setup::EyeInHand, typical_X(Setup::EyeInHand), 200, test::sim_noise()), 200);
}

TEST(Monitor, ErrorWithin10StillViewsAfterTheCameraMoves3mm) {
  const Calibration calibration = monitored_calibration();
  CalibrationMonitor monitor(calibration, settings().rig, std::nullopt, monitor_options());
  EXPECT_EQ(monitor.latest().level, MonitorLevel::Waiting);
  Rng rng(21);
  Isometry3d X = typical_X(Setup::EyeInHand);
  expect_no_error(monitor, simulate_session(rng, Setup::EyeInHand, X, 20, test::sim_noise()), 20);
  EXPECT_EQ(monitor.latest().level, MonitorLevel::Ok) << monitor.latest().message;
  X.translation() += X.linear() * Eigen::Vector3d(3e-3, 0.0, 0.0);
  const SimulatedSession after = simulate_session(rng, Setup::EyeInHand, X, 10, test::sim_noise());
  int until_error = 0;
  for (const Observation& o : observations(after)) {
    if (const auto verdict = monitor.observe(o)) {
      ++until_error;
      if (verdict->level == MonitorLevel::Error) break;
    }
  }
  ASSERT_EQ(monitor.latest().level, MonitorLevel::Error) << monitor.latest().message;
  EXPECT_LE(until_error, 10);
  EXPECT_EQ(monitor.latest().check->change.what, ChangedPose::X) << monitor.latest().message;
  std::printf("[monitor] the camera moved 3 mm: ERROR after %d still views: %s\n", until_error,
              monitor.latest().message.c_str());
}

TEST(Session, ChangesSayWhatHappenedAndRefuseBadRequests) {
  CalibrationSession session(settings());
  const SimulatedSession sim = simulated(5);
  ASSERT_TRUE(session.replace(sim.samples.samples, "five").changed);
  const std::uint64_t g = session.generation();

  SessionEvent bad = session.remove(7);
  EXPECT_FALSE(bad.success);
  EXPECT_FALSE(bad.changed);
  EXPECT_NE(bad.message.find("valid indices are 0..4"), std::string::npos) << bad.message;
  EXPECT_FALSE(session.remove(-1).success);
  EXPECT_EQ(session.generation(), g);
  EXPECT_TRUE(session.remove(0).changed);
  EXPECT_EQ(session.samples().size(), 4u);

  const std::string saved = temp("saved.yaml");
  ASSERT_TRUE(session.save(saved).success);
  SessionSettings to_hand = settings();
  to_hand.rig.setup = Setup::EyeToHand;
  CalibrationSession other(to_hand);
  const SessionEvent wrong_setup = other.load(saved);
  EXPECT_FALSE(wrong_setup.success);
  EXPECT_NE(wrong_setup.message.find("eye_in_hand"), std::string::npos) << wrong_setup.message;
  const SessionEvent missing = session.load(temp("does_not_exist.yaml"));
  EXPECT_FALSE(missing.success);
  EXPECT_NE(missing.message.find("IoError"), std::string::npos) << missing.message;
  EXPECT_EQ(session.samples().size(), 4u) << "a failed load keeps the samples";

  EXPECT_TRUE(session.reset().changed);
  EXPECT_TRUE(session.samples().empty());
  EXPECT_NE(session.take_sample(0.0).message.find("no stamp-matched observation"), std::string::npos);
  ASSERT_TRUE(session.load(saved).success);
  EXPECT_EQ(session.samples().size(), 4u);

  // An unwritable session file is reported with the change, which still happens.
  CalibrationSession unwritable(settings("/proc/handeye_not_writable/samples.yaml"));
  const SessionEvent e = unwritable.replace(sim.samples.samples, "five");
  EXPECT_TRUE(e.changed);
  EXPECT_NE(e.persist_error.find("IoError"), std::string::npos) << e.persist_error;
}

TEST(Session, OneNoiseModel) {
  const SimulatedSession sim = simulated(6);
  PoseNoise detector;
  detector.rotation = 4e-6 * Eigen::Matrix3d::Identity();
  detector.translation = 1e-7 * Eigen::Matrix3d::Identity();
  detector.translation_rotation(2, 0) = 2e-7;  // the cross block travels too

  // Configured noise: the global block; a detector's sample keeps its covariance
  // and gets the configured robot noise.
  SessionSettings configured = settings();
  configured.noise = paper_noise(1e-5);
  CalibrationSession with_config(configured);
  for (const Observation& o : observations(sim, detector)) with_config.observe(o);
  SampleSet set = with_config.sample_set();
  ASSERT_EQ(set.samples.size(), 6u);
  EXPECT_EQ(set.noise->camera.rotation, configured.noise->camera.rotation);
  ASSERT_TRUE(set.samples[2].noise);
  EXPECT_EQ(set.samples[2].noise->camera.as_pose_covariance(), detector.as_pose_covariance());
  EXPECT_EQ(set.samples[2].noise->robot.rotation, configured.noise->robot.rotation);

  // None configured: the robot is exact, and the detector's mean covers samples without one.
  CalibrationSession detector_only(settings());
  for (const Observation& o : observations(sim, detector)) detector_only.observe(o);
  std::vector<PoseSample> mixed = detector_only.samples();
  mixed[0].noise.reset();
  detector_only.replace(mixed, "mixed");
  set = detector_only.sample_set();
  ASSERT_TRUE(set.noise);
  EXPECT_TRUE(set.noise->camera.as_pose_covariance().isApprox(detector.as_pose_covariance(), 1e-12));
  EXPECT_TRUE(set.samples[1].noise->robot.as_pose_covariance().isZero(0.0));
  EXPECT_NO_THROW(detector_only.calibrate(detector_only.snapshot()));

  // Neither: no noise block, so the estimator estimates it.
  CalibrationSession bare(settings());
  bare.replace(simulated(6).samples.samples, "plain");
  std::vector<PoseSample> plain = bare.samples();
  for (PoseSample& s : plain) s.noise.reset();
  bare.replace(plain, "plain");
  EXPECT_FALSE(bare.sample_set().noise);
  EXPECT_EQ(bare.calibrate(bare.snapshot()).noise_origin, NoiseOrigin::EstimatedFromResiduals);
}

TEST(Session, AnalysisOfASnapshotNamesTheEstimateAndTheNextPose) {
  SessionSettings s = settings();
  s.noise = test::sim_noise();
  CalibrationSession session(s);
  const SimulatedSession sim = simulated(8);
  session.replace({sim.samples.samples.begin(), sim.samples.samples.begin() + 2}, "two");
  Analysis a = session.analyse(session.snapshot());
  EXPECT_FALSE(a.estimate);
  EXPECT_TRUE(a.problem.empty()) << "fewer than 3 samples is not a problem, only too early";

  session.replace(sim.samples.samples, "eight");
  const SessionSnapshot snapshot = session.snapshot();
  session.remove(0);  // the session moves on; the snapshot does not
  a = session.analyse(snapshot);
  EXPECT_EQ(a.generation, snapshot.generation);
  EXPECT_NE(a.generation, session.generation());
  EXPECT_EQ(a.samples, 8u);
  ASSERT_TRUE(a.estimate) << a.problem;
  ASSERT_TRUE(a.next_pose) << a.problem;
  const PoseWithCovariance X{a.estimate->T_parent_camera, a.estimate->pose_covariance};
  EXPECT_LT(a.next_pose->object_sigma, object_sigma(X, s.suggest.working_distance));
  const Vector6d error = pose_error(a.estimate->T_parent_camera, sim.X);
  EXPECT_LT(error.dot(a.estimate->pose_covariance.ldlt().solve(error)), 22.5);  // chi2(6) 0.999

  // A degenerate session: a problem, not an exception.
  std::vector<PoseSample> same(3, sim.samples.samples[0]);
  session.replace(same, "degenerate");
  a = session.analyse(session.snapshot());
  EXPECT_FALSE(a.estimate);
  EXPECT_NE(a.problem.find("no estimate yet"), std::string::npos) << a.problem;
}

TEST(Session, OutlierRejectionFollowsTheSetting) {
  SessionSettings s = settings();
  s.noise = test::sim_noise();
  SimulatedSession sim = simulated(12, 9);
  sim.samples.samples[3].T_camera_pattern = sim.samples.samples[0].T_camera_pattern;  // a wrong detection
  CalibrationSession rejecting(s);
  rejecting.replace(sim.samples.samples, "with an outlier");
  const Calibration c = rejecting.calibrate(rejecting.snapshot());
  ASSERT_EQ(c.rejected.size(), 1u);
  EXPECT_EQ(c.rejected[0].index, 3);
  s.reject_outliers = false;
  CalibrationSession keeping(s);
  keeping.replace(sim.samples.samples, "with an outlier");
  try {
    const Calibration kept = keeping.calibrate(keeping.snapshot());
    EXPECT_TRUE(kept.rejected.empty());
  } catch (const HandEyeError& e) {
    EXPECT_EQ(e.code(), ErrorCode::AngleMismatch) << e.what();
  }
}

TEST(Session, SuggestionsUseOneSeedPolicyAndTheConfiguredPlan) {
  SessionSettings s = settings();
  s.noise = test::sim_noise();
  s.max_plan_poses = 4;
  CalibrationSession session(s);
  const SimulatedSession sim = simulated(5);
  session.replace({sim.samples.samples.begin(), sim.samples.samples.begin() + 2}, "two");
  try {
    session.suggest(session.snapshot(), {});
    FAIL() << "suggested from 2 samples";
  } catch (const HandEyeError& e) {
    EXPECT_NE(std::string(e.what()).find("no estimate yet"), std::string::npos) << e.what();
  }
  session.replace(sim.samples.samples, "five");
  SuggestRequest request;
  request.count = 3;
  request.target_object_sigma = 1e-6;  // out of reach: the plan stops at max_plan_poses
  const SuggestResult r = session.suggest(session.snapshot(), request);
  EXPECT_EQ(r.count, 3);
  EXPECT_EQ(r.options.seed, s.suggest.seed + 5u);
  EXPECT_EQ(r.options.min_translation, s.sampler.min_translation);
  EXPECT_FALSE(r.plan.reached);
  EXPECT_EQ(r.plan.poses.size(), 4u);
  ASSERT_FALSE(r.suggestion.ranked.empty());
  EXPECT_LE(r.suggestion.ranked.front().score, r.suggestion.ranked.back().score);
  // The same snapshot gives the same suggestion; a new sample brings new candidates.
  EXPECT_TRUE(session.suggest(session.snapshot(), request).suggestion.ranked.front().T_base_effector.isApprox(
      r.suggestion.ranked.front().T_base_effector));
  request.criterion = "trace";
  EXPECT_THROW(session.suggest(session.snapshot(), request), HandEyeError);
}

TEST(Session, SettingsFromAConfigReadTheFilesAndRefuseTypos) {
  SessionConfig config;
  config.suggest_criterion = "determinant";
  config.target_tolerance_mm = 0.5;
  config.reach_translation = 0.3;
  SessionSettings s = session_settings(config);
  EXPECT_EQ(s.suggest.criterion, SuggestCriterion::Determinant);
  EXPECT_DOUBLE_EQ(s.target_object_sigma, 0.5e-3);
  EXPECT_DOUBLE_EQ(s.suggest.max_step_translation, 0.3);
  EXPECT_FALSE(s.noise);

  const std::string noise_file = temp("noise.yaml");
  SampleSet with_noise = simulated(3).samples;
  io::write_file_atomically(noise_file, io::format_samples(with_noise));
  config.noise_config = noise_file;
  s = session_settings(config);
  ASSERT_TRUE(s.noise);
  EXPECT_EQ(s.noise->camera.rotation, test::sim_noise().camera.rotation);

  config.suggest_criterion = "trace";
  try {
    session_settings(config);
    FAIL() << "accepted criterion `trace`";
  } catch (const HandEyeError& e) {
    EXPECT_NE(std::string(e.what()).find("unknown criterion"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace handeye
