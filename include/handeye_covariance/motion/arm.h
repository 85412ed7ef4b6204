// The arm that moves the camera (or the target): its chain from the base to the
// effector, joint limits and collision geometry, read from a URDF. No ROS: the
// URDF text comes from the caller (the node reads `robot_description`), parsed by
// urdfdom and kdl_parser; forward and inverse kinematics by orocos KDL.
//
// Frames: poses are T_base_<link> (points in the link to the chain's base frame).
// Joint vectors q follow the chain's order of movable joints, in rad (or m).
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "handeye_covariance/core/viewpoints.h"  // Rng

namespace KDL {
class Chain;
}

namespace handeye::motion {

struct JointLimit {
  std::string name;
  double lower = 0.0, upper = 0.0;  // rad
  double velocity = 0.0;            // rad/s, from the URDF
};

/// A primitive of the arm's collision geometry, in its link's frame.
struct Shape {
  enum class Kind { Box, Cylinder, Sphere };
  Kind kind = Kind::Box;
  /// Box: the full sizes along x, y, z. Cylinder: radius, length (along z), 0.
  /// Sphere: radius, 0, 0. Metres.
  Eigen::Vector3d size = Eigen::Vector3d::Zero();
  Eigen::Isometry3d T_link_shape = Eigen::Isometry3d::Identity();
};

/// One rigid body of the chain: a URDF link of the chain with the shapes of the
/// links fixed below it off the chain (a camera or a gripper bolted on), and the
/// number of movable joints before it.
struct Body {
  std::string name;
  int segment = 0;          // the chain's segments up to and including this link
  int joints_before = 0;    // 0: fixed to the base, it never moves
  std::vector<Shape> shapes;
};

/// Not thread-safe: KDL caches joint poses inside the chain, so calls on one Arm
/// from two threads race (copies are independent: one per thread).
class Arm {
 public:
  /// The chain from `base_link` to `tip_link` of the URDF text. Throws
  /// HandEyeError naming `where` when the URDF does not parse, a link is not in
  /// it, the chain has no movable joint, or a movable joint has no limits
  /// (continuous joints get [-2 pi, 2 pi]). Mesh collision geometry is refused
  /// (the planner checks primitives): approximate it with boxes and cylinders.
  static Arm from_urdf(const std::string& urdf, const std::string& base_link, const std::string& tip_link,
                       const std::string& where);
  Arm(const Arm&);
  Arm& operator=(const Arm&);
  Arm(Arm&&) noexcept;
  Arm& operator=(Arm&&) noexcept;
  ~Arm();

  int joints() const { return static_cast<int>(limits_.size()); }
  const std::vector<JointLimit>& limits() const { return limits_; }
  const std::vector<Body>& bodies() const { return bodies_; }
  const std::string& base_link() const { return base_link_; }
  const std::string& tip_link() const { return tip_link_; }

  /// Adds a shape to the body `link` (e.g. the camera's housing on the flange,
  /// placed by X). Throws HandEyeError when the link is not one of bodies().
  void attach(const std::string& link, const Shape& shape);

  /// T_base_tip at q.
  Eigen::Isometry3d forward(const Eigen::VectorXd& q) const;
  /// T_base_body for every body, in bodies()' order.
  std::vector<Eigen::Isometry3d> body_poses(const Eigen::VectorXd& q) const;

  /// For each movable joint, a bound on the distance from its origin of every
  /// point of the shapes it moves, in every configuration (segment lengths
  /// beyond it plus the shapes' extent): a turn by dq moves no point of the arm
  /// more than reach * |dq|. Revolute joints; a prismatic joint's travel is added.
  std::vector<double> reach() const;

  /// Every distinct solution of T_base_tip found from `near` and `seeds` more
  /// random starts (KDL's Levenberg-Marquardt solver), each joint moved by
  /// multiples of 2 pi to the value within its limits nearest `near`; nearest
  /// first (largest joint change). Solutions with a joint outside its limits
  /// are returned too: the caller says why it refuses them.
  std::vector<Eigen::VectorXd> inverse(const Eigen::Isometry3d& T_base_tip, const Eigen::VectorXd& near, int seeds,
                                       Rng& rng) const;

 private:
  Arm();
  std::unique_ptr<KDL::Chain> chain_;
  std::vector<JointLimit> limits_;
  std::vector<Body> bodies_;
  std::string base_link_, tip_link_;
};

/// The largest |q_a - q_b| over the joints.
double largest_joint_change(const Eigen::VectorXd& a, const Eigen::VectorXd& b);

}  // namespace handeye::motion
