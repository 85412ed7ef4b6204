#include <gtest/gtest.h>

#include "handeye_covariance/session/sampler.h"
#include "test_helpers.h"

namespace handeye {
namespace {

using Eigen::Isometry3d;
using Eigen::Vector3d;

Observation at(double stamp, const Isometry3d& E, const Isometry3d& P = Isometry3d::Identity()) {
  Observation o;
  o.stamp = stamp;
  o.T_base_effector = E;
  o.T_camera_pattern = P;
  return o;
}

Isometry3d pose(double x, double angle = 0.0) {
  return se3::make_pose(so3::exp(Vector3d(0, 0, angle)), Vector3d(x, 0, 0.5));
}

SamplerOptions options() {
  SamplerOptions o;
  o.still_window = 1.0;
  o.max_gap = 0.2;
  return o;
}

/// Feeds observations of `E` at 20 Hz over [t0, t1); returns the outcomes.
std::vector<SampleOutcome> hold(Sampler& s, const Isometry3d& E, double t0, double t1) {
  std::vector<SampleOutcome> outcomes;
  for (double t = t0; t < t1 - 1e-9; t += 0.05) {
    if (auto o = s.observe(at(t, E))) outcomes.push_back(*o);
  }
  return outcomes;
}

TEST(Sampler, TakesOneSampleAfterTheStillWindowAndThenWaitsForMotion) {
  Sampler s(options());
  EXPECT_EQ(s.state(), SamplerState::WaitingForData);
  EXPECT_TRUE(hold(s, pose(0.0), 0.0, 0.9).empty());  // not still for a full second yet
  const auto outcomes = hold(s, pose(0.0), 0.9, 3.0);
  ASSERT_EQ(outcomes.size(), 1u);
  EXPECT_TRUE(outcomes[0].accepted);
  EXPECT_EQ(s.samples().size(), 1u);
  EXPECT_EQ(s.state(), SamplerState::WaitingForMotion);
  // Move 5 cm and stay: a second sample.
  const auto second = hold(s, pose(0.05), 3.0, 5.0);
  ASSERT_EQ(second.size(), 1u);
  EXPECT_TRUE(second[0].accepted);
  EXPECT_EQ(s.samples().size(), 2u);
  EXPECT_NEAR(*s.samples()[1].stamp, 4.0, 0.06);  // the observation that completed the window
}

TEST(Sampler, MovingRobotOrPatternIsNeverSampled) {
  Sampler s(options());
  for (double t = 0; t < 5; t += 0.05) EXPECT_FALSE(s.observe(at(t, pose(0.01 * t))));  // 1 cm/s
  Sampler p(options());
  for (double t = 0; t < 5; t += 0.05) {
    EXPECT_FALSE(p.observe(at(t, pose(0), se3::make_pose(so3::exp(Vector3d(0.05 * t, 0, 0)), Vector3d::Zero()))));
  }
  EXPECT_TRUE(s.samples().empty());
  EXPECT_TRUE(p.samples().empty());
}

TEST(Sampler, RefusesANearDuplicateWithAReason) {
  Sampler s(options());
  hold(s, pose(0.0), 0.0, 2.0);
  hold(s, pose(0.2), 2.0, 2.5);                          // move away ...
  const auto again = hold(s, pose(0.002, 0.01), 2.5, 5.0);  // ... and back to 2 mm, 0.6 deg from sample 0
  ASSERT_EQ(again.size(), 1u);
  EXPECT_FALSE(again[0].accepted);
  EXPECT_NE(again[0].message.find("too close to sample 0"), std::string::npos) << again[0].message;
  EXPECT_EQ(s.samples().size(), 1u);
  // A pure rotation of 5 degrees is a new sample.
  hold(s, pose(0.2), 5.0, 5.5);
  const auto rotated = hold(s, pose(0.0, 5 * M_PI / 180), 5.5, 8.0);
  ASSERT_EQ(rotated.size(), 1u);
  EXPECT_TRUE(rotated[0].accepted);
}

TEST(Sampler, GapsBreakStillnessAndTimeGoingBackwardsClearsHistory) {
  Sampler s(options());
  s.observe(at(0.0, pose(0)));
  EXPECT_FALSE(s.observe(at(1.5, pose(0))));  // a 1.5 s hole: motion unknown
  Sampler loop(options());
  hold(loop, pose(0), 10.0, 10.8);
  // The bag loops: stamps restart. Old history must not complete a window.
  EXPECT_TRUE(hold(loop, pose(0), 0.0, 0.9).empty());
  EXPECT_EQ(hold(loop, pose(0), 0.9, 1.5).size(), 1u);
}

TEST(Sampler, ManualSamplingNeedsRecentStillData) {
  SamplerOptions o = options();
  o.auto_sample = false;
  Sampler s(o);
  EXPECT_NE(s.take_sample(0.0).message.find("no stamp-matched observation"), std::string::npos);
  hold(s, pose(0), 0.0, 0.5);
  EXPECT_NE(s.take_sample(0.5).message.find("moved within"), std::string::npos);
  hold(s, pose(0), 0.5, 2.0);
  EXPECT_NE(s.take_sample(10.0).message.find("s old"), std::string::npos);
  const SampleOutcome taken = s.take_sample(2.0);
  EXPECT_TRUE(taken.accepted) << taken.message;
  EXPECT_FALSE(s.take_sample(2.0).accepted);  // the same pose again: too close
  EXPECT_FALSE(s.remove(1));
  EXPECT_TRUE(s.remove(0));
  EXPECT_TRUE(s.samples().empty());
}

TEST(Sampler, ASampleWithTheDetectorsCovarianceGetsTheRobotNoise) {
  PoseNoise robot;
  robot.translation = 2.5e-9 * Eigen::Matrix3d::Identity();
  Sampler s(options(), robot);
  PoseNoise detector;
  detector.translation = 1e-7 * Eigen::Matrix3d::Identity();
  detector.translation_rotation(2, 0) = 1e-9;
  for (double t = 0; t < 1.5; t += 0.05) {
    Observation o = at(t, pose(0.0));
    o.pattern_noise = detector;
    s.observe(o);
  }
  hold(s, pose(0.1), 1.5, 3.0);  // no detector covariance: no per-sample noise
  ASSERT_EQ(s.samples().size(), 2u);
  ASSERT_TRUE(s.samples()[0].noise);
  EXPECT_EQ(s.samples()[0].noise->camera.as_pose_covariance(), detector.as_pose_covariance());
  EXPECT_EQ(s.samples()[0].noise->robot.translation, robot.translation);
  EXPECT_FALSE(s.samples()[1].noise);
}

}  // namespace
}  // namespace handeye
