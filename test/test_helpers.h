// Shared helpers for the tests: seeded data and numeric differentiation.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <functional>
#include <random>
#include <utility>
#include <vector>

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

/// The central `coverage` band of the mean of NEES over sessions whose covariances
/// scale with a pixel variance estimated from dof[k] degrees of freedom and carry
/// the Student-t factor nu / (nu - 2) (PixelNoise::covariance_variance): each
/// NEES is chi2(dim) / (chi2(nu) / nu) x (nu - 2) / nu, with mean dim. For large nu
/// this is the chi2 band; for 12 views of one marker (nu = 24) it is wider. By
/// seeded Monte-Carlo, 200 000 draws of the mean (100 beyond each end of a 99.9%
/// band). A model: the estimator's own chi2 gate, which re-fits a noise scale when
/// s^2 comes out small, is not in it. (test_helpers.cpp)
std::pair<double, double> nees_band_under_estimated_sigma(const std::vector<int>& dof, int dim, double coverage);

/// The central `coverage` band of the mean of `draws` independent chi2(dim) values
/// (an honest covariance's NEES with its noise known): chi2(dim x draws) / draws. A
/// Monte-Carlo test's band follows its number of draws through this. (test_helpers.cpp:
/// boost's chi2 quantiles are compiled once, not in every test that includes this.)
std::pair<double, double> chi2_mean_band(int draws, int dim, double coverage);

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
