#include "handeye_covariance/core/rig.h"

#include "handeye_covariance/core/errors.h"

namespace handeye {

using Eigen::Isometry3d;

const char* to_string(Setup setup) { return setup == Setup::EyeInHand ? "eye_in_hand" : "eye_to_hand"; }

Setup setup_from_string(const std::string& name, const std::string& where) {
  if (name == "eye_in_hand") return Setup::EyeInHand;
  if (name == "eye_to_hand") return Setup::EyeToHand;
  throw HandEyeError(ErrorCode::MalformedFile, "unknown setup `" + name + "`", where,
                     "use eye_in_hand (camera on the flange) or eye_to_hand (camera fixed, pattern on the flange)");
}

Setup setup_from_eye_on_hand(bool eye_on_hand) { return eye_on_hand ? Setup::EyeInHand : Setup::EyeToHand; }

Isometry3d Rig::face_half_turn() const {
  // T_pattern_face Rz(pi) T_pattern_face^-1, its rotation built exactly: a turn by pi
  // about the unit normal n is 2 n n^T - I (no sin(pi) residue), and F F = I.
  const Eigen::Vector3d normal = T_pattern_face.linear().col(2).normalized(), centre = T_pattern_face.translation();
  const Eigen::Matrix3d R = 2.0 * normal * normal.transpose() - Eigen::Matrix3d::Identity();
  return se3::make_pose(R, centre - R * centre);
}

Isometry3d Rig::robot_link(const Isometry3d& E) const { return link_is_inverse() ? E.inverse() : E; }

Matrix6d Rig::robot_link_jacobian(const Isometry3d& E) const {
  return link_is_inverse() ? inverse_jacobian(E) : Matrix6d::Identity();
}

Isometry3d Rig::effector_for_link(const Isometry3d& V) const { return link_is_inverse() ? V.inverse() : V; }

Isometry3d Rig::robot_motion(const Isometry3d& E_i, const Isometry3d& E_j) const {
  // eye_in_hand A = E_j^-1 E_i; eye_to_hand A = E_j E_i^-1.
  return eye_in_hand() ? E_j.inverse() * E_i : E_j * E_i.inverse();
}

std::pair<Matrix6d, Matrix6d> Rig::robot_motion_jacobians(const Isometry3d& E_i, const Isometry3d& E_j) const {
  // A = V_j V_i^-1; written per setup so that V_i^-1 = E_i (eye_in_hand) needs no
  // inverse Jacobian pair (they cancel exactly).
  if (eye_in_hand()) {
    return {compose_jacobian_right(E_j.inverse()),
            compose_jacobian_left(E_j.inverse(), E_i) * inverse_jacobian(E_j)};
  }
  return {compose_jacobian_right(E_j) * inverse_jacobian(E_i), compose_jacobian_left(E_j, E_i.inverse())};
}

Eigen::Matrix3d Rig::robot_motion_rotation_covariance(const Isometry3d& E_i, const Isometry3d& E_j,
                                                      const Eigen::Matrix3d& rotation_covariance_i,
                                                      const Eigen::Matrix3d& rotation_covariance_j) const {
  if (eye_in_hand()) {
    const Eigen::Matrix3d& R_j = E_j.linear();
    return R_j.transpose() * (rotation_covariance_i + rotation_covariance_j) * R_j;
  }
  const Eigen::Matrix3d R_A = E_j.linear() * E_i.linear().transpose();
  return rotation_covariance_j + R_A * rotation_covariance_i * R_A.transpose();
}

Isometry3d Rig::pattern_pose(const Isometry3d& E, const Isometry3d& X, const Isometry3d& P) const {
  return (eye_in_hand() ? E : E.inverse()) * X * P;  // V^-1 X P
}

Isometry3d Rig::predicted_view(const Isometry3d& E, const Isometry3d& X, const Isometry3d& Y) const {
  return X.inverse() * robot_link(E) * Y;  // P = X^-1 V Y
}

Isometry3d Rig::effector_for_view(const Isometry3d& X, const Isometry3d& Y, const Isometry3d& P) const {
  // V = X P Y^-1, written out per setup so that no inverse of a product is rounded twice.
  return eye_in_hand() ? Isometry3d(Y * P.inverse() * X.inverse()) : Isometry3d(X * P * Y.inverse());
}

Isometry3d Rig::camera_parent_in_base(const Isometry3d& E) const {
  return eye_in_hand() ? E : Isometry3d::Identity();
}

}  // namespace handeye
