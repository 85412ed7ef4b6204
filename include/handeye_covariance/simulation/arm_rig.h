// The simulated arm's calibration rig, shared by the motion tests, the planner's
// benchmark and the simulated arm's nodes: urdf/sim_arm.urdf (UR5 kinematics)
// with a camera on its flange (eye-in-hand) and a board flat on the table in
// front of it.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "handeye_covariance/core/measurements.h"
#include "handeye_covariance/motion/view_planner.h"

namespace handeye {

struct ArmRig {
  motion::Arm arm;   // base_link -> tool0, the camera's housing attached to tool0
  Rig rig;           // eye_in_hand; frames base_link, tool0, camera, pattern; a 0.2 x 0.15 m face
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();  // T_tool0_camera: 5 cm off the flange, looking along its z
  Eigen::Isometry3d Y = Eigen::Isometry3d::Identity();  // T_base_pattern: face up at (0.45, 0.15, 0)
  Eigen::VectorXd ready;  // upright, the flange pointing down
  ViewpointOptions views; // 0.3-0.7 m from the board

  /// Reads the URDF (urdf/sim_arm.urdf of the package) from `urdf_path`.
  static ArmRig load(const std::string& urdf_path);

  /// A random view of the board's face (rig.T_pattern_face: the pattern frame's own for
  /// the default board, a target's printed face once set_target gave it one) and the
  /// effector pose that shows it.
  motion::ViewCandidate random_candidate(Rng& rng) const;
  /// A start: the joints of a random view with the board whole in the image
  /// (motion::view_problem, no camera model), reachable within the limits less
  /// the margin and free of contact; none after `attempts` views.
  std::optional<Eigen::VectorXd> random_start(Rng& rng, const motion::CollisionModel& collision,
                                              const motion::PlannerOptions& options, int attempts = 30) const;
  /// The sample the camera takes at joints q: the true poses perturbed by `noise`.
  PoseSample sample_at(Rng& rng, const Eigen::VectorXd& q, const MeasurementNoise& noise) const;
};

}  // namespace handeye
