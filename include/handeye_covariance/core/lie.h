// SO(3) and SE(3) helpers used by the hand-eye estimator.
//
// Conventions (the same everywhere in this package):
//  * hat(w) is the skew matrix [w] with [w] v = w x v; vee is its inverse.
//  * Rotation uncertainty is a LEFT perturbation in the parent frame:
//    R = exp([xi]) * R_hat, as in the paper (eq. 3-4) and in ROS pose covariances.
//  * exp/log are robust at 0 (Taylor series) and at pi (log goes through a
//    quaternion with w >= 0, so the angle is atan2-accurate up to and including pi).
//  * left_jacobian(phi) J satisfies exp([phi + d]) ~= exp([J d]) exp([phi]), and
//    log(exp([d]) exp([phi])) ~= phi + J^{-1} d  (Barfoot & Furgale, the paper's [9]).
//  * SE(3) tangent vectors are ordered (rho, phi) = (translation, rotation), the
//    same order as ROS covariances (x, y, z, rx, ry, rz).
#pragma once

#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace handeye {

using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Matrix12d = Eigen::Matrix<double, 12, 12>;  // the joint (X, Y) blocks, X first
using Vector6d = Eigen::Matrix<double, 6, 1>;

namespace so3 {

/// [w]: the skew-symmetric matrix with hat(w) * v == w.cross(v).
Eigen::Matrix3d hat(const Eigen::Vector3d& w);

/// Inverse of hat; reads the skew-symmetric part, so it tolerates rounding noise.
Eigen::Vector3d vee(const Eigen::Matrix3d& W);

/// Rodrigues' formula; Taylor-expanded below 1e-4 rad.
Eigen::Matrix3d exp(const Eigen::Vector3d& phi);

/// Rotation vector of R with angle in [0, pi]. At exactly pi the axis sign is
/// whatever the quaternion gives; callers that need a consistent sign across
/// pairs (the estimator) choose the representative themselves.
Eigen::Vector3d log(const Eigen::Matrix3d& R);

/// Left Jacobian J_l(phi) of SO(3).
Eigen::Matrix3d left_jacobian(const Eigen::Vector3d& phi);

/// Inverse of the left Jacobian; finite for |phi| < 2 pi (including pi).
Eigen::Matrix3d left_jacobian_inverse(const Eigen::Vector3d& phi);

/// Same rotation as phi, expressed with angle |phi| - 2 pi (axis flipped).
/// Used near pi to choose the log representative that agrees with a reference.
Eigen::Vector3d other_representative(const Eigen::Vector3d& phi);

}  // namespace so3

namespace se3 {

/// exp of a twist (rho, phi): R = exp(phi), t = J_l(phi) rho.
Eigen::Isometry3d exp(const Vector6d& twist);

/// Inverse of exp; the rotation angle is in [0, pi].
Vector6d log(const Eigen::Isometry3d& T);

/// Pose with a rotation and translation; no checks (see validation.h).
Eigen::Isometry3d make_pose(const Eigen::Matrix3d& R, const Eigen::Vector3d& t);

}  // namespace se3

/// The mean pose of eq. (66-67): the rotation mean on SO(3) (iterated about
/// the current mean so it holds near pi too) and the arithmetic mean of t.
Eigen::Isometry3d mean_pose(const std::vector<Eigen::Isometry3d>& poses, int max_iterations = 20);

}  // namespace handeye
