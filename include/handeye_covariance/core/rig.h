// The setup's geometry, in one place: the two setups, the frame names, which
// frame is X's parent, and how a sample's robot pose enters the loop.
//
// Frames: T_a_b maps points in frame b to frame a (p_a = T_a_b * p_b).
//   eye_in_hand: X = T_effector_camera, camera on the flange, Y = T_base_pattern fixed in the world.
//   eye_to_hand: X = T_base_camera, camera fixed,              Y = T_effector_pattern on the flange.
//
// Every sample (E = T_base_effector, P = T_camera_pattern) closes one loop,
//     Y = V^-1 X P,   V = E^-1 (eye_in_hand) or E (eye_to_hand),
// where V, the robot's link in the loop, maps points in Y's parent frame into
// X's parent frame. Everything that depends on the setup follows from V:
//   the motion between samples i -> j (the paper's eq. 2): A = V_j V_i^-1, B = P_j P_i^-1;
//   what the camera sees at a robot pose:                 P = X^-1 V Y;
//   the robot pose that shows a view:                     V = X P Y^-1.
// Perturbations are left perturbations in the parent frame, ROS order
// (x, y, z, rx, ry, rz), as everywhere (pose_covariance.h).
#pragma once

#include <string>
#include <utility>

#include "handeye_covariance/core/pose_covariance.h"

namespace handeye {

enum class Setup { EyeInHand, EyeToHand };

/// "eye_in_hand" / "eye_to_hand": the spelling of files and messages.
const char* to_string(Setup setup);
/// The inverse of to_string; throws HandEyeError(MalformedFile) naming `where` otherwise.
Setup setup_from_string(const std::string& name, const std::string& where);
/// easy_handeye's and the node's `eye_on_hand` parameter.
Setup setup_from_eye_on_hand(bool eye_on_hand);

struct FrameNames {
  std::string base, effector, camera, pattern;  // empty when unknown
};

struct Rig {
  Setup setup = Setup::EyeInHand;
  FrameNames frames;
  /// Where the target's printed face is in the pattern frame: its middle, z out
  /// of the face towards a camera that sees it (core/target.h, target_face). The
  /// identity for a tag or a layout centred on its frame; a chessboard's or a
  /// ChArUco board's frame is OpenCV's (a corner, z into the board). New views
  /// (next-best-pose candidates) look at the face, not at the frame's origin.
  Eigen::Isometry3d T_pattern_face = Eigen::Isometry3d::Identity();
  /// The printed face's width and height (m) about T_pattern_face, over its
  /// detected points (core/target.h target_face_size); zero when the target is not
  /// known. The view-following noise model takes its shape from it (view_noise.h).
  Eigen::Vector2d face_size = Eigen::Vector2d::Zero();
  /// The target looks the same turned by pi about its face's normal through the
  /// face's centre (core/target.h is_half_turn_symmetric): each view's detected pose
  /// P is one of two candidates, P and P face_half_turn(), which the session
  /// decides from the robot's motion (estimation/symmetric_views.h).
  bool symmetric_face = false;

  bool eye_in_hand() const { return setup == Setup::EyeInHand; }
  /// F = T_pattern_pattern': the pattern frame turned by pi about the face's
  /// normal (T_pattern_face's z) through its centre. F F = I.
  Eigen::Isometry3d face_half_turn() const;
  /// X's parent frame: the effector (eye_in_hand) or the base (eye_to_hand).
  const std::string& camera_parent_frame() const { return eye_in_hand() ? frames.effector : frames.base; }
  std::string& camera_parent_frame() { return eye_in_hand() ? frames.effector : frames.base; }
  /// Y's parent frame: the base (eye_in_hand) or the effector (eye_to_hand).
  const std::string& pattern_parent_frame() const { return eye_in_hand() ? frames.base : frames.effector; }
  std::string& pattern_parent_frame() { return eye_in_hand() ? frames.base : frames.effector; }

  /// Which setup inverts E in the loop: V = E^-1 eye_in_hand, V = E eye_to_hand. The
  /// one statement of it; robot_link, its Jacobian and the solver's terms ask it.
  bool link_is_inverse() const { return eye_in_hand(); }
  /// V: E^-1 (eye_in_hand) or E (eye_to_hand).
  Eigen::Isometry3d robot_link(const Eigen::Isometry3d& T_base_effector) const;
  /// d V / d E: V's perturbation from E's (ROS order).
  Matrix6d robot_link_jacobian(const Eigen::Isometry3d& T_base_effector) const;
  /// The effector pose with robot link V (robot_link's inverse).
  Eigen::Isometry3d effector_for_link(const Eigen::Isometry3d& V) const;

  /// The robot motion A = V_j V_i^-1 between samples i -> j, and its Jacobians
  /// to the perturbations of E_i and E_j.
  Eigen::Isometry3d robot_motion(const Eigen::Isometry3d& E_i, const Eigen::Isometry3d& E_j) const;
  std::pair<Matrix6d, Matrix6d> robot_motion_jacobians(const Eigen::Isometry3d& E_i, const Eigen::Isometry3d& E_j) const;
  /// The rotation block of A's covariance from the robot poses' rotation covariances
  /// (the rotation rows of robot_motion_jacobians, written out: a pose's translation
  /// does not move A's rotation). eye_in_hand R_A = R_j^T R_i: R_j^T (S_i + S_j) R_j;
  /// eye_to_hand R_A = R_j R_i^T: S_j + R_A S_i R_A^T.
  Eigen::Matrix3d robot_motion_rotation_covariance(const Eigen::Isometry3d& E_i, const Eigen::Isometry3d& E_j,
                                                   const Eigen::Matrix3d& rotation_covariance_i,
                                                   const Eigen::Matrix3d& rotation_covariance_j) const;

  /// Y = V^-1 X P: the pattern's pose as one sample and X see it.
  Eigen::Isometry3d pattern_pose(const Eigen::Isometry3d& T_base_effector, const Eigen::Isometry3d& X,
                                 const Eigen::Isometry3d& T_camera_pattern) const;
  /// P = X^-1 V Y: what the camera sees with the robot at T_base_effector.
  Eigen::Isometry3d predicted_view(const Eigen::Isometry3d& T_base_effector, const Eigen::Isometry3d& X,
                                   const Eigen::Isometry3d& Y) const;
  /// The effector pose at which the camera sees `T_camera_pattern`: V = X P Y^-1.
  Eigen::Isometry3d effector_for_view(const Eigen::Isometry3d& X, const Eigen::Isometry3d& Y,
                                      const Eigen::Isometry3d& T_camera_pattern) const;

  /// T_base_<X's parent> with the robot at T_base_effector: E (eye_in_hand) or the
  /// identity (eye_to_hand), the first factor of eq. (68) T_base_object = T_base_parent X P.
  Eigen::Isometry3d camera_parent_in_base(const Eigen::Isometry3d& T_base_effector) const;
};

}  // namespace handeye
