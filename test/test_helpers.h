// Shared helpers for the tests: seeded data and numeric differentiation.
#pragma once

#include <gtest/gtest.h>

#include <functional>

#include "handeye_covariance/core/lie.h"
#include "handeye_covariance/simulation/simulation.h"

namespace handeye {
namespace test {

/// Rotation-vector difference log(R1 R2^T), the left-perturbation error.
inline Eigen::Vector3d rotation_difference(const Eigen::Matrix3d& R1, const Eigen::Matrix3d& R2) {
  return so3::log(R1 * R2.transpose());
}

/// Central-difference Jacobian of f: R^n -> R^m at 0.
template <int M, int N>
Eigen::Matrix<double, M, N> numeric_jacobian(const std::function<Eigen::Matrix<double, M, 1>(const Eigen::Matrix<double, N, 1>&)>& f,
                                             double h = 1e-6) {
  Eigen::Matrix<double, M, N> J;
  for (int j = 0; j < N; ++j) {
    Eigen::Matrix<double, N, 1> d = Eigen::Matrix<double, N, 1>::Zero();
    d(j) = h;
    J.col(j) = (f(d) - f(-d)) / (2.0 * h);
  }
  return J;
}

/// The 6-vector perturbation (dt, xi_R) of `perturbed` relative to `nominal`.
inline Vector6d pose_perturbation(const Eigen::Isometry3d& perturbed, const Eigen::Isometry3d& nominal) {
  Vector6d d;
  d.head<3>() = perturbed.translation() - nominal.translation();
  d.tail<3>() = rotation_difference(perturbed.linear(), nominal.linear());
  return d;
}

/// `handeye sim`'s default noise: pattern 0.5 mm / 0.05 deg, robot 0.05 mm / 0.01 deg (1 sigma per axis).
inline MeasurementNoise sim_noise() {
  const double deg = M_PI / 180.0;
  MeasurementNoise noise;
  noise.camera = {std::pow(0.05 * deg, 2) * Eigen::Matrix3d::Identity(), std::pow(0.5e-3, 2) * Eigen::Matrix3d::Identity()};
  noise.robot = {std::pow(0.01 * deg, 2) * Eigen::Matrix3d::Identity(), std::pow(0.05e-3, 2) * Eigen::Matrix3d::Identity()};
  return noise;
}

/// Applies a perturbation (dt, xi_R) to a pose: R = exp(xi_R) R, t = t + dt.
inline Eigen::Isometry3d apply(const Eigen::Isometry3d& pose, const Vector6d& d) {
  return se3::make_pose(so3::exp(d.tail<3>()) * pose.linear(), pose.translation() + d.head<3>());
}

}  // namespace test
}  // namespace handeye
