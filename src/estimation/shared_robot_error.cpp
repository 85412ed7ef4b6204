#include "handeye_covariance/estimation/shared_robot_error.h"

#include <Eigen/Cholesky>
#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <random>

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/core/lie.h"
#include "handeye_covariance/core/units.h"
#include "handeye_covariance/estimation/joint_estimator.h"
#include "handeye_covariance/estimation/split_check.h"

namespace handeye {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;
using Vector12d = Eigen::Matrix<double, 12, 1>;
/// C's numbers: the scale s of the per-view S_i, the shared error's translation and
/// rotation variances a and b.
constexpr int kComponents = 3;
using Theta = Eigen::Vector3d;
constexpr double kFloor[kComponents] = {1e-6, 0.0, 0.0};

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

/// C's parts, theta's three numbers: the per-view S_i (block diagonal), and the
/// kernel's translation and rotation parts, k(p_i, p_j) D_i E D_j^T.
struct Parts {
  std::array<MatrixXd, kComponents> part;
  int components = 1;  // C's: the view part alone (1), or with the kernel's two (3)
  const MatrixXd& view() const { return part[0]; }
  /// The kernel's parts in factors, part a = B_a (K x I3) B_a^T, B_a block diagonal with
  /// D_i's translation (a = 1) or rotation (a = 2) columns: what evaluate multiplies by.
  std::vector<Matrix6d> D;
  MatrixXd K;  // k(p_i, p_j), n x n
};

Parts make_parts(const Linearised& L, double length_scale) {
  Parts P;
  const int m = 6 * L.n;
  P.part[0] = MatrixXd::Zero(m, m);
  for (int i = 0; i < L.n; ++i) P.part[0].block<6, 6>(6 * i, 6 * i) = L.S[static_cast<std::size_t>(i)];
  if (length_scale <= 0.0) return P;
  P.part[1] = MatrixXd::Zero(m, m);
  P.part[2] = MatrixXd::Zero(m, m);
  P.D = L.D;
  P.K.resize(L.n, L.n);
  for (int i = 0; i < L.n; ++i) {
    for (int j = 0; j < L.n; ++j) {
      const double k = shared_error_kernel(L.position[static_cast<std::size_t>(i)], L.position[static_cast<std::size_t>(j)],
                                           length_scale);
      P.K(i, j) = k;
      const Matrix6d& Di = L.D[static_cast<std::size_t>(i)];
      const Matrix6d& Dj = L.D[static_cast<std::size_t>(j)];
      P.part[1].block<6, 6>(6 * i, 6 * j) = k * Di.leftCols<3>() * Dj.leftCols<3>().transpose();
      P.part[2].block<6, 6>(6 * i, 6 * j) = k * Di.rightCols<3>() * Dj.rightCols<3>().transpose();
    }
  }
  P.components = 3;
  return P;
}

MatrixXd combine(const Parts& P, const Theta& theta) {
  MatrixXd C = MatrixXd::Zero(P.part[0].rows(), P.part[0].cols());
  for (int c = 0; c < P.components; ++c) C += theta(c) * P.part[static_cast<std::size_t>(c)];
  return C;
}

/// The restricted log-likelihood at theta, its score and expected information.
struct Reml {
  bool ok = false;
  double log_likelihood = 0.0;
  Theta score = Theta::Zero();
  Eigen::Matrix3d information = Eigen::Matrix3d::Identity();
};

Reml evaluate(const Parts& P, const Theta& theta, const MatrixXd& J, const VectorXd& r) {
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
  std::array<MatrixXd, kComponents> PC;
  for (int a = 0; a < P.components; ++a) {
    const MatrixXd& Ca = P.part[static_cast<std::size_t>(a)];
    MatrixXd& PCa = PC[static_cast<std::size_t>(a)];
    if (a == 0) {  // the view part is block diagonal: P C_0 and C_0 Pr a block at a time, not m^3
      const Eigen::Index m = Ca.rows();
      PCa.resize(m, m);
      VectorXd CPr(m);
      for (Eigen::Index i = 0; i < m; i += 6) {
        const Matrix6d block = Ca.block<6, 6>(i, i);
        PCa.middleCols<6>(i).noalias() = Pm.middleCols<6>(i) * block;
        CPr.segment<6>(i).noalias() = block * Pr.segment<6>(i);
      }
      out.score(a) = 0.5 * (Pr.dot(CPr) - PCa.trace());
    } else {  // a kernel part: P C_a = ((P B_a)(K x I3)) B_a^T, m^3 / 12 instead of m^3
      const Eigen::Index m = Ca.rows(), n = P.K.rows();
      const Eigen::Index first = a == 1 ? 0 : 3;  // D_i's translation or rotation columns
      MatrixXd PB(m, 3 * n), PBK(m, 3 * n);
      for (Eigen::Index i = 0; i < n; ++i) {
        PB.middleCols<3>(3 * i).noalias() = Pm.middleCols<6>(6 * i) * P.D[static_cast<std::size_t>(i)].middleCols<3>(first);
      }
      using Columns = Eigen::OuterStride<>;  // every third column: one axis of every view
      for (Eigen::Index axis = 0; axis < 3; ++axis) {
        const Eigen::Map<const MatrixXd, 0, Columns> in(PB.data() + axis * m, m, n, Columns(3 * m));
        Eigen::Map<MatrixXd, 0, Columns> product(PBK.data() + axis * m, m, n, Columns(3 * m));
        product.noalias() = in * P.K;
      }
      PCa.resize(m, m);
      for (Eigen::Index j = 0; j < n; ++j) {
        PCa.middleCols<6>(6 * j).noalias() =
            PBK.middleCols<3>(3 * j) * P.D[static_cast<std::size_t>(j)].middleCols<3>(first).transpose();
      }
      out.score(a) = 0.5 * (Pr.dot(Ca * Pr) - PCa.trace());
    }
  }
  for (int a = 0; a < P.components; ++a) {
    for (int b = 0; b < P.components; ++b) {
      // tr(P C_a P C_b) = sum_ij (P C_a)_ij (P C_b)_ji
      out.information(a, b) = 0.5 * PC[static_cast<std::size_t>(a)].cwiseProduct(PC[static_cast<std::size_t>(b)].transpose()).sum();
    }
  }
  out.ok = true;
  return out;
}

/// Fisher scoring from `theta` within theta >= 0 (the view scale >= 1e-6): a
/// component at its bound whose score points out of the region stays there; a step
/// is halved until the likelihood does not fall. Only P's components move.
Theta fit_theta(const Parts& P, Theta theta, const MatrixXd& J, const VectorXd& r, int max_iterations, double* log_likelihood) {
  const int k = P.components;
  Reml at = evaluate(P, theta, J, r);
  if (!at.ok) {
    *log_likelihood = -std::numeric_limits<double>::infinity();
    return theta;
  }
  for (int it = 0; it < max_iterations; ++it) {
    Eigen::MatrixXd F = at.information.topLeftCorner(k, k);
    Eigen::VectorXd g = at.score.head(k);
    for (int x = 0; x < k; ++x) {
      if (theta(x) <= kFloor[x] && g(x) < 0.0) {  // held at its bound
        g(x) = 0.0;
        F.row(x).setZero(), F.col(x).setZero(), F(x, x) = 1.0;
      }
    }
    const Eigen::VectorXd step = F.ldlt().solve(g);
    double t = 1.0;
    bool moved = false;
    for (int halving = 0; halving < 30; ++halving, t *= 0.5) {
      Theta candidate = theta;
      for (int x = 0; x < k; ++x) candidate(x) = std::max(kFloor[x], theta(x) + t * step(x));
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

SharedRobotError describe(double length_scale, const Theta& theta, double log_likelihood) {
  SharedRobotError e;
  e.length_scale = length_scale;
  e.view_noise_scale = theta(0);
  e.translation_sigma = std::sqrt(std::max(theta(1), 0.0));
  e.rotation_sigma = std::sqrt(std::max(theta(2), 0.0));
  e.log_likelihood = log_likelihood;
  return e;
}

Theta theta_of(const SharedRobotError& e) {
  return {e.view_noise_scale, e.translation_sigma * e.translation_sigma, e.rotation_sigma * e.rotation_sigma};
}

/// The GLS covariance with the fitted (s, a, b)'s own error, as Kenward and Roger
/// (1997, Biometrics 53: 983) adjust it for a covariance linear in its numbers:
///   Phi_A = Phi + 2 Phi [sum_kl W_kl (Q_kl - P_k Phi P_l)] Phi,
///   Phi = (J^T C^-1 J)^-1,  P_k = -J^T C^-1 C_k C^-1 J,  Q_kl = J^T C^-1 C_k C^-1 C_l C^-1 J,
/// W the inverse of the REML expected information over the numbers off their bound
/// (a number held at 0 is not estimated from the data's spread). The length l is
/// taken as known (chosen from a grid, not estimated continuously).
MatrixXd kenward_roger(const Parts& P, const Theta& theta, const MatrixXd& J, const VectorXd& r,
                       const Eigen::LLT<MatrixXd>& llt, const MatrixXd& CiJ, const MatrixXd& Phi) {
  const Reml at = evaluate(P, theta, J, r);
  if (!at.ok) return Phi;
  std::vector<int> active;
  for (int k = 0; k < P.components; ++k) {
    if (theta(k) > kFloor[k]) active.push_back(k);
  }
  if (active.empty()) return Phi;
  const int m = static_cast<int>(active.size());
  MatrixXd I(m, m);
  for (int x = 0; x < m; ++x) {
    for (int y = 0; y < m; ++y) I(x, y) = at.information(active[static_cast<std::size_t>(x)], active[static_cast<std::size_t>(y)]);
  }
  const Eigen::LDLT<MatrixXd> information(I);
  if (information.info() != Eigen::Success || !information.isPositive() || information.rcond() < 1e-12) return Phi;
  const MatrixXd W = information.solve(MatrixXd::Identity(m, m));
  std::vector<MatrixXd> U, CiU, Pk;  // U_k = C_k C^-1 J
  for (int k : active) {
    U.push_back(P.part[static_cast<std::size_t>(k)] * CiJ);
    CiU.push_back(llt.solve(U.back()));
    Pk.push_back(-CiJ.transpose() * U.back());
  }
  MatrixXd Lambda = MatrixXd::Zero(Phi.rows(), Phi.cols());
  for (int x = 0; x < m; ++x) {
    for (int y = 0; y < m; ++y) {
      const MatrixXd Q = U[static_cast<std::size_t>(x)].transpose() * CiU[static_cast<std::size_t>(y)];
      Lambda += W(x, y) * (Q - Pk[static_cast<std::size_t>(x)] * Phi * Pk[static_cast<std::size_t>(y)]);
    }
  }
  MatrixXd adjusted = Phi + 2.0 * Phi * Lambda * Phi;
  return 0.5 * (adjusted + adjusted.transpose());
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

/// One split of the linearised check: X's difference between the halves' estimates,
/// each the weighted least-squares step under W's blocks (W = C: the GLS estimate;
/// W = the per-view S_i: the calibration's own), judged under C with the cross-half
/// terms. Adds the split to `check` (its NEES, difference and 1 sigma per axis).
void add_split(const MatrixXd& C, const MatrixXd& W, const MatrixXd& J, const VectorXd& r,
               const std::array<std::vector<int>, 2>& halves, SplitCheck& check) {
  MatrixXd G[2];
  Vector12d estimate[2];
  for (int h = 0; h < 2; ++h) {
    const std::vector<int>& half = halves[static_cast<std::size_t>(h)];
    const Eigen::LLT<MatrixXd> llt(blocks(W, half, half));
    if (llt.info() != Eigen::Success) throw singular_covariance();
    const MatrixXd Jh = rows_of(J, half);
    const MatrixXd WiJ = llt.solve(Jh);
    G[h] = (Jh.transpose() * WiJ).ldlt().solve(WiJ.transpose());
    estimate[h] = -G[h] * rows_of(r, half);  // the half's step
  }
  const MatrixXd cross = G[0] * blocks(C, halves[0], halves[1]) * G[1].transpose();
  const MatrixXd V = G[0] * blocks(C, halves[0], halves[0]) * G[0].transpose() +
                     G[1] * blocks(C, halves[1], halves[1]) * G[1].transpose() - cross - cross.transpose();
  const Vector6d d = (estimate[0] - estimate[1]).head<6>();
  const Matrix6d Vx = V.topLeftCorner<6, 6>();
  check.nees.push_back(d.dot(Vx.ldlt().solve(d)));
  check.differences.push_back(d);
  check.difference_sigmas.push_back(Vx.diagonal().cwiseMax(0.0).cwiseSqrt());
  check.mean_nees_translation += d.head<3>().dot(Vx.topLeftCorner<3, 3>().ldlt().solve(d.head<3>()));
  check.mean_nees_rotation += d.tail<3>().dot(Vx.bottomRightCorner<3, 3>().ldlt().solve(d.tail<3>()));
  check.half_size = std::min(check.half_size, static_cast<int>(std::min(halves[0].size(), halves[1].size())));
}

/// The split check of residuals r under C (estimator weights W) over the first
/// `count` of `splits`.
SplitCheck linear_split_check(const MatrixXd& C, const MatrixXd& W, const MatrixXd& J, const VectorXd& r, int run_length,
                              const std::vector<std::array<std::vector<int>, 2>>& splits, std::size_t count) {
  SplitCheck check;
  check.run_length = run_length;
  check.half_size = static_cast<int>(r.size() / 12);
  for (std::size_t s = 0; s < std::min(count, splits.size()); ++s) add_split(C, W, J, r, splits[s], check);
  summarise_splits(check);
  return check;
}

}  // namespace

SharedRobotErrorFit fit_shared_robot_error(const SampleSet& samples, const Calibration& calibration,
                                           const SharedRobotErrorOptions& options) {
  SharedRobotErrorFit fit;
  const Linearised L = linearise(samples, calibration, fit.used);
  const Parts per_view = make_parts(L, 0.0);
  const Theta unit(1.0, 0.0, 0.0);  // the calibration's own model
  const Reml at_model = evaluate(per_view, unit, L.J, L.r);
  if (!at_model.ok) {
    throw HandEyeError(ErrorCode::InvalidNoise, "a residual covariance of the calibration's noise model is singular",
                       "calibration", "check the samples' stated noise");
  }
  fit.per_view = describe(0.0, unit, at_model.log_likelihood);
  fit.best = fit.per_view;
  // The first length starts inside the region, from a shared error of 1 mm and
  // 0.006 degree per axis and the view scale a little below 1 (an eighth of the
  // per-view variance left for the shared part to take): Fisher scoring leaves a
  // bound slowly. Each next length starts where the last ended.
  Theta start(0.875, 1e-6, 1e-8);
  const std::vector<double> none;
  const bool fitted = !options.model && L.n >= options.min_samples && L.n <= options.max_samples;
  for (double l : fitted ? options.length_scales : none) {
    const Parts parts = make_parts(L, l);
    double log_likelihood = 0.0;
    const Theta theta = fit_theta(parts, start, L.J, L.r, options.max_iterations, &log_likelihood);
    fit.candidates.push_back(describe(l, theta, log_likelihood));
    if (std::isfinite(log_likelihood)) start = theta;  // the next length starts here
    if (log_likelihood > fit.best.log_likelihood) fit.best = fit.candidates.back();
  }
  if (options.model) {
    fit.best = *options.model;
    fit.chosen = fit.best.length_scale > 0.0;
  } else {
    fit.bic_gain = 2.0 * (fit.best.log_likelihood - fit.per_view.log_likelihood) - 4.0 * std::log(6.0 * L.n - 12.0);
    fit.chosen = fit.best.length_scale > 0.0 && fit.bic_gain > 0.0;
  }
  const SharedRobotError& model = fit.chosen ? fit.best : fit.per_view;
  const Parts model_parts = make_parts(L, model.length_scale);
  const MatrixXd C = combine(model_parts, theta_of(model));
  const Eigen::LLT<MatrixXd> llt(C);
  const MatrixXd CiJ = llt.solve(L.J);
  const MatrixXd A = L.J.transpose() * CiJ;
  const MatrixXd information_inverse = A.inverse();
  const Vector12d step = fit.chosen ? Vector12d(-information_inverse * (CiJ.transpose() * L.r)) : Vector12d::Zero();
  // (J^T C^-1 J)^-1 takes C as known; (s, a, b) were fitted from these residuals.
  const MatrixXd covariance =
      fit.chosen ? kenward_roger(model_parts, theta_of(model), L.J, L.r, llt, CiJ, information_inverse)
                 : information_inverse;
  if (fit.chosen) {  // their mean effect, tr(Phi^-1 Phi_A) / 6 on X's block and on Y's
    fit.covariance_inflation = information_inverse.topLeftCorner<6, 6>().ldlt().solve(covariance.topLeftCorner<6, 6>()).trace() / 6.0;
    fit.pattern_covariance_inflation =
        information_inverse.bottomRightCorner<6, 6>().ldlt().solve(covariance.bottomRightCorner<6, 6>()).trace() / 6.0;
  }
  {
    // The per-view estimate's error is -H0 eps and the GLS one's -G eps (eps the
    // errors under C, G = Phi J^T C^-1), so the step from one to the other is
    // (H0 - G) eps: its covariance under the model is (H0 - G) C (H0 - G)^T, and
    // H0 C H0^T is the per-view estimate's own.
    const Eigen::LLT<MatrixXd> per_view_llt(per_view.view());
    const MatrixXd SiJ = per_view_llt.solve(L.J);
    const MatrixXd H0 = (L.J.transpose() * SiJ).ldlt().solve(SiJ.transpose());
    const MatrixXd gain = H0 - information_inverse * CiJ.transpose();
    const Matrix6d move = (gain * C * gain.transpose()).topLeftCorner<6, 6>();
    const MatrixXd under_model = H0 * C * H0.transpose();
    fit.per_view_estimate_covariance = under_model.topLeftCorner<6, 6>();
    fit.per_view_estimate_pattern_covariance = under_model.bottomRightCorner<6, 6>();
    fit.per_view_estimate_cross_covariance = under_model.topRightCorner<6, 6>();
    for (int j = 0; j < L.n; ++j) {
      Calibration::SharedError::View v;
      v.position = L.position[static_cast<std::size_t>(j)];
      v.gain = H0.middleCols<6>(6 * j) * L.D[static_cast<std::size_t>(j)];
      fit.views.push_back(v);
    }
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

Calibration per_view_calibration(const Calibration& calibration) {
  if (!calibration.shared_robot_error || !calibration.shared_robot_error->used || !calibration.pattern) return calibration;
  const Calibration::SharedError& e = *calibration.shared_robot_error;
  Calibration c = calibration;
  c.T_parent_camera = e.per_view_X.pose;
  set_pose_covariance(c, e.per_view_X.covariance);
  c.pattern->pose = e.per_view_pattern.pose;
  c.pattern->covariance = e.per_view_pattern.covariance;
  c.cross_covariance = e.per_view_cross_covariance;
  c.covariance_kind = CovarianceKind::Information;
  c.covariance_inflation = e.per_view_covariance_inflation;
  c.pattern_covariance_inflation = e.per_view_pattern_covariance_inflation;
  c.warnings.clear();  // the model's (its check's inflation among them)
  c.shared_robot_error->used = false;
  // Its own honesty check: the verdict it gave and its inflation, as record_honesty applies it.
  Calibration::Honesty h;
  h.inflation = e.per_view_inflation;
  h.model_pose_covariance = e.per_view_X.covariance;
  h.verdict = e.per_view_honesty.empty() ? Honesty::NotRun : e.per_view_inflation > 1.0 ? Honesty::Overconfident : Honesty::Honest;
  h.text = e.per_view_honesty.empty() ? "the per-view model was not checked" : e.per_view_honesty;
  c.honesty = h;
  if (e.per_view_inflation > 1.0) scale_covariances(c, e.per_view_inflation);
  return c;
}

double shared_error_kernel(const Eigen::Vector3d& p, const Eigen::Vector3d& q, double length_scale) {
  const double d = (p - q).norm();
  return std::exp(-d * d / (2.0 * length_scale * length_scale));
}

Matrix6d shared_error_covariance(const SharedRobotError& model) {
  Matrix6d E = Matrix6d::Zero();
  E.topLeftCorner<3, 3>().diagonal().setConstant(model.translation_sigma * model.translation_sigma);
  E.bottomRightCorner<3, 3>().diagonal().setConstant(model.rotation_sigma * model.rotation_sigma);
  return E;
}

SharedRobotError model_of(const Calibration::SharedError& record) {
  SharedRobotError model;
  model.length_scale = record.length_scale;
  model.view_noise_scale = record.view_noise_scale;
  model.translation_sigma = record.translation_sigma;
  model.rotation_sigma = record.rotation_sigma;
  return model;
}

void require_predictable(const Calibration::SharedError& record, const std::string& where) {
  if (record.length_scale > 0.0 && record.view_noise_scale > 0.0 && record.translation_sigma >= 0.0 &&
      record.rotation_sigma >= 0.0) {
    return;
  }
  throw HandEyeError(ErrorCode::MalformedFile,
                     "the shared robot error needs a length_scale and a view_noise_scale above 0 and no negative "
                     "sigma to predict new views; it has " + number_text(record.length_scale) + " m, " +
                         number_text(record.view_noise_scale) + ", " + number_text(record.translation_sigma) + " m and " +
                         number_text(record.rotation_sigma) + " rad",
                     where, "write the numbers its fit gave (metres, radians), or save the calibration again with this version");
}

Matrix12d per_view_estimate_joint_covariance(const Calibration::SharedError& record) {
  Matrix12d P;
  P << record.per_view_estimate_covariance, record.per_view_estimate_cross_covariance,
      record.per_view_estimate_cross_covariance.transpose(), record.per_view_estimate_pattern_covariance;
  return P;
}

void use_shared_robot_error(Calibration& c, const SharedRobotErrorFit& fit) {
  if (!fit.chosen || !c.shared_robot_error || !c.pattern) {
    throw HandEyeError(ErrorCode::InvalidNoise,
                       "the shared robot error can only be used where its fit chose it, on a joint calibration that "
                       "records it", "calibration", "use it only when fit_shared_robot_error says chosen");
  }
  Calibration::SharedError& record = *c.shared_robot_error;
  record.used = true;
  record.per_view_X.pose = c.T_parent_camera;
  record.per_view_X.covariance = c.pose_covariance;
  record.per_view_pattern.pose = c.pattern->pose;
  record.per_view_pattern.covariance = c.pattern->covariance;
  record.per_view_cross_covariance = c.cross_covariance;
  record.per_view_covariance_inflation = c.covariance_inflation;
  record.per_view_pattern_covariance_inflation = c.pattern_covariance_inflation;
  c.T_parent_camera = fit.T_parent_camera;
  set_pose_covariance(c, fit.pose_covariance);
  c.cross_covariance = fit.cross_covariance;
  c.pattern->pose = fit.pattern.pose;
  c.pattern->covariance = fit.pattern.covariance;
  c.covariance_kind = CovarianceKind::SharedRobotError;
  c.covariance_inflation = fit.covariance_inflation;
  c.pattern_covariance_inflation = fit.pattern_covariance_inflation;
}

Calibration::SharedError shared_error_record(const SharedRobotErrorFit& fit) {
  Calibration::SharedError r;
  r.chosen = fit.chosen;
  r.bic_gain = fit.bic_gain;
  r.given = fit.candidates.empty();
  r.length_scale = fit.best.length_scale;
  r.translation_sigma = fit.best.translation_sigma;
  r.rotation_sigma = fit.best.rotation_sigma;
  r.view_noise_scale = fit.best.view_noise_scale;
  r.covariance_inflation = fit.covariance_inflation;
  r.X = {fit.T_parent_camera, fit.pose_covariance};
  r.step_nees = fit.step_nees;
  r.per_view_estimate_covariance = fit.per_view_estimate_covariance;
  r.per_view_estimate_pattern_covariance = fit.per_view_estimate_pattern_covariance;
  r.per_view_estimate_cross_covariance = fit.per_view_estimate_cross_covariance;
  r.views = fit.views;
  return r;
}

HonestyCheck check_shared_robot_error(const SampleSet& samples, const Calibration& calibration, const SharedRobotError& model,
                                      const HonestyOptions& options, SharedErrorEstimator estimator) {
  if (options.splits < 1 || options.replicates < 2 || options.replicate_splits < 1) {
    throw HandEyeError(ErrorCode::TooFewMotions,
                       "the linearised split-half check needs splits >= 1, replicates >= 2 and replicate_splits >= 1",
                       "HonestyOptions", "use the defaults (200 splits, 100 simulated sessions of 40 splits)");
  }
  std::vector<int> used;
  const Linearised L = linearise(samples, calibration, used);
  const Parts parts = make_parts(L, model.length_scale);
  const Theta theta = theta_of(model);
  const MatrixXd C = combine(parts, theta);
  const Eigen::LLT<MatrixXd> factor(C);
  if (factor.info() != Eigen::Success) throw singular_covariance();
  // The halves' estimator: the calibration's own (weights S_i; their scale s does not
  // change the estimate), or the GLS one under the model.
  const MatrixXd& view = parts.view();
  const auto weights = [&](const MatrixXd& covariance) -> const MatrixXd& {
    return estimator == SharedErrorEstimator::PerView ? view : covariance;
  };
  // The session's halves, both looks, as honesty_check draws them.
  std::string why_not;
  const int k = runs_length_for(options, L.n, &why_not);
  const int looks = k == 0 ? 1 : 2;
  std::vector<std::array<std::vector<int>, 2>> splits[2];
  for (int look = 0; look < looks; ++look) {
    std::mt19937_64 rng(options.seed);
    HalfSplitter splitter(L.n, look == 0 ? 1 : k);
    for (int s = 0; s < options.splits; ++s) splits[look].push_back(splitter.next(rng));
  }
  const std::size_t replicate_splits[2] = {
      static_cast<std::size_t>(std::min(options.splits, options.replicate_splits)),
      static_cast<std::size_t>(std::min(options.splits, std::max(20, options.replicate_splits / 2)))};
  // The bootstrap sessions, once for both looks: r* ~ N(0, C) at the session's J,
  // (s, a, b) fitted again at the model's length as the session's own fit was.
  const MatrixXd lower = factor.matrixL();
  std::mt19937_64 draw(options.seed ^ 0x5eed5eedULL);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<SplitCheck> replicates[2];
  int failed = 0;
  for (int b = 0; b < options.replicates; ++b) {
    VectorXd z(L.r.size());
    for (int i = 0; i < z.size(); ++i) z(i) = normal(draw);
    const VectorXd r = lower * z;
    double log_likelihood = 0.0;
    const Theta refit = fit_theta(parts, theta, L.J, r, 50, &log_likelihood);
    if (!std::isfinite(log_likelihood)) {
      ++failed;
      continue;
    }
    const MatrixXd Cb = combine(parts, refit);
    for (int look = 0; look < looks; ++look) {
      replicates[look].push_back(linear_split_check(Cb, weights(Cb), L.J, r, look == 0 ? 1 : k, splits[look],
                                                    replicate_splits[look]));
    }
  }
  HonestyCheck look[2];
  for (int l = 0; l < looks; ++l) {
    const SplitCheck observed = linear_split_check(C, weights(C), L.J, L.r, l == 0 ? 1 : k, splits[l], splits[l].size());
    look[l] = judge_look(observed, replicates[l], failed, static_cast<int>(replicate_splits[l]));
  }
  HonestyCheck check = worse_look(look[0], looks == 2 ? &look[1] : nullptr, looks == 2 ? k : 0);
  if (looks == 1) check.runs_note = why_not;
  return check;
}

}  // namespace handeye
