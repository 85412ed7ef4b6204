#include "handeye_covariance/estimation/noise_estimation.h"

#include <Eigen/Eigenvalues>
#include <algorithm>

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/core/validation.h"
#include "handeye_covariance/estimation/joint_estimator.h"

namespace handeye {

using Eigen::Isometry3d;
using Eigen::Matrix3d;
using Eigen::Vector3d;

const char* to_string(NoiseSource source) {
  return source == NoiseSource::RepeatedObservations ? "repeated_observations" : "residuals";
}

namespace {

/// The nearest PSD matrix (negative eigenvalues set to 0); notes when it clipped.
Matrix3d clip_to_psd(const Matrix3d& C, const std::string& what, std::vector<std::string>& notes) {
  const Eigen::SelfAdjointEigenSolver<Matrix3d> eig(0.5 * (C + C.transpose()));
  if (eig.eigenvalues().minCoeff() >= 0.0) return 0.5 * (C + C.transpose());
  notes.push_back(what + ": the given robot noise explains more than the residuals along one axis; "
                         "that variance was set to 0 (the robot noise is likely overstated)");
  return eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).asDiagonal() * eig.eigenvectors().transpose();
}

void check_samples(const SampleSet& samples) {
  for (std::size_t i = 0; i < samples.samples.size(); ++i) {
    const std::string where = "samples[" + std::to_string(i) + "]";
    check_pose(samples.samples[i].T_base_effector, where + ".effector");
    check_pose(samples.samples[i].T_camera_pattern, where + ".pattern");
  }
}

}  // namespace

SampleResidual sample_residual(const Rig& rig, const PoseSample& sample, const Isometry3d& X, const Isometry3d& pattern) {
  // The joint estimator's residual and its robot Jacobian (one of each, checked
  // numerically in test_joint_estimator): e = P (-) P_hat with P_hat = X^-1 V Y, so
  // d e / d xi_E = -d P_hat / d xi_E to first order. eq. (64-65)
  const JointResidual joint = joint_residual(rig, sample, X, pattern);
  SampleResidual r;
  r.error = joint.error;
  r.d_effector = -joint.d_effector;
  return r;
}

NoiseEstimate noise_from_repeated_observations(const SampleSet& samples, const RepeatedObservationOptions& options) {
  check_samples(samples);
  // Greedy grouping by the effector pose: a held pose is far tighter than the
  // distance between poses of a session (centimetres, degrees).
  std::vector<std::vector<std::size_t>> groups;
  for (std::size_t i = 0; i < samples.samples.size(); ++i) {
    const Isometry3d& E = samples.samples[i].T_base_effector;
    auto same_pose = [&](const std::vector<std::size_t>& g) {
      const Isometry3d& first = samples.samples[g.front()].T_base_effector;
      return (E.translation() - first.translation()).norm() <= options.group_translation &&
             so3::log(E.linear() * first.linear().transpose()).norm() <= options.group_rotation;
    };
    auto it = std::find_if(groups.begin(), groups.end(), same_pose);
    if (it == groups.end()) {
      groups.push_back({i});
    } else {
      it->push_back(i);
    }
  }
  Matrix6d robot = Matrix6d::Zero(), camera = Matrix6d::Zero();
  NoiseEstimate estimate;
  estimate.source = NoiseSource::RepeatedObservations;
  for (const auto& g : groups) {
    if (g.size() < 2) continue;
    std::vector<Isometry3d> E, P;
    for (std::size_t i : g) {
      E.push_back(samples.samples[i].T_base_effector);
      P.push_back(samples.samples[i].T_camera_pattern);
    }
    const Isometry3d E_mean = mean_pose(E), P_mean = mean_pose(P);
    for (std::size_t k = 0; k < g.size(); ++k) {
      const Vector6d e = pose_error(E[k], E_mean), p = pose_error(P[k], P_mean);
      robot += e * e.transpose();
      camera += p * p.transpose();
    }
    ++estimate.groups;
    estimate.samples_used += static_cast<int>(g.size());
    estimate.dof += static_cast<double>(g.size() - 1);  // each group's mean absorbs one sample
  }
  if (estimate.dof < 4.0) {
    throw HandEyeError(ErrorCode::NoiseUnidentifiable,
                       std::to_string(estimate.groups) + " pose(s) were seen more than once, giving " +
                           number_text(estimate.dof) + " degrees of freedom (need >= 4)",
                       "samples", "hold the robot still and take 5-10 samples at each of a few poses "
                                  "(effector poses within 1 mm and 0.1 deg count as one), or use the residuals "
                                  "against a calibration (--source residuals)");
  }
  estimate.noise.robot = PoseNoise::from_pose_covariance(robot / estimate.dof);  // a sample covariance: PSD, cross block kept
  estimate.noise.camera = PoseNoise::from_pose_covariance(camera / estimate.dof);
  estimate.robot_identified = true;
  estimate.notes.push_back("robot noise = the scatter of the reported effector pose while it is held still "
                           "(not its repeatability between approaches)");
  return estimate;
}

NoiseEstimate noise_from_residuals(const SampleSet& samples, const Isometry3d& X, bool X_fitted_to_these_samples,
                                   const std::optional<PoseNoise>& robot_noise) {
  check_samples(samples);
  check_pose(X, "calibration");
  if (robot_noise) check_covariance(*robot_noise, "robot noise");
  const std::size_t n = samples.samples.size();
  const double fitted = 1.0 + (X_fitted_to_these_samples ? 1.0 : 0.0);  // Y, and X: 6 parameters each
  if (n < 4 || static_cast<double>(n) - fitted < 3.0) {
    throw HandEyeError(ErrorCode::NoiseUnidentifiable,
                       std::to_string(n) + " samples are too few to estimate the noise from residuals",
                       "samples", "record at least 10 samples (30+ for a 25% accurate variance)");
  }
  const Isometry3d Y_mean = pattern_pose(samples, X);  // eq. (66-67)
  Matrix6d residual = Matrix6d::Zero(), robot_part = Matrix6d::Zero();
  for (const PoseSample& s : samples.samples) {
    const SampleResidual r = sample_residual(samples.rig, s, X, Y_mean);
    residual += r.error * r.error.transpose();
    if (robot_noise) robot_part += r.d_effector * robot_noise->as_pose_covariance() * r.d_effector.transpose();
  }
  NoiseEstimate estimate;
  estimate.source = NoiseSource::Residuals;
  estimate.samples_used = static_cast<int>(n);
  estimate.dof = static_cast<double>(n) - fitted;  // Y's (and X's) fit absorbs about one sample each
  Matrix6d camera = residual / estimate.dof;
  if (robot_noise) {
    camera -= robot_part / static_cast<double>(n);
    estimate.noise.robot = *robot_noise;
    estimate.notes.push_back("the given robot noise was subtracted from the residuals");
  } else {
    estimate.notes.push_back("robot taken as exact: the pattern noise includes the robot's (conservative)");
  }
  // Per block: clipping a 6x6 of m^2 and rad^2 to PSD would depend on the units;
  // the cross block is left out of this estimate.
  estimate.noise.camera.rotation = clip_to_psd(camera.bottomRightCorner<3, 3>(), "pattern rotation", estimate.notes);
  estimate.noise.camera.translation = clip_to_psd(camera.topLeftCorner<3, 3>(), "pattern translation", estimate.notes);
  return estimate;
}

}  // namespace handeye
