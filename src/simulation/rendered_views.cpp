#include "handeye_covariance/simulation/rendered_views.h"

#include "handeye_covariance/images/pooled_detector.h"

namespace handeye {

SampleSet rendered_views(Rng& rng, const Rig& rig, const std::vector<Eigen::Isometry3d>& effectors,
                         const Eigen::Isometry3d& X, const Eigen::Isometry3d& Y, const PatternRenderer& renderer,
                         const Target& target, const PoseNoise& robot_noise) {
  SampleSet set;
  set.rig = rig;
  set.rig.T_pattern_face = target_face(target);
  // The rig's pattern frame is the face's; the target's own frame is T_face_pattern from it.
  const Eigen::Isometry3d T_face_pattern = set.rig.T_pattern_face.inverse();
  images::PooledDetector detector(target);
  for (const Eigen::Isometry3d& E : effectors) {
    detector.add(renderer.render(rig.predicted_view(E, X, Y) * T_face_pattern, rng), renderer.camera());
  }
  MeasurementNoise robot;
  robot.robot = robot_noise;
  for (std::size_t i = 0; i < effectors.size(); ++i) {
    const std::optional<PatternPose> pose = detector.pooled(i);
    if (!pose) continue;
    PoseSample sample;
    sample.T_base_effector = perturb(rng, effectors[i], robot_noise);
    sample.T_camera_pattern = pose->T_camera_pattern;
    sample.noise = MeasurementNoise{PoseNoise{}, PoseNoise::from_pose_covariance(pose->covariance)};
    set.samples.push_back(sample);
  }
  return with_default_noise(std::move(set));  // as the session solves it
}

}  // namespace handeye
