// Simulated sessions with the errors real sessions have and the Gaussian model
// has not: a robot whose kinematics are off (a 6-axis arm with perturbed DH
// parameters: it reports the nominal forward kinematics of its joint angles
// while the flange is where the true kinematics put it), a camera whose focal
// length is off (the detector's depth is scaled), and heavy-tailed detections
// (Student-t, or a share of poses with several times the noise).
//
// With systematic errors there are two X to judge an estimate against: the
// true one, and the pseudo-true one, the limit of the estimator on endless data
// of the same kind (part of a kinematic error after the last joint is a fixed
// flange offset, which X absorbs for good: it then predicts the camera
// correctly from the nominal kinematics). pseudo_true_X computes the latter.
#pragma once

#include <array>

#include "handeye_covariance/simulation/simulation.h"

namespace handeye {

/// Standard Denavit-Hartenberg parameters of one joint: Rz(theta + offset) Tz(d) Tx(a) Rx(alpha).
struct DhJoint {
  double a = 0.0, d = 0.0, alpha = 0.0, offset = 0.0;
};

class SerialArm {
 public:
  explicit SerialArm(const std::array<DhJoint, 6>& joints);

  /// A UR10 (Universal Robots' published DH parameters): 1.3 m reach.
  static SerialArm ur10();

  /// T_base_flange at joint angles q.
  Eigen::Isometry3d forward(const Vector6d& q) const;
  /// Joint angles that put the flange at `T_base_flange`, by damped Gauss-Newton
  /// from several seeds; nullopt when none reaches it within 1e-10 (unreachable).
  std::optional<Vector6d> inverse(const Eigen::Isometry3d& T_base_flange) const;

  /// The same arm with every length off by N(0, length_sigma) (m) and every
  /// angle (alpha and the joint offset) by N(0, angle_sigma) (rad).
  SerialArm perturbed(Rng& rng, double length_sigma, double angle_sigma) const;

 private:
  std::array<DhJoint, 6> joints_;
  /// Each link's part that does not move with its joint, Tz(d) Tx(a) Rx(alpha).
  std::array<Eigen::Isometry3d, 6> fixed_;
};

struct SystematicErrors {
  double dh_length_sigma = 0.0;  // m, each DH length of the true arm off the nominal one
  double dh_angle_sigma = 0.0;   // rad
  double focal_error = 0.0;      // relative: the detector's depth is (1 + focal_error) times the true one
  enum class Tails { Gaussian, StudentT3, Contaminated } tails = Tails::Gaussian;
  double contaminated_share = 0.05;  // Contaminated: this share of poses ...
  double contaminated_scale = 5.0;   // ... has this many times the noise (sigma)
};

/// A session as simulate_session, with the errors above. The detection noise is
/// drawn from `noise.camera` (Student-t: with it as the scale matrix); the robot
/// reports the nominal arm's pose of the joint angles that put the true arm's
/// flange where the view needs it (then `noise.robot` on top). The samples carry
/// `noise` as their stated noise block.
SimulatedSession simulate_systematic_session(Rng& rng, Setup setup, const Eigen::Isometry3d& X, int n,
                                             const MeasurementNoise& noise, const SystematicErrors& errors,
                                             const SerialArm& nominal, const SerialArm& truth,
                                             const ViewpointOptions& views = {});

/// The pseudo-true X and Y: the joint estimate from `n` noise-free poses with the
/// same systematic errors, weighed as the sessions are (`weights`: the stated
/// noise; absent: estimated from the residuals). Under a misspecified model the
/// limit depends on the weights.
struct PseudoTruth {
  Eigen::Isometry3d X, Y;
};
PseudoTruth pseudo_truth(Rng& rng, Setup setup, const Eigen::Isometry3d& X, const SystematicErrors& errors,
                         const SerialArm& nominal, const SerialArm& truth,
                         const std::optional<MeasurementNoise>& weights, int n = 2000,
                         const ViewpointOptions& views = {});

}  // namespace handeye
