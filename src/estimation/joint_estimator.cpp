#include "handeye_covariance/estimation/joint_estimator.h"

#include <Eigen/Cholesky>
#include <cmath>

#include "handeye_covariance/core/validation.h"
#include "handeye_covariance/estimation/noise_estimation.h"

namespace handeye {

using Eigen::Isometry3d;
using Eigen::Matrix3d;
using Eigen::Vector3d;
using Matrix12d = Eigen::Matrix<double, 12, 12>;
using Vector12d = Eigen::Matrix<double, 12, 1>;

JointResidual joint_residual(const Rig& rig, const PoseSample& sample, const Isometry3d& X, const Isometry3d& Y) {
  const Isometry3d X_inverse = X.inverse();
  const Isometry3d V = rig.robot_link(sample.T_base_effector);
  const Isometry3d VY = V * Y;
  const Isometry3d predicted = X_inverse * VY;  // P_hat = X^-1 V Y
  JointResidual r;
  const Vector3d phi = so3::log(sample.T_camera_pattern.linear() * predicted.linear().transpose());
  r.error << sample.T_camera_pattern.translation() - predicted.translation(), phi;
  // d P_hat / d xi_X through X^-1, d P_hat / d xi_Y; then e's sensitivity to
  // P_hat: -I for t, and -J_r^-1(phi) for R (log(exp(phi) exp(-xi)) = phi - J_r^-1 xi).
  const Matrix6d dP_dX = compose_jacobian_left(X_inverse, VY) * inverse_jacobian(X);
  const Matrix6d dP_dY = compose_jacobian_right(X_inverse * V);
  Matrix6d de_dP = -Matrix6d::Identity();
  de_dP.bottomRightCorner<3, 3>() = -so3::left_jacobian_inverse(-phi);
  r.jacobian << de_dP * dP_dX, de_dP * dP_dY;
  r.d_effector = compose_jacobian_right(X_inverse) * compose_jacobian_left(V, Y) *
                 rig.robot_link_jacobian(sample.T_base_effector);
  return r;
}

namespace {

/// The noise model of each sample, as in the pairs estimator: its own, else the
/// global block; with neither anywhere, none (to be estimated).
struct SampleNoise {
  Matrix6d camera = Matrix6d::Zero(), robot = Matrix6d::Zero();
  bool robot_is_zero = true;
};

std::vector<SampleNoise> sample_noise(const SampleSet& set, bool& given) {
  given = set.noise.has_value();
  if (set.noise) check_covariance(set.noise->robot, "noise.effector"), check_covariance(set.noise->camera, "noise.pattern");
  std::vector<SampleNoise> out(set.samples.size());
  for (std::size_t i = 0; i < set.samples.size(); ++i) {
    const std::optional<MeasurementNoise>& own = set.samples[i].noise;
    if (own && !set.noise) {
      throw HandEyeError(ErrorCode::InvalidNoise, "a per-item noise is given but there is no global noise block",
                         "samples[" + std::to_string(i) + "]",
                         "add a global `noise` block (it is the default for the other items), or remove the per-item "
                         "noise to have all noise estimated from the residuals");
    }
    if (own) {
      const std::string where = "samples[" + std::to_string(i) + "].noise";
      check_covariance(own->robot, where + ".effector");
      check_covariance(own->camera, where + ".pattern");
    }
    const MeasurementNoise& n = own ? *own : (set.noise ? *set.noise : MeasurementNoise{});
    out[i].camera = n.camera.as_pose_covariance();
    out[i].robot = n.robot.as_pose_covariance();
    out[i].robot_is_zero = out[i].robot.isZero(0.0);
  }
  return out;
}

/// Each sample's weight S_i^-1 at (X, Y). S_i depends on X and Y only through
/// the robot's term D_i Sigma_E D_i^T; the weights are held fixed while
/// Gauss-Newton runs (so the cost it halves on is one function) and refreshed
/// between runs until they no longer move the solution.
std::vector<Matrix6d> weights(const SampleSet& set, const std::vector<SampleNoise>& noise, const Matrix6d* shared_camera,
                              const Isometry3d& X, const Isometry3d& Y) {
  std::vector<Matrix6d> W(set.samples.size());
  for (std::size_t i = 0; i < set.samples.size(); ++i) {
    Matrix6d S = shared_camera ? *shared_camera : noise[i].camera;
    if (!noise[i].robot_is_zero) {
      const JointResidual r = joint_residual(set.rig, set.samples[i], X, Y);
      S.noalias() += r.d_effector * noise[i].robot * r.d_effector.transpose();
    }
    const Eigen::LLT<Matrix6d> llt(S);
    if (llt.info() != Eigen::Success || !(llt.matrixLLT().diagonal().array() > 0.0).all()) {
      throw HandEyeError(ErrorCode::InvalidNoise, "the combined robot + camera noise of this sample is singular",
                         "samples[" + std::to_string(i) + "]",
                         "give a non-zero rotation and translation noise for the pattern (or the robot), or omit the "
                         "noise block to estimate it");
    }
    W[i] = llt.solve(Matrix6d::Identity());
    W[i] = 0.5 * (W[i] + W[i].transpose());
  }
  return W;
}

/// The normal equations at (X, Y) under fixed weights.
struct Linearization {
  Matrix12d information = Matrix12d::Zero();
  Vector12d gradient = Vector12d::Zero();
  double cost = 0.0;
  Matrix6d residual_scatter = Matrix6d::Zero();  // sum e e^T, for noise estimation
};

Linearization linearize(const SampleSet& set, const std::vector<Matrix6d>& W, const Isometry3d& X, const Isometry3d& Y) {
  Linearization lin;
  for (std::size_t i = 0; i < set.samples.size(); ++i) {
    const JointResidual r = joint_residual(set.rig, set.samples[i], X, Y);
    const Eigen::Matrix<double, 6, 12> WH = W[i] * r.jacobian;
    const Vector6d We = W[i] * r.error;
    lin.information.noalias() += r.jacobian.transpose() * WH;
    lin.gradient.noalias() += r.jacobian.transpose() * We;
    lin.cost += r.error.dot(We);
    lin.residual_scatter.noalias() += r.error * r.error.transpose();
  }
  lin.information = 0.5 * (lin.information + lin.information.transpose());
  return lin;
}

Isometry3d apply(const Isometry3d& T, const Vector6d& d) {
  return se3::make_pose(so3::exp(d.tail<3>()) * T.linear(), T.translation() + d.head<3>());
}

struct JointSolution {
  Isometry3d X, Y;
  Linearization linearization;  // at the solution: its information gives the covariance
  StageDiagnostics diagnostics;
};

/// Gauss-Newton with step halving from (X0, Y0) under fixed weights.
JointSolution gauss_newton(const SampleSet& set, const std::vector<Matrix6d>& W, const Isometry3d& X0,
                           const Isometry3d& Y0, const JointOptions& o) {
  JointSolution s{X0, Y0, linearize(set, W, X0, Y0), {}};
  for (int iteration = 1; iteration <= o.max_iterations; ++iteration) {
    s.diagnostics.iterations = iteration;
    const Eigen::LDLT<Matrix12d> ldlt(s.linearization.information);
    Vector12d step = -ldlt.solve(s.linearization.gradient);
    const double length = step.dot(s.linearization.information * step);
    if (!std::isfinite(length)) break;  // a singular information: reported by the caller
    Isometry3d X = apply(s.X, step.head<6>()), Y = apply(s.Y, step.tail<6>());
    if (length < o.step_tolerance) {
      // Below 1e-4 sigma: take it; the current linearisation is as good to first order.
      s.X = X, s.Y = Y;
      s.diagnostics.stop_reason = StopReason::StepBelowTolerance;
      break;
    }
    Linearization next = linearize(set, W, X, Y);
    for (int halving = 0; halving < 30 && next.cost > s.linearization.cost * (1.0 + 1e-12); ++halving) {
      step *= 0.5;
      X = apply(s.X, step.head<6>()), Y = apply(s.Y, step.tail<6>());
      next = linearize(set, W, X, Y);
    }
    const double previous = s.linearization.cost;
    if (next.cost <= previous * (1.0 + 1e-12)) s.X = X, s.Y = Y, s.linearization = std::move(next);
    if (std::abs(previous - s.linearization.cost) <= 1e-14 * std::max(previous, 1e-300)) {
      s.diagnostics.stop_reason = StopReason::CostChangeBelowTolerance;
      break;
    }
  }
  s.diagnostics.chi2 = s.linearization.cost;
  s.diagnostics.dof = 6 * static_cast<int>(set.samples.size()) - 12;
  return s;
}

/// Gauss-Newton, refreshing the weights (the robot's term) until a run starts converged.
JointSolution solve_weighted(const SampleSet& set, const std::vector<SampleNoise>& noise, const Matrix6d* shared_camera,
                             const Isometry3d& X0, const Isometry3d& Y0, const JointOptions& o) {
  bool robot = false;
  for (const SampleNoise& n : noise) robot = robot || !n.robot_is_zero;
  JointSolution s = gauss_newton(set, weights(set, noise, shared_camera, X0, Y0), X0, Y0, o);
  int iterations = s.diagnostics.iterations;
  for (int round = 0; robot && round < 10; ++round) {
    s = gauss_newton(set, weights(set, noise, shared_camera, s.X, s.Y), s.X, s.Y, o);
    iterations += s.diagnostics.iterations;
    if (s.diagnostics.iterations <= 1 && s.diagnostics.converged()) break;
  }
  s.diagnostics.iterations = iterations;
  return s;
}

}  // namespace

Calibration estimate(const SampleSet& samples, Method method) {
  return method == Method::Joint ? solve_joint(samples) : solve(samples);
}

Calibration solve_joint(const SampleSet& samples, const JointOptions& options) {
  const int n = static_cast<int>(samples.samples.size());
  for (int i = 0; i < n; ++i) {
    const std::string where = "samples[" + std::to_string(i) + "]";
    check_pose(samples.samples[i].T_base_effector, where + ".effector");
    check_pose(samples.samples[i].T_camera_pattern, where + ".pattern");
  }
  bool given = false;
  const std::vector<SampleNoise> noise = sample_noise(samples, given);
  const Isometry3d X0 = checked_initial_guess(samples, options.checks);  // throws the degeneracy errors
  std::vector<Isometry3d> loops;
  loops.reserve(samples.samples.size());
  for (const PoseSample& s : samples.samples) loops.push_back(samples.rig.pattern_pose(s.T_base_effector, X0, s.T_camera_pattern));
  const Isometry3d Y0 = mean_pose(loops);

  Calibration result;
  result.method = Method::Joint;
  result.initial_guess = X0;
  result.samples_used = n;
  JointSolution s;
  Matrix6d camera = Matrix6d::Zero();
  double inflation = 1.0;  // estimated noise: see joint_estimator.h
  if (given) {
    s = solve_weighted(samples, noise, nullptr, X0, Y0, options);
    result.noise = samples.noise ? *samples.noise : MeasurementNoise{};
  } else {
    if (n < 4) {
      throw HandEyeError(ErrorCode::NoiseUnidentifiable,
                         "no noise was given and " + std::to_string(n) +
                             " samples are too few to estimate a 6x6 noise from the residuals (need >= 4)",
                         "input", "add a `noise` block with the pose covariances, or record more samples");
    }
    // A start of 1 mm and 0.1 deg per axis; then the residuals' own 6x6, iterated with the solve.
    camera.diagonal() << Vector3d::Constant(1e-6), Vector3d::Constant(std::pow(0.1 * M_PI / 180.0, 2));
    s = solve_weighted(samples, noise, &camera, X0, Y0, options);
    // As many noise parameters as the residuals' dof support (joint_estimator.h).
    const int dof = n - 2;
    const auto model = [&](const Matrix6d& scatter) {
      Matrix6d C = scatter / static_cast<double>(dof);
      if (dof < options.full_noise_min_dof) C = Matrix6d(C.diagonal().asDiagonal());
      if (dof < options.per_axis_noise_min_dof) {
        C.diagonal() << Vector3d::Constant(C.diagonal().head<3>().mean()), Vector3d::Constant(C.diagonal().tail<3>().mean());
      }
      C.diagonal() = C.diagonal().cwiseMax(1e-18);  // (1e-9 m or rad)^2: noise-free input stays solvable
      return C;
    };
    const bool full = dof >= options.full_noise_min_dof, per_axis = dof >= options.per_axis_noise_min_dof;
    inflation = full ? dof / (dof - 7.0) : per_axis ? dof / (dof - 2.0) : 3.0 * dof / (3.0 * dof - 2.0);
    result.noise_model = full ? "a full 6x6 camera noise" : per_axis ? "per-axis camera variances" : "one camera variance for translation and one for rotation";
    result.noise_model += " from " + std::to_string(dof) + " samples' worth of residuals, robot taken as exact; covariance x" +
                          number_text(inflation, 3) + " for the noise estimate's own uncertainty";
    for (int round = 0; round < options.max_noise_rounds; ++round) {
      const Matrix6d next = model(s.linearization.residual_scatter);
      const double change = (next - camera).norm() / std::max(camera.norm(), 1e-300);
      camera = next;
      s = solve_weighted(samples, noise, &camera, s.X, s.Y, options);
      if (change < options.noise_tolerance) break;
    }
    result.noise_origin = NoiseOrigin::EstimatedFromResiduals;
    result.noise.camera = PoseNoise::from_pose_covariance(camera);
  }

  const Eigen::LDLT<Matrix12d> ldlt(s.linearization.information);
  const Matrix12d covariance = ldlt.solve(Matrix12d::Identity());
  if (ldlt.info() != Eigen::Success || !covariance.allFinite() || !(covariance.diagonal().array() > 0.0).all()) {
    throw HandEyeError(ErrorCode::PoorlyConstrained, "the samples do not determine X and the pattern pose together",
                       "input", "add samples that rotate the flange about different axes");
  }
  const Eigen::Matrix<double, 12, 12> symmetric = 0.5 * inflation * (covariance + covariance.transpose());
  result.T_parent_camera = s.X;
  result.pose_covariance = symmetric.topLeftCorner<6, 6>();
  result.translation_covariance = result.pose_covariance.topLeftCorner<3, 3>();
  result.rotation_covariance = result.pose_covariance.bottomRightCorner<3, 3>();
  result.pattern = PoseWithCovariance{s.Y, symmetric.bottomRightCorner<6, 6>()};
  result.cross_covariance = symmetric.topRightCorner<6, 6>();
  result.rotation_stage = result.translation_stage = s.diagnostics;
  result.motions_used = 0;

  const double rotation_sigma = max_sigma(result.rotation_covariance);
  if (!(rotation_sigma <= options.checks.max_rotation_sigma)) {
    throw HandEyeError(ErrorCode::PoorlyConstrained,
                       "the samples constrain the rotation only to " + number_text(rotation_sigma * 180.0 / M_PI) +
                           " deg (1 sigma); a first-order covariance is not valid there",
                       "input", "add samples with larger rotations about different axes, or reduce the noise");
  }
  if (given && s.diagnostics.dof >= 12) {
    const double ratio = s.diagnostics.chi2 / s.diagnostics.dof;
    if (ratio > 3.0) {
      result.warnings.push_back("residuals are " + number_text(std::sqrt(ratio), 2) +
                                "x larger than the stated noise predicts (chi2/dof = " + number_text(ratio, 3) +
                                "); the covariance is likely optimistic. Check the noise block or estimate it "
                                "(omit it, or use `handeye noise`).");
    }
  }
  return result;
}

}  // namespace handeye
