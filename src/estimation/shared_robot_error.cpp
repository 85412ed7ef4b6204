#include "handeye_covariance/estimation/shared_robot_error.h"

#include <Eigen/Cholesky>
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/core/lie.h"
#include "handeye_covariance/estimation/joint_estimator.h"
#include "handeye_covariance/estimation/split_check.h"

namespace handeye {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;
using Vector12d = Eigen::Matrix<double, 12, 1>;

/// The session linearised at the calibration: e = r + J dxi (6n rows, sample by sample).
struct Linearised {
  int n = 0;
  MatrixXd J;
  VectorXd r;
  std::vector<Matrix6d> S, D;
  std::vector<Eigen::Vector3d> position;  // the effector's, base frame
};

Linearised linearise(const SampleSet& samples, const Calibration& calibration, std::vector<int>& used) {
  if (!calibration.pattern) {
    throw HandEyeError(ErrorCode::InvalidNoise, "the shared robot error needs a joint fit (X and the pattern pose Y)",
                       "calibration", "fit the samples with the joint estimator first");
  }
  std::vector<bool> rejected(samples.samples.size(), false);
  for (const Calibration::Rejected& r : calibration.rejected) {
    if (r.index >= 0 && r.index < static_cast<int>(rejected.size())) rejected[static_cast<std::size_t>(r.index)] = true;
  }
  const std::vector<Matrix6d> S = residual_covariances(samples, calibration);
  used.clear();
  for (std::size_t i = 0; i < samples.samples.size(); ++i) {
    if (!rejected[i]) used.push_back(static_cast<int>(i));
  }
  Linearised L;
  L.n = static_cast<int>(used.size());
  if (L.n < 8) {
    throw HandEyeError(ErrorCode::TooFewMotions,
                       "the shared robot error needs at least 8 samples, got " + std::to_string(L.n), "samples",
                       "record more samples");
  }
  L.J.resize(6 * L.n, 12);
  L.r.resize(6 * L.n);
  for (int k = 0; k < L.n; ++k) {
    const PoseSample& s = samples.samples[static_cast<std::size_t>(used[static_cast<std::size_t>(k)])];
    const JointResidual e = joint_residual(samples.rig, s, calibration.T_parent_camera, calibration.pattern->pose);
    L.J.middleRows<6>(6 * k) = e.jacobian;
    L.r.segment<6>(6 * k) = e.error;
    L.S.push_back(S[static_cast<std::size_t>(used[static_cast<std::size_t>(k)])]);
    L.D.push_back(e.d_effector);
    L.position.push_back(s.T_base_effector.translation());
  }
  return L;
}

/// C's three parts: the per-view S_i (block diagonal), and the kernel's
/// translation and rotation parts, k(p_i, p_j) D_i E D_j^T.
struct Parts {
  MatrixXd view, translation, rotation;
  bool shared = false;  // a kernel: three components; none: the view scale alone
};

Parts make_parts(const Linearised& L, double length_scale) {
  Parts P;
  const int m = 6 * L.n;
  P.view = MatrixXd::Zero(m, m);
  for (int i = 0; i < L.n; ++i) P.view.block<6, 6>(6 * i, 6 * i) = L.S[static_cast<std::size_t>(i)];
  P.shared = length_scale > 0.0;
  if (!P.shared) return P;
  P.translation = MatrixXd::Zero(m, m);
  P.rotation = MatrixXd::Zero(m, m);
  for (int i = 0; i < L.n; ++i) {
    for (int j = 0; j < L.n; ++j) {
      const double d = (L.position[static_cast<std::size_t>(i)] - L.position[static_cast<std::size_t>(j)]).norm();
      const double k = std::exp(-d * d / (2.0 * length_scale * length_scale));
      const Matrix6d& Di = L.D[static_cast<std::size_t>(i)];
      const Matrix6d& Dj = L.D[static_cast<std::size_t>(j)];
      P.translation.block<6, 6>(6 * i, 6 * j) = k * Di.leftCols<3>() * Dj.leftCols<3>().transpose();
      P.rotation.block<6, 6>(6 * i, 6 * j) = k * Di.rightCols<3>() * Dj.rightCols<3>().transpose();
    }
  }
  return P;
}

MatrixXd combine(const Parts& P, const Eigen::Vector3d& theta) {
  MatrixXd C = theta(0) * P.view;
  if (P.shared) C += theta(1) * P.translation + theta(2) * P.rotation;
  return C;
}

/// The restricted log-likelihood at theta, its score and expected information.
struct Reml {
  bool ok = false;
  double log_likelihood = 0.0;
  Eigen::Vector3d score = Eigen::Vector3d::Zero();
  Eigen::Matrix3d information = Eigen::Matrix3d::Identity();
};

Reml evaluate(const Parts& P, const Eigen::Vector3d& theta, const MatrixXd& J, const VectorXd& r) {
  Reml out;
  const MatrixXd C = combine(P, theta);
  const Eigen::LLT<MatrixXd> llt(C);
  if (llt.info() != Eigen::Success) return out;
  const MatrixXd Ci = llt.solve(MatrixXd::Identity(C.rows(), C.cols()));
  const MatrixXd W = Ci * J;
  const MatrixXd A = J.transpose() * W;
  const Eigen::LLT<MatrixXd> lla(A);
  if (lla.info() != Eigen::Success) return out;
  const MatrixXd Pm = Ci - W * lla.solve(W.transpose());
  const VectorXd Pr = Pm * r;
  const double log_det_C = 2.0 * llt.matrixLLT().diagonal().array().log().sum();
  const double log_det_A = 2.0 * lla.matrixLLT().diagonal().array().log().sum();
  out.log_likelihood = -0.5 * (log_det_C + log_det_A + r.dot(Pr));
  const int k = P.shared ? 3 : 1;
  const MatrixXd* part[3] = {&P.view, &P.translation, &P.rotation};
  std::vector<MatrixXd> PC;
  for (int a = 0; a < k; ++a) {
    PC.push_back(Pm * *part[a]);
    out.score(a) = 0.5 * (Pr.dot(*part[a] * Pr) - PC.back().trace());
  }
  for (int a = 0; a < k; ++a) {
    for (int b = 0; b <= a; ++b) {
      // tr(P C_a P C_b) = sum_ij (P C_a)_ij (P C_b)_ji
      out.information(a, b) = out.information(b, a) = 0.5 * PC[static_cast<std::size_t>(a)].cwiseProduct(PC[static_cast<std::size_t>(b)].transpose()).sum();
    }
  }
  out.ok = true;
  return out;
}

/// Fisher scoring from `theta` within theta >= 0 (s > 0): a component at its bound
/// whose score points out of the region stays there; a step is halved until the
/// likelihood does not fall.
Eigen::Vector3d fit_theta(const Parts& P, Eigen::Vector3d theta, const MatrixXd& J, const VectorXd& r, int max_iterations,
                          double* log_likelihood) {
  const int k = P.shared ? 3 : 1;
  Reml at = evaluate(P, theta, J, r);
  if (!at.ok) {
    *log_likelihood = -std::numeric_limits<double>::infinity();
    return theta;
  }
  const double floor[3] = {1e-6, 0.0, 0.0};
  for (int it = 0; it < max_iterations; ++it) {
    Eigen::MatrixXd F = at.information.topLeftCorner(k, k);
    Eigen::VectorXd g = at.score.head(k);
    for (int a = 0; a < k; ++a) {
      if (theta(a) <= floor[a] && g(a) < 0.0) {  // held at its bound
        g(a) = 0.0;
        F.row(a).setZero(), F.col(a).setZero(), F(a, a) = 1.0;
      }
    }
    const Eigen::VectorXd step = F.ldlt().solve(g);
    double t = 1.0;
    bool moved = false;
    for (int halving = 0; halving < 30; ++halving, t *= 0.5) {
      Eigen::Vector3d candidate = theta;
      for (int a = 0; a < k; ++a) candidate(a) = std::max(floor[a], theta(a) + t * step(a));
      const Reml next = evaluate(P, candidate, J, r);
      if (next.ok && next.log_likelihood >= at.log_likelihood - 1e-9) {
        const double gain = next.log_likelihood - at.log_likelihood;
        theta = candidate, at = next, moved = true;
        if (gain < 1e-7) it = max_iterations;  // converged
        break;
      }
    }
    if (!moved) break;
  }
  *log_likelihood = at.log_likelihood;
  return theta;
}

SharedRobotError describe(double length_scale, const Eigen::Vector3d& theta, double log_likelihood) {
  SharedRobotError e;
  e.length_scale = length_scale;
  e.view_noise_scale = theta(0);
  e.translation_sigma = std::sqrt(std::max(theta(1), 0.0));
  e.rotation_sigma = std::sqrt(std::max(theta(2), 0.0));
  e.log_likelihood = log_likelihood;
  return e;
}

Eigen::Vector3d theta_of(const SharedRobotError& e) {
  return {e.view_noise_scale, e.translation_sigma * e.translation_sigma, e.rotation_sigma * e.rotation_sigma};
}

/// The 6x6 blocks of C at samples a (rows) and b (columns); the 6-row blocks of M at a.
MatrixXd blocks(const MatrixXd& C, const std::vector<int>& a, const std::vector<int>& b) {
  MatrixXd out(6 * a.size(), 6 * b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    for (std::size_t j = 0; j < b.size(); ++j) out.block<6, 6>(6 * static_cast<long>(i), 6 * static_cast<long>(j)) = C.block<6, 6>(6 * a[i], 6 * b[j]);
  }
  return out;
}
MatrixXd rows_of(const MatrixXd& M, const std::vector<int>& a) {
  MatrixXd out(6 * a.size(), M.cols());
  for (std::size_t i = 0; i < a.size(); ++i) out.middleRows<6>(6 * static_cast<long>(i)) = M.middleRows<6>(6 * a[i]);
  return out;
}

HandEyeError singular_covariance() {
  return HandEyeError(ErrorCode::InvalidNoise,
                      "the residuals' covariance of the shared robot error model is not positive definite", "calibration",
                      "check the samples' stated noise; a model from fit_shared_robot_error of these samples is one");
}

/// The NEES of X's difference between the halves' GLS estimates under C, the
/// covariance of the difference with its cross-half terms.
double split_nees(const MatrixXd& C, const MatrixXd& J, const VectorXd& r, const std::array<std::vector<int>, 2>& halves) {
  MatrixXd G[2];
  Vector12d estimate[2];
  for (int h = 0; h < 2; ++h) {
    const std::vector<int>& half = halves[static_cast<std::size_t>(h)];
    const Eigen::LLT<MatrixXd> llt(blocks(C, half, half));
    if (llt.info() != Eigen::Success) throw singular_covariance();
    const MatrixXd Jh = rows_of(J, half);
    const MatrixXd CiJ = llt.solve(Jh);
    G[h] = (Jh.transpose() * CiJ).ldlt().solve(CiJ.transpose());
    estimate[h] = -G[h] * rows_of(r, half);  // the half's GLS step
  }
  const MatrixXd cross = G[0] * blocks(C, halves[0], halves[1]) * G[1].transpose();
  const MatrixXd V = G[0] * blocks(C, halves[0], halves[0]) * G[0].transpose() +
                     G[1] * blocks(C, halves[1], halves[1]) * G[1].transpose() - cross - cross.transpose();
  const Vector6d d = (estimate[0] - estimate[1]).head<6>();
  const Matrix6d Vx = V.topLeftCorner<6, 6>();
  return d.dot(Vx.ldlt().solve(d));
}

double mean_nees(const MatrixXd& C, const MatrixXd& J, const VectorXd& r, const std::vector<std::array<std::vector<int>, 2>>& splits,
                 std::size_t count) {
  count = std::min(count, splits.size());
  double sum = 0.0;
  for (std::size_t s = 0; s < count; ++s) sum += split_nees(C, J, r, splits[s]);
  return sum / static_cast<double>(count);
}

}  // namespace

SharedRobotErrorFit fit_shared_robot_error(const SampleSet& samples, const Calibration& calibration,
                                           const SharedRobotErrorOptions& options) {
  SharedRobotErrorFit fit;
  const Linearised L = linearise(samples, calibration, fit.used);
  const Parts per_view = make_parts(L, 0.0);
  const Reml at_model = evaluate(per_view, Eigen::Vector3d(1.0, 0.0, 0.0), L.J, L.r);
  if (!at_model.ok) {
    throw HandEyeError(ErrorCode::InvalidNoise, "a residual covariance of the calibration's noise model is singular",
                       "calibration", "check the samples' stated noise");
  }
  fit.per_view = describe(0.0, Eigen::Vector3d(1.0, 0.0, 0.0), at_model.log_likelihood);
  fit.best = fit.per_view;
  // The first length starts inside the region, from a shared error of 1 mm and
  // 0.006 degree per axis and the view scale a little below 1 (an eighth of the
  // per-view variance left for the shared part to take): Fisher scoring leaves a
  // bound slowly. Each next length starts where the last ended.
  Eigen::Vector3d start(0.875, 1e-6, 1e-8);
  const std::vector<double> none;
  for (double l : L.n >= options.min_samples && L.n <= options.max_samples ? options.length_scales : none) {
    const Parts parts = make_parts(L, l);
    double log_likelihood = 0.0;
    const Eigen::Vector3d theta = fit_theta(parts, start, L.J, L.r, options.max_iterations, &log_likelihood);
    fit.candidates.push_back(describe(l, theta, log_likelihood));
    if (std::isfinite(log_likelihood)) start = theta;  // the next length starts here
    if (log_likelihood > fit.best.log_likelihood) fit.best = fit.candidates.back();
  }
  fit.bic_gain = 2.0 * (fit.best.log_likelihood - fit.per_view.log_likelihood) - 4.0 * std::log(6.0 * L.n - 12.0);
  fit.chosen = fit.best.length_scale > 0.0 && fit.bic_gain > 0.0;
  const SharedRobotError& model = fit.chosen ? fit.best : fit.per_view;
  const MatrixXd C = combine(make_parts(L, model.length_scale), theta_of(model));
  const Eigen::LLT<MatrixXd> llt(C);
  const MatrixXd CiJ = llt.solve(L.J);
  const MatrixXd A = L.J.transpose() * CiJ;
  const MatrixXd covariance = A.inverse();
  const Vector12d step = fit.chosen ? Vector12d(-covariance * (CiJ.transpose() * L.r)) : Vector12d::Zero();
  {
    // The per-view estimate's error is H0 eps and the GLS one's -G eps (eps the
    // errors under C), so the step is (H0 + G) eps: its covariance under the model
    // is (H0 + G) C (H0 + G)^T, and H0 C H0^T is the per-view estimate's own.
    const Eigen::LLT<MatrixXd> per_view_llt(per_view.view);
    const MatrixXd SiJ = per_view_llt.solve(L.J);
    const MatrixXd H0 = (L.J.transpose() * SiJ).ldlt().solve(SiJ.transpose());
    const MatrixXd gain = H0 - covariance * CiJ.transpose();
    const Matrix6d move = (gain * C * gain.transpose()).topLeftCorner<6, 6>();
    fit.per_view_estimate_covariance = (H0 * C * H0.transpose()).topLeftCorner<6, 6>();
    const Vector6d x = step.head<6>();
    fit.step_nees = fit.chosen ? x.dot(move.ldlt().solve(x)) : 0.0;
  }
  auto moved = [](const Eigen::Isometry3d& T, const Vector6d& xi) {
    return se3::make_pose(so3::exp(xi.tail<3>()) * T.linear(), T.translation() + xi.head<3>());
  };
  fit.T_parent_camera = moved(calibration.T_parent_camera, step.head<6>());
  fit.pattern.pose = moved(calibration.pattern->pose, step.tail<6>());
  fit.pose_covariance = covariance.topLeftCorner<6, 6>();
  fit.pattern.covariance = covariance.bottomRightCorner<6, 6>();
  fit.cross_covariance = covariance.topRightCorner<6, 6>();
  return fit;
}

Calibration::SharedError shared_error_record(const SharedRobotErrorFit& fit) {
  Calibration::SharedError r;
  r.chosen = fit.chosen;
  r.bic_gain = fit.bic_gain;
  r.length_scale = fit.best.length_scale;
  r.translation_sigma = fit.best.translation_sigma;
  r.rotation_sigma = fit.best.rotation_sigma;
  r.view_noise_scale = fit.best.view_noise_scale;
  r.T_parent_camera = fit.T_parent_camera;
  r.pose_covariance = fit.pose_covariance;
  r.step_nees = fit.step_nees;
  r.per_view_estimate_covariance = fit.per_view_estimate_covariance;
  return r;
}

SharedRobotErrorCheck check_shared_robot_error(const SampleSet& samples, const Calibration& calibration,
                                               const SharedRobotError& model, const LinearCheckOptions& options) {
  if (options.splits < 1 || options.replicates < 1 || options.replicate_splits < 1 || options.run_length < 2) {
    throw HandEyeError(ErrorCode::TooFewMotions,
                       "the linearised split-half check needs splits, replicates and replicate_splits >= 1 and a run length >= 2",
                       "LinearCheckOptions", "use the defaults (200 splits, 40 replicates of 40 splits, runs of 3)");
  }
  std::vector<int> used;
  const Linearised L = linearise(samples, calibration, used);
  const Parts parts = make_parts(L, model.length_scale);
  const Eigen::Vector3d theta = theta_of(model);
  const MatrixXd C = combine(parts, theta);
  const Eigen::LLT<MatrixXd> factor(C);
  if (factor.info() != Eigen::Success) throw singular_covariance();
  const MatrixXd lower = factor.matrixL();
  SharedRobotErrorCheck check;
  const int looks[2] = {1, L.n >= min_samples_for_runs(options.run_length) ? options.run_length : 0};
  for (int look = 0; look < 2; ++look) {
    LinearSplitLook& out = look == 0 ? check.random : check.runs;
    out.run_length = looks[look];
    if (out.run_length == 0) continue;
    std::mt19937_64 rng(options.seed + static_cast<unsigned>(look));
    HalfSplitter splitter(L.n, out.run_length);
    std::vector<std::array<std::vector<int>, 2>> splits;
    for (int s = 0; s < options.splits; ++s) splits.push_back(splitter.next(rng));
    out.observed = mean_nees(C, L.J, L.r, splits, splits.size());
    std::mt19937_64 draw(options.seed + 101u * static_cast<unsigned>(look + 1));
    std::normal_distribution<double> normal(0.0, 1.0);
    std::vector<double> means;
    for (int b = 0; b < options.replicates; ++b) {
      VectorXd z(L.r.size());
      for (int k = 0; k < z.size(); ++k) z(k) = normal(draw);
      const VectorXd r = lower * z;
      double log_likelihood = 0.0;
      const Eigen::Vector3d refit = fit_theta(parts, theta, L.J, r, 50, &log_likelihood);
      if (!std::isfinite(log_likelihood)) continue;
      means.push_back(mean_nees(combine(parts, refit), L.J, r, splits, static_cast<std::size_t>(options.replicate_splits)));
    }
    if (means.empty()) continue;
    out.reference = std::accumulate(means.begin(), means.end(), 0.0) / static_cast<double>(means.size());
    out.low = linear_quantile(means, 0.05);
    out.high = linear_quantile(means, 0.95);
    out.ratio = out.observed / out.reference;
  }
  return check;
}

}  // namespace handeye
