#include "handeye_covariance/simulation/arm_rig.h"

#include <fstream>
#include <sstream>

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/simulation/simulation.h"

namespace handeye {

ArmRig ArmRig::load(const std::string& urdf_path) {
  std::ifstream in(urdf_path);
  if (!in)
    throw HandEyeError(ErrorCode::IoError, "cannot read the simulated arm's URDF", urdf_path,
                       "give the path of urdf/sim_arm.urdf in the package");
  std::stringstream text;
  text << in.rdbuf();
  ArmRig r{motion::Arm::from_urdf(text.str(), "base_link", "tool0", urdf_path), Rig{}, Eigen::Isometry3d::Identity(),
           Eigen::Isometry3d::Identity(), Eigen::VectorXd(), ViewpointOptions{}};
  r.rig.setup = Setup::EyeInHand;
  r.rig.frames = {"base_link", "tool0", "camera", "pattern"};
  r.rig.face_size = Eigen::Vector2d(0.2, 0.15);
  r.X.translation() = Eigen::Vector3d(0.0, 0.05, 0.04);
  r.Y.translation() = Eigen::Vector3d(0.45, 0.15, 0.0);
  r.ready.resize(6);
  r.ready << 0.0, -M_PI / 2, M_PI / 2, -M_PI / 2, -M_PI / 2, 0.0;
  r.views.min_distance = 0.3, r.views.max_distance = 0.7;
  motion::Shape housing;  // 8 x 6 x 5 cm, behind the lens
  housing.kind = motion::Shape::Kind::Box;
  housing.size = Eigen::Vector3d(0.08, 0.06, 0.05);
  housing.T_link_shape = r.X;
  housing.T_link_shape.translation().z() -= 0.02;
  r.arm.attach("tool0", housing);
  return r;
}

motion::ViewCandidate ArmRig::random_candidate(Rng& rng) const {
  // random_view looks at a frame whose z faces the camera: the target's face (T_camera_face).
  const Eigen::Isometry3d view = random_view(rng, views) * rig.T_pattern_face.inverse();
  return {rig.effector_for_view(X, Y, view), view};
}

std::optional<Eigen::VectorXd> ArmRig::random_start(Rng& rng, const motion::CollisionModel& collision,
                                                    const motion::PlannerOptions& options, int attempts) const {
  for (int a = 0; a < attempts; ++a) {
    const motion::ViewCandidate c = random_candidate(rng);
    if (motion::view_problem(rig, std::nullopt, c.T_camera_pattern, options)) continue;  // the camera must see the board
    for (const Eigen::VectorXd& q : arm.inverse(c.T_base_effector, ready, 4, rng))
      if (!motion::limit_problem(arm, q, options.joint_margin) && !collision.contact(q)) return q;
  }
  return std::nullopt;
}

PoseSample ArmRig::sample_at(Rng& rng, const Eigen::VectorXd& q, const MeasurementNoise& noise) const {
  const Eigen::Isometry3d E = arm.forward(q);
  PoseSample s;
  s.T_base_effector = perturb(rng, E, noise.robot);
  s.T_camera_pattern = perturb(rng, rig.predicted_view(E, X, Y), noise.camera);
  return s;
}

}  // namespace handeye
