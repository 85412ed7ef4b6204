// Synthetic calibration data with known truth, seeded and deterministic.
// Used by the tests, the benchmarks, the shipped demo file and `handeye validate`.
#pragma once

#include "handeye_covariance/core/measurements.h"
#include "handeye_covariance/core/viewpoints.h"

namespace handeye {

/// Zero-mean Gaussian 3-vector with the given covariance (PSD; zero allowed).
Eigen::Vector3d sample_gaussian(Rng& rng, const Eigen::Matrix3d& covariance);

/// Rotation uniform on SO(3) (Shoemake), translation uniform in [-extent, extent]^3.
Eigen::Isometry3d random_pose(Rng& rng, double translation_extent);

/// The noise model of the paper (eq. 3-6): R = exp([xi_R]) R_bar, t = t_bar + xi_t, with
/// (xi_t, xi_R) drawn from the full 6x6 (cross block included).
Eigen::Isometry3d perturb(Rng& rng, const Eigen::Isometry3d& pose, const PoseNoise& noise);
/// The same with the paper's decoupled blocks (no cross block).
inline Eigen::Isometry3d perturb(Rng& rng, const Eigen::Isometry3d& pose, const DecoupledCovariance& noise) {
  return perturb(rng, pose, PoseNoise{noise.rotation, noise.translation});
}

/// The paper's synthetic study (section IV-A), eq. (57-60), scaled by lambda.
MeasurementNoise paper_noise(double lambda);

/// k independent pairs: A_bar random (uniform rotation, translation in
/// [-extent, extent]^3), B_bar = X^-1 A_bar X, each corrupted by `noise`.
/// The returned set carries `noise` as its noise block.
MotionSet simulate_motions(Rng& rng, const Eigen::Isometry3d& X, int k, const MeasurementNoise& noise,
                           double translation_extent = 0.5);

struct SimulatedSession {
  SampleSet samples;                  // noisy, with the noise block set
  Eigen::Isometry3d X;                // truth: T_effector_camera or T_base_camera
  Eigen::Isometry3d T_world_pattern;  // truth: T_base_pattern (in hand) or T_effector_pattern (to hand)
};

/// n absolute samples of a session with truth X. eye_in_hand: the pattern is
/// fixed in the base frame; eye_to_hand: it is fixed on the flange.
SimulatedSession simulate_session(Rng& rng, Setup setup, const Eigen::Isometry3d& X, int n,
                                  const MeasurementNoise& noise, const ViewpointOptions& views = {});

/// A robot error shared by nearby poses (estimation/shared_robot_error.h), added to
/// the recorded robot poses of `samples`: per axis one draw of a Gaussian process
/// over the effector positions, exp(-d^2 / (2 l^2)), l the median distance between
/// two poses, `translation_sigma` (m) and `rotation_sigma` (rad) per axis in the
/// base frame (R = exp(w) R, t + dt), as a real arm's kinematic error is a smooth
/// function of where it is.
void add_shared_robot_error(Rng& rng, SampleSet& samples, double translation_sigma, double rotation_sigma);

/// A robot that holds each pose for `pause` seconds, then moves smoothly to the
/// next in `move` seconds (slerp + lerp with a smoothstep), and stays at the
/// last pose. Shared by the simulated rig node and the simulated bags.
struct RigTrajectory {
  Rig rig;                            // setup and frame names
  Eigen::Isometry3d X;                // truth
  Eigen::Isometry3d T_world_pattern;  // see SimulatedSession
  std::vector<Eigen::Isometry3d> poses;  // T_base_effector at each pause
  double pause = 2.0, move = 1.0;     // s

  /// T_base_effector at t seconds from the start.
  Eigen::Isometry3d effector_at(double t) const;
  /// The true T_camera_pattern at t.
  Eigen::Isometry3d pattern_at(double t) const;
  /// The views were drawn looking at the pattern frame; make them look at a
  /// target's printed face instead (core/target.h, target_face): the pattern
  /// frame moves to T_pattern_face^-1 from where the views look (a board's own
  /// frame is at a corner, z into the board).
  void look_at_face(const Eigen::Isometry3d& T_pattern_face) { T_world_pattern = T_world_pattern * T_pattern_face.inverse(); }
  /// Time until the robot reaches its last pose, plus one pause.
  double duration() const { return static_cast<double>(poses.size()) * (pause + move) - move; }
};

/// n poses from random viewpoints (as simulate_session) around a truth X.
RigTrajectory make_rig_trajectory(Rng& rng, Setup setup, const Eigen::Isometry3d& X, int n, double pause, double move,
                                  const ViewpointOptions& views = {});

/// A plausible X for demos and tests: a camera 10 cm off the flange (eye-in-hand),
/// or 1.2 m from the base looking at the workspace (eye-to-hand).
Eigen::Isometry3d typical_X(Setup setup);

}  // namespace handeye
