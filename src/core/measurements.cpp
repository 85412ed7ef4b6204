#include "handeye_covariance/core/measurements.h"

#include "handeye_covariance/core/lie.h"

namespace handeye {

SampleSet with_default_noise(SampleSet samples) {
  if (samples.noise) return samples;
  Matrix6d mean_camera = Matrix6d::Zero();
  int with_noise = 0;
  for (const PoseSample& sample : samples.samples) {
    if (!sample.noise) continue;
    mean_camera += sample.noise->camera.as_pose_covariance();
    ++with_noise;
  }
  if (with_noise > 0) {
    MeasurementNoise fallback;
    fallback.camera = PoseNoise::from_pose_covariance(mean_camera / with_noise);
    samples.noise = fallback;
  }
  return samples;
}

MotionPair motion_between(const Rig& rig, const PoseSample& from, const PoseSample& to) {
  MotionPair motion;
  motion.A = rig.robot_motion(from.T_base_effector, to.T_base_effector);
  motion.B = to.T_camera_pattern * from.T_camera_pattern.inverse();
  return motion;
}

Eigen::Isometry3d pattern_pose(const SampleSet& samples, const Eigen::Isometry3d& X) {
  std::vector<Eigen::Isometry3d> Y;
  Y.reserve(samples.samples.size());
  for (const PoseSample& s : samples.samples) Y.push_back(samples.rig.pattern_pose(s.T_base_effector, X, s.T_camera_pattern));
  return mean_pose(Y);
}

}  // namespace handeye
