#include "handeye_covariance/estimation/joint_estimator.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>

#include "handeye_covariance/core/statistics.h"
#include "handeye_covariance/core/units.h"
#include "handeye_covariance/core/validation.h"
#include "handeye_covariance/core/view_noise.h"
#include "handeye_covariance/estimation/variance_components.h"

namespace handeye {

using Eigen::Isometry3d;
using Eigen::Matrix3d;
using Eigen::Vector3d;
using Vector12d = Eigen::Matrix<double, 12, 1>;
using Matrix6x12 = Eigen::Matrix<double, 6, 12>;

namespace {

/// One sample, as the solver needs it: the robot's link V in the loop, the view
/// P, and the stated noise (zero when none). Kept small, since every pass over
/// 10^4 samples streams through them: rotations and translations without the
/// Isometry's fourth row, no stored dV/dE (Rig::robot_link_jacobian: I eye-to-hand,
/// the inverse's Jacobian of E = V^-1 eye-in-hand, which linearize writes out from V),
/// and the noise as pointers into its Terms' storage (most samples share the global one).
struct Term {
  Term() {}  // user-provided: a vector of 10^4 terms is not zero-filled before it is written
  Matrix3d RV, RP;
  Vector3d tV, tP;
  bool link_is_inverse = false;  // Rig::link_is_inverse, kept per term for the hot loop
  bool has_robot = false;
  const Matrix6d* camera_noise = nullptr;
  const Matrix6d* robot_noise = nullptr;
  const Matrix6d* view_shape = nullptr;  // the view's planar-target shape, when the noise model has one (view_noise.h)
  const Matrix6d& camera() const { return *camera_noise; }
  const Matrix6d& robot() const { return *robot_noise; }
};

Term make_term(const Rig& rig, const PoseSample& sample) {
  Term t;
  const Isometry3d V = rig.robot_link(sample.T_base_effector);
  t.RV = V.linear(), t.tV = V.translation();
  t.RP = sample.T_camera_pattern.linear(), t.tP = sample.T_camera_pattern.translation();
  t.link_is_inverse = rig.link_is_inverse();
  return t;
}

/// The terms and the noise matrices they point to (reserved up front, so the
/// pointers stay valid; moving the vector keeps its buffer).
struct Terms {
  std::vector<Term> terms;
  std::vector<Matrix6d> noises;
};

/// X and Y as the residuals use them.
struct Frame {
  Matrix3d RXt, RY;
  Vector3d tX, tY;
  explicit Frame(const Isometry3d& X, const Isometry3d& Y)
      : RXt(X.linear().transpose()), RY(Y.linear()), tX(X.translation()), tY(Y.translation()) {}
};

struct Linear {
  Vector6d e;
  Matrix6x12 J;
  Matrix6d D = Matrix6d::Zero();  // d P_hat / d xi_E (only when a robot noise enters)
};

/// e = (t_P - t_hat, log(R_P R_hat^T)) with P_hat = X^-1 V Y.
Vector6d residual(const Term& t, const Frame& f) {
  const Vector3d t_hat = f.RXt * (t.RV * f.tY + t.tV - f.tX);
  const Matrix3d R_hat = f.RXt * t.RV * f.RY;
  Vector6d e;
  e << t.tP - t_hat, so3::log(t.RP * R_hat.transpose());
  return e;
}

/// The residual and its Jacobians, written out (left perturbations, ROS order):
///   d P_hat / d xi_X = [[-RX^T, RX^T [t_VY - t_X]x], [0, -RX^T]],
///   d P_hat / d xi_Y = diag(RX^T RV, RX^T RV),
///   d P_hat / d xi_E = diag(RX^T, RX^T) [[I, -[RV t_Y]x], [0, I]] dV/dE,
/// with dV/dE = I eye-to-hand (V = E) and [[-RV, [t_V]x RV], [0, -RV]] eye-in-hand
/// (V = E^-1), where the product is [[-RX^T RV, RX^T [t_VY]x RV], [0, -RX^T RV]];
/// e's sensitivity to P_hat is -I for t and -J_r^-1(phi) for R
/// (log(exp(phi) exp(-d)) = phi - J_r^-1(phi) d). Checked numerically in test_joint_estimator.
void linearize(const Term& t, const Frame& f, Linear& out, bool with_robot = true) {
  const Matrix3d& RV = t.RV;
  const Vector3d RV_tY = RV * f.tY;
  const Vector3d t_VY = RV_tY + t.tV;
  const Matrix3d RXt_RV = f.RXt * RV;
  const Vector3d t_hat = f.RXt * (t_VY - f.tX);
  const Matrix3d R_hat = RXt_RV * f.RY;
  const Vector3d phi = so3::log(t.RP * R_hat.transpose());
  out.e << t.tP - t_hat, phi;
  const Matrix3d Jr_inverse = so3::left_jacobian_inverse(-phi);
  out.J.setZero();
  out.J.block<3, 3>(0, 0) = f.RXt;
  out.J.block<3, 3>(0, 3) = -f.RXt * so3::hat(t_VY - f.tX);
  out.J.block<3, 3>(3, 3) = Jr_inverse * f.RXt;
  out.J.block<3, 3>(0, 6) = -RXt_RV;
  out.J.block<3, 3>(3, 9) = -Jr_inverse * RXt_RV;
  if (!with_robot) return;
  out.D.bottomLeftCorner<3, 3>().setZero();
  if (t.link_is_inverse) {
    out.D.topLeftCorner<3, 3>() = -RXt_RV;
    out.D.topRightCorner<3, 3>().noalias() = f.RXt * so3::hat(t_VY) * RV;
    out.D.bottomRightCorner<3, 3>() = -RXt_RV;
  } else {
    out.D.topLeftCorner<3, 3>() = f.RXt;
    out.D.topRightCorner<3, 3>().noalias() = -f.RXt * so3::hat(RV_tY);
    out.D.bottomRightCorner<3, 3>() = f.RXt;
  }
}

/// Jw = L^-1 J by 3x3 blocks: L^-1 is lower triangular and J (linearize) is
/// [[T1, T2, T3, 0], [0, R2, 0, R4]], so seven 3x3 products instead of a 6x6 by 6x12.
void whiten(const Matrix6d& L_inverse, const Matrix6x12& J, Matrix6x12& Jw) {
  const Matrix3d P = L_inverse.topLeftCorner<3, 3>(), Q = L_inverse.bottomLeftCorner<3, 3>(),
                 R = L_inverse.bottomRightCorner<3, 3>();
  const auto T = [&](int column) { return J.block<3, 3>(0, column); };
  const auto B = [&](int column) { return J.block<3, 3>(3, column); };
  Jw.block<3, 3>(0, 0).noalias() = P * T(0);
  Jw.block<3, 3>(0, 3).noalias() = P * T(3);
  Jw.block<3, 3>(0, 6).noalias() = P * T(6);
  Jw.block<3, 3>(0, 9).setZero();
  Jw.block<3, 3>(3, 0).noalias() = Q * T(0);
  Jw.block<3, 3>(3, 3).noalias() = Q * T(3) + R * B(3);
  Jw.block<3, 3>(3, 6).noalias() = Q * T(6);
  Jw.block<3, 3>(3, 9).noalias() = R * B(9);
}

/// J Sigma J^T for J of linearize's shape [[T1, T2, T3, 0], [0, R2, 0, R4]] (3x3
/// blocks): the zero blocks skipped, about half the products of a dense 6x12.
Matrix6d projected_covariance(const Matrix6x12& J, const Matrix12d& Sigma) {
  Matrix6x12 JS;
  JS.topRows<3>().noalias() = J.block<3, 9>(0, 0).lazyProduct(Sigma.topRows<9>());
  JS.bottomRows<3>().noalias() = J.block<3, 3>(3, 3).lazyProduct(Sigma.middleRows<3>(3));
  JS.bottomRows<3>().noalias() += J.block<3, 3>(3, 9).lazyProduct(Sigma.bottomRows<3>());
  Matrix6d out;
  out.leftCols<3>().noalias() = JS.leftCols<9>().lazyProduct(J.block<3, 9>(0, 0).transpose());
  out.rightCols<3>().noalias() = JS.middleCols<3>(3).lazyProduct(J.block<3, 3>(3, 3).transpose());
  out.rightCols<3>().noalias() += JS.rightCols<3>().lazyProduct(J.block<3, 3>(3, 9).transpose());
  return out;
}

/// Whether a step (X then Y, each translation then rotation) is large enough to
/// move the robot's share of S_i: more than 0.01 rad or 1 cm on either pose.
bool moves_weights(const Vector12d& step) {
  return std::max(step.segment<3>(3).norm(), step.segment<3>(9).norm()) > 1e-2 ||
         std::max(step.segment<3>(0).norm(), step.segment<3>(6).norm()) > 1e-2;
}

Isometry3d apply(const Isometry3d& T, const Vector6d& d) {
  return se3::make_pose(so3::exp(d.tail<3>()) * T.linear(), T.translation() + d.head<3>());
}

/// The noise model: S_i = scale Sigma_P,i + camera + view G_i + D_i (Sigma_E,i + robot) D_i^T.
struct NoiseModel {
  double camera_scale = 1.0;
  double view_scale = 0.0;  // times the view's shape G_i (Term::view_shape)
  Matrix6d camera = Matrix6d::Zero();
  Matrix6d robot = Matrix6d::Zero();  // written through set_robot
  bool robot_free_or_given = false;  // D_i enters S_i

  Matrix6d covariance(const Term& t, const Matrix6d& D) const {
    Matrix6d S = camera_scale * t.camera() + camera;
    if (view_scale != 0.0) S.noalias() += view_scale * *t.view_shape;
    if (!robot_free_or_given) return S;
    if (t.has_robot || robot_part == RobotPart::Full) {
      const Matrix6d D_robot = D * (t.robot() + robot);  // evaluated once: a nested lazy product recomputes it per entry
      S.noalias() += D_robot * D.transpose();
    } else if (robot_part == RobotPart::Rotation) {  // the fitted robot noise: D's rotation columns only
      const Eigen::Matrix<double, 6, 3> D_robot = D.rightCols<3>() * robot.bottomRightCorner<3, 3>();
      S.noalias() += D_robot * D.rightCols<3>().transpose();
    }
    return S;
  }
  /// Which part of `robot` is non-zero, read once rather than per sample.
  enum class RobotPart { None, Rotation, Full } robot_part = RobotPart::None;
  void set_robot(const Matrix6d& r) {
    robot = r;
    robot_part = r.isZero(0.0) ? RobotPart::None
                 : (r.topRows<3>().isZero(0.0) && r.leftCols<3>().isZero(0.0)) ? RobotPart::Rotation
                                                                                : RobotPart::Full;
  }
};

/// Sigma = I^-1 for a 12x12 information I: by its Cholesky factor, I = L L^T and
/// Sigma = L^-T L^-1, with L^-1 by forward substitution (a quarter of the work of
/// solving against the identity); by LDLT when I is not positive definite.
Matrix12d inverse_information(const Matrix12d& information) {
  const Eigen::LLT<Matrix12d> llt(information);
  if (llt.info() != Eigen::Success) return information.ldlt().solve(Matrix12d::Identity());
  const Matrix12d L_inverse = lower_triangular_inverse(llt.matrixLLT(), false);  // L in the lower triangle
  return L_inverse.transpose().lazyProduct(L_inverse);
}

/// Huber's loss on a Mahalanobis distance d (s: the robust scale; k: threshold in
/// units of s; k = 0 for the squared loss). Returns the IRLS weight; rho is the loss.
double huber_weight(double d, double k_scaled) { return k_scaled <= 0.0 || d <= k_scaled ? 1.0 : k_scaled / d; }
double huber_rho(double d, double k_scaled) {
  return k_scaled <= 0.0 || d <= k_scaled ? 0.5 * d * d : k_scaled * d - 0.5 * k_scaled * k_scaled;
}

/// One sample's linearisation as a solve keeps it: the residual, its Jacobian
/// whitened by the sample's S = L L^T (Jw = L^-1 J: what the information, the
/// leverages and the sandwich use).
struct Linearized {
  Linearized() {}  // as Term: resize() does not zero-fill what linearize_all writes
  Vector6d e;
  Matrix6x12 Jw;
};

/// The state of a solve at (X, Y): every sample's linearisation and weight.
struct Solution {
  Isometry3d X, Y;
  std::vector<Linearized> lin;
  /// Each sample's L^-1 (its residual covariance S = L L^T), shared with the
  /// solutions that keep the same weights rather than copied.
  std::shared_ptr<const std::vector<Matrix6d>> whitening;
  const Matrix6d& L_inverse(std::size_t i) const { return (*whitening)[i]; }
  /// S_i^-1 = L^-T L^-1.
  Matrix6d weight_matrix(std::size_t i) const { return L_inverse(i).transpose().lazyProduct(L_inverse(i)); }
  /// d P_hat / d xi_E and the unwhitened J per sample, kept only while the noise is
  /// estimated (JointProblem::keep_robot_jacobians).
  std::vector<Matrix6d> D;
  std::vector<Matrix6x12> J;
  std::vector<double> weight;          // robust weights (1 for the squared loss)
  Matrix12d information = Matrix12d::Zero();  // sum w J^T S^-1 J
  /// information^-1 when a predicted step has computed it; every linearisation clears it.
  std::optional<Matrix12d> covariance;
  Vector12d gradient = Vector12d::Zero();
  double cost = 0.0;  // sum rho(d_i)
  double chi2 = 0.0;  // sum d_i^2
  StageDiagnostics diagnostics;

  /// sum e_i e_i^T at the linearisation point.
  Matrix6d scatter() const {
    Matrix6d out = Matrix6d::Zero();
    for (const Linearized& l : lin) out.noalias() += l.e * l.e.transpose();
    return out;
  }
};

/// s.information^-1, from the solution's own when it has one.
Matrix12d covariance_of(const Solution& s) { return s.covariance ? *s.covariance : inverse_information(s.information); }

class JointProblem {
 public:
  JointProblem(Terms terms, const JointOptions& o) : terms_(std::move(terms.terms)), noises_(std::move(terms.noises)), o_(o) {}

  std::size_t size() const { return terms_.size(); }
  const std::vector<Term>& terms() const { return terms_; }

  /// From now on each linearisation keeps D (the noise fit's robot factors need it).
  void keep_robot_jacobians() { keep_D_ = true; }
  /// The stated camera noise's square roots F (F F^T = Sigma_P: the fit reads only
  /// that product), for the fit of its scale: its Cholesky factor, or its
  /// symmetric root when it is only semi-definite (a zero-noise axis).
  void set_camera_roots() {
    camera_roots_.resize(terms_.size());
    for (std::size_t i = 0; i < terms_.size(); ++i) {
      if (i > 0 && terms_[i].camera_noise == terms_[i - 1].camera_noise) {  // the global noise, shared
        camera_roots_[i] = camera_roots_[i - 1];
        continue;
      }
      const Eigen::LLT<Matrix6d> llt(terms_[i].camera());
      if (llt.info() == Eigen::Success) {
        camera_roots_[i] = llt.matrixL();
        continue;
      }
      const Eigen::SelfAdjointEigenSolver<Matrix6d> eig(terms_[i].camera());
      camera_roots_[i] = eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).cwiseSqrt().asDiagonal() * eig.eigenvectors().transpose();
    }
  }
  const Matrix6d& camera_root(std::size_t i) const { return camera_roots_.at(i); }

  /// Each view's planar-target shape G_i and its Cholesky factor (view_noise.h), from
  /// the view P_i itself and the target's points: the view-following noise.
  /// Whether every view has a shape (none is edge-on or behind the camera).
  bool set_view_shapes(const std::vector<Eigen::Vector3d>& points) {
    view_points_ = points;
    const std::size_t n = terms_.size();
    view_shapes_.resize(n), view_roots_.resize(n), view_informations_.resize(n), view_log_dets_.resize(n);
    bool all = true;
    for (std::size_t i = 0; i < n; ++i) {
      Term& t = terms_[i];
      Isometry3d P = Isometry3d::Identity();
      P.linear() = t.RP, P.translation() = t.tP;
      // G = I^-1 = L^-T L^-1 from the information's factor I = L L^T: L^-T is a root of G.
      view_informations_[i] = planar_view_information(P, points);
      Matrix6d L_inverse;
      if (!inverse_cholesky(view_informations_[i], L_inverse)) {
        view_shapes_[i].setZero(), view_roots_[i].setZero(), view_log_dets_[i] = 0.0;
        all = false;
      } else {
        view_roots_[i] = L_inverse.transpose();
        view_shapes_[i] = L_inverse.transpose().lazyProduct(L_inverse);
        view_log_dets_[i] = 2.0 * std::log(L_inverse.diagonal().prod());
      }
      t.view_shape = &view_shapes_[i];
    }
    return all;
  }
  const Matrix6d& view_root(std::size_t i) const { return view_roots_.at(i); }
  /// G_i^-1 and log det G_i.
  const Matrix6d& view_information(std::size_t i) const { return view_informations_.at(i); }
  double view_log_det(std::size_t i) const { return view_log_dets_.at(i); }
  const std::vector<Eigen::Vector3d>& view_points() const { return view_points_; }

  /// Linearises every sample at (X, Y) under `model`, with Huber weights at
  /// threshold k_scaled (0: squared loss). Throws InvalidNoise on a singular S_i.
  /// `weights` (S_i^-1 = L^-T L^-1) from `reuse` when given: the robot's term moves
  /// S_i with X and Y, but within a sigma of the solution it moves it negligibly.
  /// `at` holds the samples' linearisations at (s.X, s.Y) when they are known.
  void linearize_all(const NoiseModel& model, double k_scaled, Solution& s, const Solution* reuse = nullptr,
                     const std::vector<Linear>* at = nullptr) const {
    const Frame f(s.X, s.Y);
    const std::size_t n = terms_.size();
    s.lin.resize(n), s.weight.assign(n, 1.0);
    if (keep_D_) s.D.resize(n), s.J.resize(n);
    else s.D.clear(), s.J.clear();
    s.information.setZero(), s.gradient.setZero(), s.cost = 0.0, s.chi2 = 0.0;
    s.covariance.reset();
    std::shared_ptr<std::vector<Matrix6d>> fresh;
    if (!reuse) fresh = std::make_shared<std::vector<Matrix6d>>(n);
    Linear fresh_l;
    for (std::size_t i = 0; i < n; ++i) {
      if (!at) linearize(terms_[i], f, fresh_l, model.robot_free_or_given);
      const Linear& l = at ? (*at)[i] : fresh_l;
      if (keep_D_) s.D[i] = l.D, s.J[i] = l.J;
      if (!reuse && !inverse_cholesky(model.covariance(terms_[i], l.D), (*fresh)[i])) {
        throw HandEyeError(ErrorCode::InvalidNoise, "the combined robot + camera noise of this sample is singular",
                           "samples[" + std::to_string(i) + "]",
                           "give a non-zero rotation and translation noise for the pattern (or the robot), or omit the "
                           "noise block to estimate it");
      }
      // Whitened: r = L^-1 e, Jw = L^-1 J; the information's X-X, X-Y and Y-Y blocks
      // only (the Y-X block is the X-Y block's transpose, filled after the loop).
      const Matrix6d& L_inverse = reuse ? reuse->L_inverse(i) : (*fresh)[i];
      Linearized& out = s.lin[i];
      out.e = l.e;
      whiten(L_inverse, l.J, out.Jw);
      const Vector6d r = L_inverse * l.e;
      const Matrix6x12& Jw = out.Jw;
      const double d2 = r.squaredNorm();
      const double w = huber_weight(std::sqrt(d2), k_scaled);
      const Matrix6x12 wJw = w * Jw;
      s.weight[i] = w;
      s.information.topLeftCorner<6, 6>().noalias() += wJw.leftCols<6>().transpose().lazyProduct(Jw.leftCols<6>());
      s.information.topRightCorner<6, 6>().noalias() += wJw.leftCols<6>().transpose().lazyProduct(Jw.rightCols<6>());
      s.information.bottomRightCorner<6, 6>().noalias() += wJw.rightCols<6>().transpose().lazyProduct(Jw.rightCols<6>());
      s.gradient.noalias() += wJw.transpose() * r;
      s.cost += huber_rho(std::sqrt(d2), k_scaled);
      s.chi2 += d2;
    }
    s.information.bottomLeftCorner<6, 6>() = s.information.topRightCorner<6, 6>().transpose();
    if (reuse) s.whitening = reuse->whitening;
    else s.whitening = std::move(fresh);
  }

  /// sum e_i e_i^T at (X, Y): the noise fit's first values, with no weights to solve under.
  Matrix6d residual_scatter(const Isometry3d& X, const Isometry3d& Y) const {
    const Frame f(X, Y);
    Matrix6d out = Matrix6d::Zero();
    for (const Term& t : terms_) {
      const Vector6d e = residual(t, f);
      out.noalias() += e * e.transpose();
    }
    return out;
  }

  /// The robust cost at (X, Y) with the covariances of `at` held fixed.
  double cost_at(const Isometry3d& X, const Isometry3d& Y, const Solution& at, double k_scaled) const {
    const Frame f(X, Y);
    double cost = 0.0;
    for (std::size_t i = 0; i < terms_.size(); ++i) {
      const Vector6d r = at.L_inverse(i) * residual(terms_[i], f);
      cost += huber_rho(r.norm(), k_scaled);
    }
    return cost;
  }

  /// One Gauss-Newton step from s.X, s.Y, taken without a second linearisation:
  /// the residuals move by their linear prediction e + J step, which is off by
  /// the step's square (in radians: under 1e-4 for a step that moves_weights
  /// passes). False, with nothing taken, when the step would move the weights, or
  /// is longer than `max_sigmas` in its own Mahalanobis length: solve then. For the
  /// noise rounds, which keep J (keep_robot_jacobians).
  bool predicted_step(const NoiseModel& model, Solution& s, double max_sigmas, const std::vector<Linear>* at = nullptr) const {
    linearize_all(model, 0.0, s, nullptr, at);
    // Its Sigma serves the noise fit and the result too (the step only moves X and Y).
    s.covariance = inverse_information(s.information);
    const Vector12d step = -(*s.covariance * s.gradient);
    if (!step.allFinite() || moves_weights(step) || !(step.dot(s.information * step) <= max_sigmas * max_sigmas)) return false;
    s.X = apply(s.X, step.head<6>()), s.Y = apply(s.Y, step.tail<6>());
    for (std::size_t i = 0; i < s.lin.size(); ++i) s.lin[i].e.noalias() += s.J.at(i) * step;
    s.chi2 -= step.dot(s.information * step);  // |r + Jw step|^2 at the Gauss-Newton step
    s.diagnostics.iterations += 1;
    s.diagnostics.stop_reason = StopReason::StepBelowTolerance;
    return true;
  }

  /// Gauss-Newton (iteratively reweighted: the robot's term and the Huber
  /// weights follow the estimate) with step halving, from s.X, s.Y. Each trial
  /// point is linearised at once (its cost comes with it); a step whose cost
  /// rose is checked again under the old weights before it is halved, since the
  /// robot's term moves S_i with the estimate.
  void gauss_newton(const NoiseModel& model, double k_scaled, Solution& s) const {
    linearize_all(model, k_scaled, s);
    Solution trial;
    int iterations = 0;
    s.diagnostics.stop_reason = StopReason::MaxIterations;
    for (int iteration = 1; iteration <= o_.max_iterations; ++iteration) {
      iterations = iteration;
      const Eigen::LDLT<Matrix12d> ldlt(s.information);
      Vector12d step = -ldlt.solve(s.gradient);
      const double length = step.dot(s.information * step);
      if (!std::isfinite(length)) break;  // a singular information: reported by the caller
      if (length < o_.step_tolerance) {
        // Below 0.1 sigma: take it; the current linearisation is as good to first order.
        s.X = apply(s.X, step.head<6>()), s.Y = apply(s.Y, step.tail<6>());
        s.diagnostics.stop_reason = StopReason::StepBelowTolerance;
        break;
      }
      bool moved = false;
      for (int halving = 0; halving < 30 && !moved; ++halving, step *= 0.5) {
        trial.X = apply(s.X, step.head<6>()), trial.Y = apply(s.Y, step.tail<6>());
        // The weights follow the estimate through a first step that turns X or Y by
        // more than 0.01 rad or moves them by more than 1 cm (the start may be far;
        // the robot's term in S_i turns with them, by under 1% within those); after
        // that they are kept, and the steps compare one cost function.
        const bool weights_follow = iteration == 1 && model.robot_free_or_given && moves_weights(step);
        linearize_all(model, k_scaled, trial, weights_follow ? nullptr : &s);
        moved = trial.cost <= s.cost * (1.0 + 1e-12) || cost_at(trial.X, trial.Y, s, k_scaled) <= s.cost * (1.0 + 1e-12);
      }
      if (!moved) {
        s.diagnostics.stop_reason = StopReason::CostChangeBelowTolerance;  // no descent left at this precision
        break;
      }
      const double previous = s.cost;
      trial.diagnostics = s.diagnostics;
      std::swap(s, trial);
      if (std::abs(previous - s.cost) <= 1e-14 * std::max(previous, 1e-300)) {
        s.diagnostics.stop_reason = StopReason::CostChangeBelowTolerance;
        break;
      }
    }
    s.diagnostics.iterations += iterations;
    s.diagnostics.chi2 = s.chi2;
    s.diagnostics.dof = 6 * static_cast<int>(terms_.size()) - 12;
  }

 private:
  std::vector<Term> terms_;
  std::vector<Matrix6d> noises_;  // what the terms' noise pointers point to
  const JointOptions& o_;
  bool keep_D_ = false;
  std::vector<Matrix6d> camera_roots_, view_shapes_, view_roots_, view_informations_;
  std::vector<double> view_log_dets_;
  std::vector<Eigen::Vector3d> view_points_;

};

Terms make_terms(const SampleSet& set, bool& given) {
  given = set.noise.has_value();
  if (set.noise) check_covariance(set.noise->robot, "noise.effector"), check_covariance(set.noise->camera, "noise.pattern");
  Terms out;
  std::vector<Term>& terms = out.terms;
  terms.resize(set.samples.size());
  std::size_t own_count = 0;
  for (const PoseSample& sample : set.samples) own_count += sample.noise.has_value();
  out.noises.reserve(2 + 2 * own_count);  // no reallocation below: the terms point into it
  // The global noise as 6x6 once; a sample's own noise replaces it.
  const MeasurementNoise global = set.noise ? *set.noise : MeasurementNoise{};
  out.noises.push_back(global.camera.as_pose_covariance());
  out.noises.push_back(global.robot.as_pose_covariance());
  const Matrix6d* global_camera = &out.noises[0];
  const Matrix6d* global_robot = &out.noises[1];
  for (std::size_t i = 0; i < set.samples.size(); ++i) {
    const PoseSample& sample = set.samples[i];
    const std::optional<MeasurementNoise>& own = sample.noise;
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
    Term& t = terms[i];
    t = make_term(set.rig, sample);
    t.camera_noise = global_camera, t.robot_noise = global_robot;
    if (own) {
      out.noises.push_back(own->camera.as_pose_covariance());
      t.camera_noise = &out.noises.back();
      out.noises.push_back(own->robot.as_pose_covariance());
      t.robot_noise = &out.noises.back();
    }
    t.has_robot = !t.robot().isZero(0.0);
  }
  return out;
}

/// The free noise numbers and how each enters S_i (variance_components.h).
enum class Kind {
  CameraScale, CameraAxis, CameraTranslation, CameraRotation, CameraPair, RobotTranslation, RobotRotation,
  ViewShape,  // the view's planar-target shape G_i (view_noise.h), scaled
};
/// Whether a component's factor changes from sample to sample (the robot's lever arms, the view's shape).
bool per_sample(Kind kind) { return kind == Kind::RobotTranslation || kind == Kind::RobotRotation || kind == Kind::ViewShape; }
bool robot_kind_of(Kind kind) { return kind == Kind::RobotTranslation || kind == Kind::RobotRotation; }
struct Free {
  Kind kind;
  int a = 0, b = 0;  // axes (CameraAxis: a; CameraPair: a, b)
  VarianceComponent component;
};

const char* axis_name(int a) {
  static const char* names[] = {"x", "y", "z", "rx", "ry", "rz"};
  return names[a];
}

std::vector<Free> free_components(bool given, bool chi2_failed, bool any_camera_stated, int dof, const JointOptions& o) {
  std::vector<Free> free;
  const double floor = 1e-18;  // (1e-9 m or rad)^2: noise-free input stays solvable
  if (given) {
    if (!chi2_failed) return free;
    if (any_camera_stated) {
      free.push_back({Kind::CameraScale, 0, 0, {"stated camera noise scale", 1e-3}});
    } else {
      free.push_back({Kind::CameraTranslation, 0, 0, {"camera translation", floor}});
      free.push_back({Kind::CameraRotation, 0, 0, {"camera rotation", floor}});
    }
    free.push_back({Kind::RobotTranslation, 0, 0, {"robot translation", 0.0}});
    free.push_back({Kind::RobotRotation, 0, 0, {"robot rotation", 0.0}});
    return free;
  }
  if (dof >= o.full_noise_min_dof) {
    const double none = -std::numeric_limits<double>::infinity();  // kept positive definite by the fit
    for (int a = 0; a < 6; ++a) free.push_back({Kind::CameraAxis, a, a, {std::string("camera ") + axis_name(a), none}});
    for (int a = 0; a < 6; ++a) {
      for (int b = a + 1; b < 6; ++b) {
        free.push_back({Kind::CameraPair, a, b, {std::string("camera ") + axis_name(a) + "-" + axis_name(b), none}});
      }
    }
  } else if (dof >= o.per_axis_noise_min_dof) {
    for (int a = 0; a < 6; ++a) free.push_back({Kind::CameraAxis, a, a, {std::string("camera ") + axis_name(a), floor}});
  } else {
    free.push_back({Kind::CameraTranslation, 0, 0, {"camera translation", floor}});
    free.push_back({Kind::CameraRotation, 0, 0, {"camera rotation", floor}});
  }
  // The robot's rotation only: an isotropic robot translation noise is isotropic
  // in every frame, so it is the camera's translation noise under another name.
  if (dof >= o.robot_noise_min_dof) free.push_back({Kind::RobotRotation, 0, 0, {"robot rotation", 0.0}});
  return free;
}

/// The factor width of a component (0: a shared camera covariance entry).
int rank_of(Kind kind) {
  switch (kind) {
    case Kind::CameraScale: case Kind::ViewShape: return 6;
    case Kind::CameraAxis: case Kind::CameraPair: return 0;
    default: return 3;
  }
}

/// The factor of component `c` for sample i (6 x rank).
ComponentFactors factor(const Free& c, const JointProblem& problem, const Solution& s, std::size_t i) {
  const auto D = [&]() -> const Matrix6d& { return s.D.at(i); };
  switch (c.kind) {
    case Kind::CameraScale: return problem.camera_root(i);
    case Kind::ViewShape: return problem.view_root(i);
    case Kind::CameraTranslation: return Matrix6d::Identity().leftCols<3>();
    case Kind::CameraRotation: return Matrix6d::Identity().rightCols<3>();
    case Kind::RobotTranslation: return D().leftCols<3>();
    case Kind::RobotRotation: return D().rightCols<3>();
    default: return ComponentFactors(6, 0);
  }
}

/// theta into the model (the stated parts stay as they are).
void apply_components(const std::vector<Free>& free, const Eigen::VectorXd& theta, NoiseModel& model) {
  model.camera.setZero();
  Matrix6d robot = Matrix6d::Zero();
  for (std::size_t k = 0; k < free.size(); ++k) {
    const Free& c = free[k];
    const double v = theta[static_cast<Eigen::Index>(k)];
    switch (c.kind) {
      case Kind::CameraScale: model.camera_scale = v; break;
      case Kind::ViewShape: model.view_scale = v; break;
      case Kind::CameraAxis: model.camera(c.a, c.a) += v; break;
      case Kind::CameraPair: model.camera(c.a, c.b) += v, model.camera(c.b, c.a) += v; break;
      case Kind::CameraTranslation: model.camera.topLeftCorner<3, 3>() += v * Matrix3d::Identity(); break;
      case Kind::CameraRotation: model.camera.bottomRightCorner<3, 3>() += v * Matrix3d::Identity(); break;
      case Kind::RobotTranslation: robot.topLeftCorner<3, 3>() += v * Matrix3d::Identity(); break;
      case Kind::RobotRotation: robot.bottomRightCorner<3, 3>() += v * Matrix3d::Identity(); break;
    }
  }
  model.set_robot(robot);
}

/// Whether the model's camera 6x6 is a covariance (a full one is fitted entry by
/// entry and may come out indefinite where every S_i is not).
bool model_is_covariance(const NoiseModel& model) {
  if (model.camera.isDiagonal(0.0)) return (model.camera.diagonal().array() >= 0.0).all();
  return Eigen::SelfAdjointEigenSolver<Matrix6d>(model.camera, Eigen::EigenvaluesOnly).eigenvalues().minCoeff() >= 1e-18;
}

/// The fit's data at a solution: fixed part, REML-completed scatter, factors; with
/// the solution's whitening when s was linearised under this model (a predicted
/// step's s: its D and its L^-1 from the same linearisation), scaled by covariance_scale.
VarianceComponentData component_data(const JointProblem& problem, const std::vector<Free>& free, const NoiseModel& model,
                                     const Solution& s, double covariance_scale = 1.0, bool whitened_at_theta = false) {
  VarianceComponentData data;
  for (const Free& c : free) {
    if (rank_of(c.kind) > 0) add_factor_component(data, rank_of(c.kind));
    else add_entry_component(data, c.a, c.b);
  }
  int column = 0;
  for (std::size_t k = 0; k < free.size(); ++k) column = std::max(column, data.columns[k] + data.ranks[k]);
  // The part of S_i that no free component touches.
  NoiseModel fixed_model;
  fixed_model.robot_free_or_given = model.robot_free_or_given;
  bool scale_free = false;
  for (const Free& c : free) scale_free = scale_free || c.kind == Kind::CameraScale;
  fixed_model.camera_scale = scale_free ? 0.0 : model.camera_scale;
  const Matrix12d covariance = covariance_of(s) * covariance_scale;
  const std::size_t n = problem.size();
  data.fixed.resize(n), data.scatter.resize(n), data.factors.resize(n);
  if (whitened_at_theta) data.start_whitening.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Term& t = problem.terms()[i];
    const Linearized& l = s.lin[i];
    data.fixed[i] = fixed_model.covariance(t, s.D.at(i));
    data.scatter[i] = l.e * l.e.transpose() + projected_covariance(s.J.at(i), covariance);
    // S_i(theta) is the covariance that s was whitened with (its scale aside).
    if (whitened_at_theta) data.start_whitening[i] = s.L_inverse(i) / std::sqrt(covariance_scale);
    data.factors[i].resize(6, column);
    for (std::size_t k = 0; k < free.size(); ++k) {
      if (data.ranks[k] > 0) data.factors[i].middleCols(data.columns[k], data.ranks[k]) = factor(free[k], problem, s, i);
    }
  }
  return data;
}

/// The starting values of the free components from the residual scatter (sum e e^T).
Eigen::VectorXd initial_components(const std::vector<Free>& free, Matrix6d scatter, const NoiseModel& model, int dof) {
  scatter /= std::max(dof, 1);
  const double t_var = scatter.diagonal().head<3>().mean(), r_var = scatter.diagonal().tail<3>().mean();
  Eigen::VectorXd theta(free.size());
  for (std::size_t k = 0; k < free.size(); ++k) {
    const Free& c = free[k];
    double v = 0.0;
    switch (c.kind) {
      case Kind::CameraScale: v = std::max(1.0, model.camera_scale); break;
      case Kind::CameraAxis: v = 0.7 * scatter(c.a, c.a); break;
      case Kind::CameraPair: v = 0.0; break;
      case Kind::CameraTranslation: v = 0.7 * t_var; break;
      case Kind::CameraRotation: v = 0.7 * r_var; break;
      case Kind::RobotTranslation: v = 0.1 * t_var; break;
      case Kind::RobotRotation: v = 0.1 * r_var; break;
      case Kind::ViewShape: v = 0.0; break;
    }
    theta[static_cast<Eigen::Index>(k)] = std::max(v, c.component.lower == -std::numeric_limits<double>::infinity()
                                                          ? v : c.component.lower);
  }
  return theta;
}

/// The free numbers by least squares of the start's residual outer products on
/// their matrices, min sum_i |e_i e_i^T - sum_k theta_k G_k,i|_F^2 (MINQUE(0)),
/// scaled by 6n / (6n - 12) for what the 12 parameters absorb. A start near the
/// fit's solution, so that the first solve is weighted close to the last one: with
/// it, 78% of 1 000 simulated 31-pose sessions need one round, against 32% from
/// the scatter's diagonal (initial_components). For the noise-free-input case (no
/// fixed part in S_i); a camera G_k is the same for every sample.
Eigen::VectorXd moment_components(const std::vector<Free>& free, const JointProblem& problem, const Isometry3d& X,
                                  const Isometry3d& Y, std::vector<Linear>& linearizations) {
  const std::size_t K = free.size();
  std::vector<Matrix6d> G(K, Matrix6d::Zero());
  std::vector<std::size_t> camera, robot;
  for (std::size_t k = 0; k < K; ++k) {
    const Free& c = free[k];
    switch (c.kind) {
      case Kind::CameraAxis: G[k](c.a, c.a) = 1.0; break;
      case Kind::CameraPair: G[k](c.a, c.b) = G[k](c.b, c.a) = 1.0; break;
      case Kind::CameraTranslation: G[k].topLeftCorner<3, 3>().setIdentity(); break;
      case Kind::CameraRotation: G[k].bottomRightCorner<3, 3>().setIdentity(); break;
      default: break;
    }
    (per_sample(c.kind) ? robot : camera).push_back(k);
  }
  const double n = static_cast<double>(problem.size());
  Eigen::MatrixXd N = Eigen::MatrixXd::Zero(K, K);
  for (std::size_t k : camera) {
    for (std::size_t j : camera) N(k, j) = n * G[k].cwiseProduct(G[j]).sum();
  }
  Eigen::VectorXd b = Eigen::VectorXd::Zero(K);
  Matrix6d scatter = Matrix6d::Zero();
  const Frame f(X, Y);
  linearizations.resize(problem.size());
  for (std::size_t i = 0; i < problem.size(); ++i) {
    Linear& l = linearizations[i];
    linearize(problem.terms()[i], f, l);  // with D: the first solve reuses it
    scatter.noalias() += l.e * l.e.transpose();
    for (std::size_t k : robot) {
      if (free[k].kind == Kind::ViewShape) {
        G[k] = *problem.terms()[i].view_shape;
        b[k] += l.e.dot(G[k] * l.e);
        continue;
      }
      Eigen::Matrix<double, 6, 3> F = Eigen::Matrix<double, 6, 3>::Zero();
      switch (free[k].kind) {
        case Kind::RobotRotation: F = l.D.rightCols<3>(); break;
        case Kind::RobotTranslation: F = l.D.leftCols<3>(); break;
        default: break;
      }
      G[k].noalias() = F * F.transpose();
      b[k] += (F.transpose() * l.e).squaredNorm();
    }
    for (std::size_t k : robot) {  // after every robot G of this sample is set
      for (std::size_t j = 0; j < K; ++j) N(k, j) += G[k].cwiseProduct(G[j]).sum();
    }
  }
  for (std::size_t k : camera) b[k] = scatter.cwiseProduct(G[k]).sum();
  for (std::size_t k : robot) {
    for (std::size_t j : camera) N(j, k) = N(k, j);
  }
  const Eigen::VectorXd scale = N.diagonal().cwiseMax(1e-300).cwiseSqrt().cwiseInverse();
  Eigen::VectorXd theta = scale.asDiagonal() * (scale.asDiagonal() * N * scale.asDiagonal()).ldlt().solve(scale.asDiagonal() * b);
  theta *= 6.0 * n / (6.0 * n - 12.0);
  for (std::size_t k = 0; k < K; ++k) {
    if (!std::isfinite(theta[k])) theta[k] = 0.0;
    const double lower = free[k].component.lower;
    if (lower != -std::numeric_limits<double>::infinity()) theta[k] = std::max(theta[k], lower);
  }
  // A full 6x6 (its entries unbounded) may come out indefinite: start from its
  // nearest matrix with every eigenvalue at least 1e-3 of the largest.
  Matrix6d full = Matrix6d::Zero();
  bool entries = false;
  for (std::size_t k = 0; k < K; ++k) {
    if (free[k].kind == Kind::CameraPair) entries = true;
    if (free[k].kind == Kind::CameraAxis || free[k].kind == Kind::CameraPair) full += theta[k] * G[k];
  }
  if (entries) {
    const Eigen::SelfAdjointEigenSolver<Matrix6d> eig(full);
    const Vector6d values = eig.eigenvalues().cwiseMax(1e-3 * std::max(eig.eigenvalues().maxCoeff(), 1e-300));
    full = eig.eigenvectors() * values.asDiagonal() * eig.eigenvectors().transpose();
    for (std::size_t k = 0; k < K; ++k) {
      if (free[k].kind == Kind::CameraAxis || free[k].kind == Kind::CameraPair) theta[k] = full(free[k].a, free[k].b);
    }
  }
  return theta;
}

/// What one pass over the samples at a solution says about the noise fit behind it.
struct NoisePass {
  /// 1 / (1 - q): the inflation of X's covariance and of Y's for the noise
  /// estimate's own error (the X-Y block takes their geometric mean).
  double inflation_x = 1.0, inflation_y = 1.0;
  /// The largest REML step from the fit's theta on this solution's residuals, in
  /// each number's own sigma: the fit is a fixed point of the rounds when it is small.
  double step = 0.0;
  /// What that step would do to X, to first order: the change of Sigma_X it makes
  /// (|Sx^-1/2 dSx Sx^-T/2|_F) in units of the change that the noise estimate's own
  /// error makes (its RMS, sqrt(spread) below), and the shift of X_hat in X's own
  /// sigma (Mahalanobis length); the shift is infinite when a number at its bound
  /// would move by 0.1 of its sigma or more (that number has no P_k, h_k).
  double x_change = 0.0, x_shift = 0.0;
  /// Whether the fit is settled: its step is under 0.1 sigma of each number, or, as
  /// X sees it, under 0.1 sigma of Sigma_X and of X_hat (a step along the
  /// likelihood's ridge, between numbers that X cannot tell apart).
  bool settled() const { return step < 0.1 || (x_change < 0.1 && x_shift < 0.1); }
};

/// The inflation 1 / (1 - q) is the mean NEES of X over the noise estimate's
/// error, per 6, to second order (joint_estimator.h). With Sigma = I(theta)^-1,
/// K_k = dI/dtheta_k (up to sign) and C = Cov(theta_hat):
///   E NEES ~ 6 + sum_kl C_kl tr(Sx^-1 dSx_k Sx^-1 dSx_l) - tr(Sx^-1 E[Delta]),
///   dSigma_k = Sigma K_k Sigma,   K_k = sum_i J^T A G_k A J,
///   E[Delta] = 1/2 sum_kl C_kl d2Sigma_kl = Sigma (sum_kl C_kl K_k Sigma K_l) Sigma - 1/2 Sigma M Sigma,
///   M = sum_kl C_kl sum_i J^T (A G_l A G_k A + A G_k A G_l A) J,
/// the second term being the bias of Sigma(theta_hat), which is not linear in theta
/// (for one scale of every variance it is, and q = 2 / nu exactly). Y's q is the
/// same figure for Y: its traces through Vy = S T (below), its Q_k the part of
/// K'_k T = S^T K_k Vy off T's columns, K'_k = [P Q; Q^T R] in the root S = [V | Wy].
/// Every trace is taken through V = Sigma_{:,x} Lx^-T (Sx = Lx Lx^T), so that a
/// sample adds 12x6 products, not 12x12 ones: Sx^-1 dSx_k is similar to
/// P_k = V^T K_k V, tr(Sx^-1 [Sigma N Sigma]_xx) = tr(V^T N V), and with B = A J,
/// U = (B V)(B V)^T: tr(V^T M V) = sum_i 2 w sum_kl C_kl tr(G_l A G_k U).
/// The step is C times the REML score 1/2 sum_i tr((A M_i A - A) G_k) with the
/// round's scatter M_i = e e^T + J Sigma J^T (component_data), A M A = (A e)(A e)^T +
/// B Sigma B^T (through V and the Y block's conditional root); a number at its bound counts only when its score points inwards
/// (by score / sqrt(information)). s must be linearised under the fit's theta.
// Over 150 lines: the REML trace terms share the per-view roots and fixed-size column blocks of the hot loop (docs/how_it_works.md, The joint estimator's noise).
NoisePass noise_pass(const JointProblem& problem, const std::vector<Free>& free, const VarianceComponentFit& fit,
                     const Solution& s) {
  NoisePass out;
  const Matrix12d covariance = covariance_of(s);
  const Eigen::LLT<Matrix6d> Sx(covariance.topLeftCorner<6, 6>());
  if (Sx.info() != Eigen::Success || free.empty()) return out;
  const Eigen::Matrix<double, 6, 12> Vt = Sx.matrixL().solve(covariance.topRows<6>());  // V^T = Lx^-1 Sigma_{x,:}
  const Eigen::Matrix<double, 12, 6> V = Vt.transpose();
  // Sigma = V V^T + [0; Ly] [0; Ly]^T, Ly Ly^T = Sigma_{y|x} = Syy - Syx Sx^-1 Sxy (the
  // rest of Sigma lives in the Y block): B Sigma B^T = U + (By Ly)(By Ly)^T.
  const Eigen::LLT<Matrix6d> conditional(covariance.bottomRightCorner<6, 6>() - Vt.rightCols<6>().transpose() * Vt.rightCols<6>());
  const Matrix6d Ly = conditional.info() == Eigen::Success ? Matrix6d(conditional.matrixL()) : Matrix6d::Zero();
  // Y's traces go through the same root S = [V | Wy] of Sigma: Y's whitened columns
  // are Vy = Sigma_{:,y} Lyy^-T = S T, T = S_y^T Lyy^-T (S_y: S's Y rows, Syy = Lyy Lyy^T, T^T T = I).
  const Eigen::LLT<Matrix6d> Syy(covariance.bottomRightCorner<6, 6>());
  Eigen::Matrix<double, 12, 6> T = Eigen::Matrix<double, 12, 6>::Zero(), Vy = T;
  if (Syy.info() == Eigen::Success) {
    Eigen::Matrix<double, 6, 12> Sy;
    Sy << V.bottomRows<6>(), Ly;
    T = Syy.matrixL().solve(Sy).transpose();
    Vy = Syy.matrixL().solve(covariance.bottomRows<6>()).transpose();
  }
  const Matrix6d Tx = T.topRows<6>(), Ty = T.bottomRows<6>();
  const std::size_t K = free.size();
  std::vector<int> active;  // the numbers off their bounds, with a covariance
  for (std::size_t k = 0; k < K; ++k) {
    if (!fit.at_bound[k] && fit.covariance(k, k) > 0.0) active.push_back(static_cast<int>(k));
  }
  // Each G_k as a sum of p q^T over the columns of E = [I_6 | F_1 | F_2 ...]:
  // an entry (e_a e_b^T + e_b e_a^T, or e_a e_a^T) by two terms or one, a factor
  // F F^T by one term per column.
  struct Outer {
    int p, q;
  };
  std::vector<std::vector<Outer>> outers(K);
  std::vector<int> factor_column(K, -1);
  int columns = 6;
  for (std::size_t k = 0; k < K; ++k) {
    const Free& c = free[k];
    const int r = rank_of(c.kind);
    if (r == 0) {
      outers[k].push_back({c.a, c.b});
      if (c.a != c.b) outers[k].push_back({c.b, c.a});
    } else {
      factor_column[k] = columns;
      for (int j = 0; j < r; ++j) outers[k].push_back({columns + j, columns + j});
      columns += r;
    }
  }
  // The factor columns, handled one 6-vector at a time (fixed sizes, no dynamic kernels).
  const int width = columns - 6;
  using FactorColumns = Eigen::Matrix<double, 6, kMaxFactorColumns>;
  FactorColumns F = FactorColumns::Zero();
  // E^T X E for a symmetric X, in a fixed kColumns x kColumns array (E has at most 6 + kMaxFactorColumns
  // columns), so that each (p, q) entry read below is one load at a known offset.
  constexpr int kColumns = 6 + kMaxFactorColumns;
  using Gram = Eigen::Matrix<double, kColumns, kColumns>;
  const auto gram = [&F, width](const Matrix6d& X, Gram& g) {
    g.topLeftCorner<6, 6>() = X;
    for (int c = 0; c < width; ++c) {
      const Vector6d XF = X * F.col(c);
      g.block<6, 1>(0, 6 + c) = XF;
      g.block<1, 6>(6 + c, 0) = XF.transpose();
      for (int a = 0; a < width; ++a) g(6 + a, 6 + c) = F.col(a).dot(XF);
    }
  };
  const auto at = [](int row, int col) { return row + kColumns * col; };  // Gram's column-major offset
  // The second-order term, tr(V^T M V) = sum_i 2 w tr(N_i U_i), U = (B V)(B V)^T,
  // N_i = sum_kl C_kl G_l A G_k = E Nh E^T: over l's outers (p, q) and k's (p', q'),
  // Nh's entry (q', p) gathers C_kl (q^T A p'). N_i is not formed: tr(N U) =
  // tr(Nh E^T U E), and (E^T U E)(p, q') is the dot of rows p and q' of E^T B V, so
  // each pair of outer products adds C_kl (E^T A E)(q, p') (row p . row q'). The
  // (k, l) and (l, k) sums are equal (tr(G_l A G_k U) = tr(G_k A G_l U), all four
  // symmetric): l < k counts twice. The same terms give Y's, through the rows of E^T B Vy.
  struct Traced {
    double c;
    int a, r, s;  // offset in E^T A E; the two rows of E^T B V
  };
  std::vector<Traced> traced;
  struct ActiveOuter {
    int k;
    Outer o;
  };
  std::vector<ActiveOuter> active_outers;
  // A number within 1 sigma of its bound is left out of q: its error is cut off at
  // the bound, and the expansion, which takes it as Gaussian, overstates it (with a
  // view's shape beside six camera variances near 0, X's NEES over simulated
  // sessions of 16 was 5.31 with them, 5.70 without; the camera's variances alone at
  // 30 poses 6.29 and 6.19).
  std::vector<bool> clear(K, true);
  for (int k : active) {
    const double lower = free[k].component.lower;
    if (lower != -std::numeric_limits<double>::infinity() && fit.theta[k] - lower < std::sqrt(fit.covariance(k, k))) clear[k] = false;
  }
  for (int k : active) {
    for (const Outer& o : outers[k]) active_outers.push_back({k, o});
    for (int l : active) {
      if (l > k) continue;
      if (!clear[k] || !clear[l]) continue;
      const double c = (l < k ? 2.0 : 1.0) * fit.covariance(k, l);
      for (const Outer& ol : outers[l]) {
        for (const Outer& ok : outers[k]) traced.push_back({c, at(ol.q, ok.p), ok.q, ol.p});
      }
    }
  }
  // P_k = V^T K_k V, Q_k = V^T K_k Wy and R_k = Wy^T K_k Wy, Wy = [0; Ly]: the blocks
  // of K'_k = S^T K_k S (active k only).
  std::vector<Matrix6d> P(K, Matrix6d::Zero()), Q(K, Matrix6d::Zero()), R(K, Matrix6d::Zero());
  // h_k = sum_i (B V)^T G_k A e_i: dX_hat / dtheta_k in X's whitened coordinates,
  // from the normal equations sum_i J^T A(theta) e_i = 0 (dA / dtheta_k = -A G_k A;
  // e_i falls as X_hat moves along J). Over 300 simulated sessions the shift it
  // predicts matched the next round's solve to a few hundredths of a sigma.
  std::vector<Vector6d> h(K, Vector6d::Zero());
  Eigen::VectorXd score = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(K));
  double traced_M = 0.0, traced_My = 0.0;  // tr(V^T M V), tr(Vy^T M Vy)
  Gram AG;
  // Rows q^T B V and q^T W, and q^T A e, for the columns q of E.
  Eigen::Matrix<double, kColumns, 6, Eigen::RowMajor> EBV, EW, EBVy;
  Eigen::Matrix<double, kColumns, 1> EAe;
  for (std::size_t i = 0; i < problem.size(); ++i) {
    const double w = s.weight[i];
    for (std::size_t k = 0; k < K; ++k) {
      if (factor_column[k] >= 0) F.middleCols(factor_column[k] - 6, rank_of(free[k].kind)) = factor(free[k], problem, s, i);
    }
    const Matrix6d A = s.weight_matrix(i);
    const Matrix6x12 B = s.L_inverse(i).transpose().lazyProduct(s.lin[i].Jw);  // A J = L^-T (L^-1 J)
    const Matrix6d BV = B.lazyProduct(V), W = B.rightCols<6>().lazyProduct(Ly), BVy = B.lazyProduct(Vy);  // B Wy = W
    const Vector6d Ae = A * s.lin[i].e;
    gram(A, AG);
    EBV.topRows<6>() = BV, EW.topRows<6>() = W, EAe.head<6>() = Ae;
    for (int c = 0; c < width; ++c) {
      EBV.row(6 + c).noalias() = F.col(c).transpose() * BV;
      EW.row(6 + c).noalias() = F.col(c).transpose() * W;
      EAe[6 + c] = F.col(c).dot(Ae);
    }
    // The score's kernel A M A - A = (A e)(A e)^T + (B V)(B V)^T + W W^T - A, read at
    // each outer's (q, p) in E's columns.
    for (std::size_t k = 0; k < K; ++k) {
      double sum = 0.0;
      for (const Outer& o : outers[k]) {
        sum += EAe[o.q] * EAe[o.p] + EBV.row(o.q).dot(EBV.row(o.p)) + EW.row(o.q).dot(EW.row(o.p)) - AG.data()[at(o.q, o.p)];
      }
      score[static_cast<Eigen::Index>(k)] += 0.5 * sum;
    }
    if (active.empty()) continue;
    for (const ActiveOuter& ao : active_outers) {  // K_k += w B^T p q^T B, seen through V and Wy (B Wy = W)
      const Vector6d left = w * EBV.row(ao.o.p).transpose();
      P[ao.k].noalias() += left * EBV.row(ao.o.q);
      Q[ao.k].noalias() += left * EW.row(ao.o.q);
      R[ao.k].noalias() += (w * EW.row(ao.o.p).transpose()) * EW.row(ao.o.q);
      h[ao.k].noalias() += left * EAe[ao.o.q];
    }
    EBVy.topRows<6>() = BVy;
    for (int c = 0; c < width; ++c) EBVy.row(6 + c).noalias() = F.col(c).transpose() * BVy;
    double trace = 0.0, trace_y = 0.0;
    for (const Traced& t : traced) {
      const double ca = t.c * AG.data()[t.a];
      trace += ca * EBV.row(t.r).dot(EBV.row(t.s));
      trace_y += ca * EBVy.row(t.r).dot(EBVy.row(t.s));
    }
    traced_M += 2.0 * w * trace, traced_My += 2.0 * w * trace_y;
  }
  // The step: C score over the free numbers; one at its bound by its own information
  // (that one has no P_k, h_k: it is judged by its own sigma alone).
  Matrix6d change = Matrix6d::Zero();  // Sx^-1/2 dSx Sx^-T/2
  Vector6d shift = Vector6d::Zero();
  double bound_step = 0.0;
  for (std::size_t k = 0; k < K; ++k) {
    const Eigen::Index kk = static_cast<Eigen::Index>(k);
    if (std::find(active.begin(), active.end(), static_cast<int>(k)) != active.end()) {
      double step = 0.0;
      for (int l : active) step += fit.covariance(kk, l) * score[l];
      out.step = std::max(out.step, std::abs(step) / std::sqrt(fit.covariance(kk, kk)));
      change += step * P[k];  // dSigma = sum_k dtheta_k Sigma K_k Sigma
      shift += step * h[k];
    } else if (score[kk] > 0.0 && fit.information(kk, kk) > 0.0) {
      bound_step = std::max(bound_step, score[kk] / std::sqrt(fit.information(kk, kk)));
    }
  }
  out.step = std::max(out.step, bound_step);
  out.x_shift = bound_step < 0.1 ? shift.norm() : std::numeric_limits<double>::infinity();
  // spread = sum_kl C_kl tr(P_k P_l); mixed = sum_kl C_kl tr(V^T K_k Sigma K_l V)
  // = sum_kl C_kl (tr(P_k P_l) + tr(Q_k Q_l^T)), Sigma = V V^T + Wy Wy^T, so that
  // spread - mixed = -sum_kl C_kl tr(Q_k Q_l^T). For Y, through T: its Q_k is
  // (I - T T^T) K'_k T, the part of K'_k T off Y's own columns.
  using Columns = Eigen::Matrix<double, 12, 6>;
  std::vector<Columns> Qy(K);
  for (int k : active) {
    Columns KT;
    KT.topRows<6>().noalias() = P[k] * Tx + Q[k] * Ty;
    KT.bottomRows<6>().noalias() = Q[k].transpose() * Tx + R[k] * Ty;
    Qy[k].noalias() = KT - T * (T.transpose() * KT);
  }
  double spread = 0.0, crossed = 0.0, crossed_y = 0.0;  // crossed = mixed - spread
  for (std::size_t x = 0; x < active.size(); ++x) {
    for (std::size_t y = x; y < active.size(); ++y) {
      const int k = active[x], l = active[y];
      const double c = clear[k] && clear[l] ? (x == y ? 1.0 : 2.0) * fit.covariance(k, l) : 0.0;
      spread += c * P[k].cwiseProduct(P[l]).sum();
      crossed += c * Q[k].cwiseProduct(Q[l]).sum();
      crossed_y += c * Qy[k].cwiseProduct(Qy[l]).sum();
    }
  }
  // E |sum_k dtheta_k P_k|_F^2 = spread over the noise estimate's error.
  out.x_change = spread > 0.0 ? change.norm() / std::sqrt(spread) : (change.isZero(0.0) ? 0.0 : std::numeric_limits<double>::infinity());
  const double q = std::clamp((0.5 * traced_M - crossed) / 6.0, 0.0, 0.5);
  const double q_y = std::clamp((0.5 * traced_My - crossed_y) / 6.0, 0.0, 0.5);
  out.inflation_x = 1.0 / (1.0 - q), out.inflation_y = 1.0 / (1.0 - q_y);
  return out;
}

/// Sample i's residual whitened by its S_i = L L^T: r = L^-1 e_i.
Vector6d whitened_residual(const Solution& s, std::size_t i) { return s.L_inverse(i) * s.lin[i].e; }

/// Leverage-corrected squared Mahalanobis distances (covariance: s.information^-1), each about chi2(6) under the
/// model: d_i^2 = |L^-1 e_i|^2 shrinks by the share of the sample's residual the
/// fit absorbed, E d_i^2 = 6 - tr H_ii (H_ii = Jw Sigma Jw^T, its leverage; the
/// traces add up to the 12 parameters), so d~_i^2 = 6 d_i^2 / (6 - tr H_ii).
std::vector<double> corrected_distances(const Solution& s, const Matrix12d& covariance) {
  std::vector<double> out(s.lin.size());
  for (std::size_t i = 0; i < s.lin.size(); ++i) {
    const Matrix6x12& Jw = s.lin[i].Jw;
    const Matrix6x12 Jw_covariance = Jw.lazyProduct(covariance);
    const double leverage = s.weight[i] * Jw_covariance.cwiseProduct(Jw).sum();
    out[i] = whitened_residual(s, i).squaredNorm() * 6.0 / std::max(6.0 - leverage, 0.5);
  }
  return out;
}

/// The same residuals as vectors, r~_i = (I - H_ii)^-1/2 r (HC2's symmetric root),
/// each N(0, I) under the model: for the sandwich (covariance: s.information^-1).
std::vector<Vector6d> corrected_residuals(const Solution& s, const Matrix12d& covariance) {
  std::vector<Vector6d> out(s.lin.size());
  for (std::size_t i = 0; i < s.lin.size(); ++i) {
    const Matrix6x12& Jw = s.lin[i].Jw;
    const Vector6d r = whitened_residual(s, i);
    const Matrix6d H = s.weight[i] * Jw.lazyProduct(covariance).lazyProduct(Jw.transpose());
    const Eigen::SelfAdjointEigenSolver<Matrix6d> eig(Matrix6d::Identity() - 0.5 * (H + H.transpose()));
    const Vector6d scale = eig.eigenvalues().cwiseMax(1e-6).cwiseSqrt().cwiseInverse();
    out[i] = eig.eigenvectors() * scale.asDiagonal() * eig.eigenvectors().transpose() * r;
  }
  return out;
}

/// Mardia's multivariate kurtosis of the corrected residuals as a z score
/// (b2 = mean d^4 scaled to mean d^2 = 6; under the model E b2 = 48, var 384 / n).
double kurtosis_z(const std::vector<double>& d2) {
  double m2 = 0.0, m4 = 0.0;
  for (double v : d2) m2 += v, m4 += v * v;
  const double n = static_cast<double>(d2.size());
  m2 /= n, m4 /= n;
  if (!(m2 > 0.0)) return 0.0;
  const double b2 = m4 / (m2 * m2) * 36.0;
  return (b2 - 48.0) / std::sqrt(384.0 / n);
}

/// The sandwich A^-1 B A^-1 of the Huber M-estimate (joint_estimator.h).
Matrix12d sandwich(const Solution& s, double k_scaled) {
  // A starts as sum w Jw^T Jw, which linearize_all has already summed: the information.
  Matrix12d A = s.information, B = Matrix12d::Zero();
  const std::vector<Vector6d> corrected = corrected_residuals(s, inverse_information(s.information));
  for (std::size_t i = 0; i < s.lin.size(); ++i) {
    const Matrix6x12& Jw = s.lin[i].Jw;
    const Vector6d r = whitened_residual(s, i);
    const double d = r.norm(), w = s.weight[i];
    if (w < 1.0) {  // d/dx of (k/d) Jw^T r: the weight's own change
      const Vector12d g = Jw.transpose() * r;
      A.noalias() -= (k_scaled / (d * d * d)) * g * g.transpose();
    }
    const Vector12d psi = w * Jw.transpose() * corrected[i];
    B.noalias() += psi * psi.transpose();
  }
  const Eigen::LDLT<Matrix12d> ldlt(0.5 * (A + A.transpose()));
  const Matrix12d A_inverse = ldlt.solve(Matrix12d::Identity());
  return A_inverse * B * A_inverse;
}

}  // namespace

JointResidual joint_residual(const Rig& rig, const PoseSample& sample, const Isometry3d& X, const Isometry3d& Y) {
  const Term t = make_term(rig, sample);
  Linear l;
  linearize(t, Frame(X, Y), l);
  JointResidual r;
  r.error = l.e;
  r.jacobian = l.J;
  r.d_effector = l.D;
  return r;
}

/// The restricted log-likelihood of s under the S_i it was whitened with (REML, up
/// to a constant shared by every noise model of the same samples): what the noise
/// models are compared by,
///   -1/2 (sum_i log det S_i + log det sum_i J_i^T S_i^-1 J_i + sum_i e_i^T S_i^-1 e_i).
double restricted_log_likelihood(const Solution& s) {
  double log_det = 0.0;
  for (std::size_t i = 0; i < s.lin.size(); ++i) log_det -= 2.0 * std::log(s.L_inverse(i).diagonal().cwiseAbs().prod());
  const Eigen::LLT<Matrix12d> llt(s.information);
  if (llt.info() != Eigen::Success) return -std::numeric_limits<double>::infinity();
  const double information_log_det = 2.0 * Eigen::Matrix<double, 12, 1>(llt.matrixLLT().diagonal()).array().log().sum();
  return -0.5 * (log_det + information_log_det + s.chi2);
}

/// information += J^T W J and gradient += J^T W e for J of linearize's shape
/// [[T1, T2, T3, 0], [0, R2, 0, R4]] (3x3 blocks) and a dense symmetric W: by blocks,
/// a third of a dense 12x6x12 product. Only the upper triangle of `information` is
/// written; the caller mirrors it.
void add_weighted_normal(const Matrix6x12& J, const Matrix6d& W, const Vector6d& e, Matrix12d& information,
                         Vector12d& gradient) {
  const auto T = [&](int k) { return J.block<3, 3>(0, 3 * k); };
  const auto R = [&](int k) { return J.block<3, 3>(3, 3 * k); };
  const Matrix3d Wtt = W.topLeftCorner<3, 3>(), Wtr = W.topRightCorner<3, 3>(), Wrr = W.bottomRightCorner<3, 3>();
  // W J by blocks (top: translation rows, bottom: rotation rows), column block k.
  Eigen::Matrix<double, 6, 12> WJ;
  WJ.block<3, 3>(0, 0) = Wtt * T(0), WJ.block<3, 3>(3, 0) = Wtr.transpose() * T(0);
  WJ.block<3, 3>(0, 3) = Wtt * T(1) + Wtr * R(1), WJ.block<3, 3>(3, 3) = Wtr.transpose() * T(1) + Wrr * R(1);
  WJ.block<3, 3>(0, 6) = Wtt * T(2), WJ.block<3, 3>(3, 6) = Wtr.transpose() * T(2);
  WJ.block<3, 3>(0, 9) = Wtr * R(3), WJ.block<3, 3>(3, 9) = Wrr * R(3);
  // J^T (W J): J^T's block row k is T_k^T on the top rows and R_k^T on the bottom ones.
  for (int k = 0; k < 4; ++k) {
    for (int l = k; l < 4; ++l) {
      Matrix3d block = Matrix3d::Zero();
      if (k < 3) block.noalias() += T(k).transpose() * WJ.block<3, 3>(0, 3 * l);
      if (k == 1 || k == 3) block.noalias() += R(k).transpose() * WJ.block<3, 3>(3, 3 * l);
      information.block<3, 3>(3 * k, 3 * l) += block;
    }
  }
  const Vector6d We = W * e;
  for (int k = 0; k < 4; ++k) {
    Vector3d g = Vector3d::Zero();
    if (k < 3) g += T(k).transpose() * We.head<3>();
    if (k == 1 || k == 3) g += R(k).transpose() * We.tail<3>();
    gradient.segment<3>(3 * k) += g;
  }
}

/// Two cheap looks at whether a view's shape is worth a fit, at s (the chosen
/// model without it; its J kept), from one pass over the samples:
///  - score_bound: g^2 / I_vv, g = 1/2 sum_i tr((A e e^T A - A) G_i), I_vv = 1/2
///    sum_i tr(A G_i A G_i): an upper bound of score_test's statistic (the others'
///    share of the information only lowers it; its REML completion of e e^T by
///    J Sigma J^T, a few percent at 30 samples, is left out). A local look: it misses a view's shape that the model's
///    constant noise has absorbed (simulated sessions of 16 views at 0.3-1.5 m whose
///    view-following fit was 250 better by BIC had bounds of 3-4);
///  - pure: the view's shape alone, S_i = theta G_i, at its own solution (one
///    Gauss-Newton step from s's, weighted by G_i^-1, whose scale does not move it)
///    and its best theta: its restricted log-likelihood, as restricted_log_likelihood
///    gives the model's. A global look.
struct ViewScreen {
  double score_bound = 0.0;
  double pure_log_likelihood = -std::numeric_limits<double>::infinity();
};
ViewScreen screen_view(const JointProblem& problem, const Solution& s) {
  const std::size_t n = problem.size();
  double g = 0.0, information = 0.0, log_det_G = 0.0;
  Matrix12d pure_information = Matrix12d::Zero();
  Vector12d pure_gradient = Vector12d::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    const Matrix6d A = s.weight_matrix(i);
    const Matrix6d& G = *problem.terms()[i].view_shape;
    const Matrix6d AG = A * G;
    const Vector6d& e = s.lin[i].e;
    const Vector6d Ae = A * e;
    g += 0.5 * (Ae.dot(G * Ae) - AG.trace());
    information += 0.5 * AG.cwiseProduct(AG.transpose()).sum();
    add_weighted_normal(s.J.at(i), problem.view_information(i), e, pure_information, pure_gradient);
    log_det_G += problem.view_log_det(i);
  }
  ViewScreen out;
  out.score_bound = g > 0.0 && information > 0.0 ? g * g / information : 0.0;
  pure_information.triangularView<Eigen::StrictlyLower>() = pure_information.transpose();
  const Eigen::LLT<Matrix12d> llt(pure_information);
  if (llt.info() != Eigen::Success) return out;
  // At the step's end the weighted squares fall by gradient^T step (Gauss-Newton).
  double chi2 = -pure_gradient.dot(llt.solve(pure_gradient));
  for (std::size_t i = 0; i < n; ++i) chi2 += s.lin[i].e.dot(problem.view_information(i) * s.lin[i].e);
  const double dof = 6.0 * static_cast<double>(n) - 12.0;
  if (!(chi2 > 0.0) || dof <= 0.0) return out;
  const double theta = chi2 / dof;  // REML's theta for one scale
  const double information_log_det = 2.0 * Vector12d(llt.matrixLLT().diagonal()).array().log().sum() - 12.0 * std::log(theta);
  out.pure_log_likelihood = -0.5 * (6.0 * static_cast<double>(n) * std::log(theta) + log_det_G + information_log_det + dof);
  return out;
}

/// One noise model fitted with the solve: its free numbers (a robot number the
/// camera's can mimic dropped), their REML fit, the solution under them.
struct NoiseFit {
  std::vector<Free> free;
  std::vector<std::string> inseparable;  // the dropped robot numbers' names
  Eigen::VectorXd theta;
  VarianceComponentFit fit;
  NoisePass pass;
  NoiseModel model;
  Solution s;
};

/// The REML rounds (joint_estimator.h: Noise), alternating with the solve from `s`
/// until noise_pass says the fit is settled. `model` holds the stated parts; the
/// free ones are set from `free`.
NoiseFit fit_noise(const JointProblem& problem, std::vector<Free> free, NoiseModel model, Solution s, bool homogeneous,
                   bool given, int dof, const JointOptions& options, const Eigen::VectorXd* start_theta = nullptr) {
  const std::size_t n = problem.size();
  std::vector<VarianceComponent> components;
  for (const Free& c : free) components.push_back(c.component);
  std::vector<std::string> inseparable;
  std::vector<Linear> start;  // the samples' linearisations at the start, when moment_components made them
  Eigen::VectorXd theta = start_theta ? *start_theta
                          : homogeneous ? moment_components(free, problem, s.X, s.Y, start)
                                        : initial_components(free, given ? s.scatter() : problem.residual_scatter(s.X, s.Y), model, dof);
  VarianceComponentFit fit;
  bool fitted = false;  // fit is a REML fit of the current free numbers, at theta
  NoisePass pass;
  bool settled = false;  // s was solved under theta = fit.theta, a fixed point of the rounds
  for (int round = 0; round < options.max_noise_rounds; ++round) {
    apply_components(free, theta, model);
    // The first round's solve only feeds the fit: one step, checked by the next.
    // A later one starts within a step of its solution (the weights changed
    // by the fit's step alone): one step there is the solution to second order.
    const bool stepped = round == 0 ? problem.predicted_step(model, s, std::numeric_limits<double>::infinity(), start.empty() ? nullptr : &start)
                                    : problem.predicted_step(model, s, 1.0);
    if (!stepped) problem.gauss_newton(model, 0.0, s);
    start.clear();
    if (fitted && model_is_covariance(model)) {
      // The last round's fit holds when a REML step from it on this solve's
      // residuals is under a tenth of each number's sigma: X no longer moves it.
      pass = noise_pass(problem, free, fit, s);
      if (pass.settled()) {
        settled = true;
        break;
      }
    }
    double covariance_scale = 1.0;
    bool whitened = stepped;  // s's whitening is S_i(theta)'s (times covariance_scale)
    if (round == 0 && homogeneous && !start_theta && s.chi2 > 0.0) {
      // S_i is linear in theta with no fixed part: scaling theta by chi2 / dof
      // leaves the solve as it is (its covariance scales with it) and starts
      // the fit at the residuals' own size.
      covariance_scale = s.chi2 / (6.0 * n - 12.0);
      for (Eigen::Index k = 0; k < theta.size(); ++k) {
        const double scaled = theta[k] * covariance_scale;
        whitened = whitened && scaled >= free[k].component.lower;  // a number held at its floor breaks the scaling
        theta[k] = std::max(scaled, free[k].component.lower);
      }
      apply_components(free, theta, model);
    }
    // Two AI-REML steps per round, stopping within a tenth of the numbers' own
    // sigma, the second taken without a confirming evaluation: the residuals move
    // with the next solve anyway, and noise_pass judges the fit on them.
    VarianceComponentOptions per_round;
    per_round.max_iterations = 2;
    per_round.tolerance = 0.1;
    per_round.confirm_last_step = false;
    fit = fit_variance_components(components, component_data(problem, free, model, s, covariance_scale, whitened), theta, per_round);
    fitted = true;
    // A robot component the camera's can mimic (its sigma inflated 10x by the
    // others) is not separable: held at 0, the camera's numbers take its share.
    int confounded = -1;
    for (std::size_t k = 0; k < free.size(); ++k) {
      const bool robot_kind = robot_kind_of(free[k].kind);
      const Eigen::Index i = static_cast<Eigen::Index>(k);
      if (robot_kind && !fit.at_bound[k] && fit.information(i, i) * fit.covariance(i, i) > 100.0) confounded = static_cast<int>(k);
    }
    if (confounded >= 0) {
      inseparable.push_back(free[confounded].component.name);
      free.erase(free.begin() + confounded);
      components.erase(components.begin() + confounded);
      Eigen::VectorXd kept(theta.size() - 1);
      for (Eigen::Index k = 0, j = 0; k < theta.size(); ++k) {
        if (k != confounded) kept[j++] = theta[k];
      }
      theta = kept;
      fitted = false;
      if (free.empty()) break;
      continue;
    }
    theta = fit.theta;
  }
  if (!settled) {  // out of rounds, or the last one dropped a number
    if (!fitted && !free.empty()) {
      apply_components(free, theta, model);
      fit = fit_variance_components(components, component_data(problem, free, model, s), theta);
      theta = fit.theta;
    }
    apply_components(free, theta, model);
    if (!model_is_covariance(model)) {  // a full 6x6 may come out indefinite where S_i is not: keep it a covariance
      const Eigen::SelfAdjointEigenSolver<Matrix6d> eig(model.camera);
      model.camera = eig.eigenvectors() * eig.eigenvalues().cwiseMax(1e-18).asDiagonal() * eig.eigenvectors().transpose();
    }
    problem.gauss_newton(model, 0.0, s);
    if (!free.empty()) pass = noise_pass(problem, free, fit, s);
  }
  return NoiseFit{std::move(free), std::move(inseparable), std::move(theta), std::move(fit), pass, model, std::move(s)};
}

// Over 150 lines: the start, the noise candidates' sequential score-and-BIC choice and the robust stage read one fit in turn; each stage is commented.
Calibration solve_joint(const SampleSet& samples, const JointOptions& options) {
  const int n = static_cast<int>(samples.samples.size());
  for (int i = 0; i < n; ++i) {
    const auto where = [i](const char* field) { return [i, field] { return "samples[" + std::to_string(i) + "]." + field; }; };
    check_pose_at(samples.samples[i].T_base_effector, where("effector"));
    check_pose_at(samples.samples[i].T_camera_pattern, where("pattern"));
  }
  bool given = false;
  Terms terms = make_terms(samples, given);
  bool any_camera_stated = false, any_robot_stated = false;
  for (const Term& t : terms.terms) any_camera_stated = any_camera_stated || !t.camera().isZero(0.0), any_robot_stated = any_robot_stated || t.has_robot;
  // The start throws the degeneracy errors. With a robust stage behind it, only a
  // gross angle mismatch (a flipped tag, a wrong pairing) is refused there: smaller
  // ones are what Huber's loss is for.
  SolverOptions checks = options.checks;
  if (options.robust != JointOptions::Robust::Off) {
    checks.angle_mismatch_sigmas = std::max(checks.angle_mismatch_sigmas, 20.0);
    checks.min_angle_mismatch_without_noise = std::max(checks.min_angle_mismatch_without_noise, radians(5.0));
  }
  const Isometry3d X0 = checked_initial_guess(samples, checks);
  std::vector<Isometry3d> loops;
  loops.reserve(samples.samples.size());
  for (const PoseSample& s : samples.samples) loops.push_back(samples.rig.pattern_pose(s.T_base_effector, X0, s.T_camera_pattern));
  const Isometry3d Y0 = mean_pose(loops, 1);  // a start (one step of the mean: the loops agree to a degree): Gauss-Newton refines it
  JointProblem problem(std::move(terms), options);

  Calibration result;
  result.method = Method::Joint;
  result.initial_guess = X0;
  result.samples_used = n;
  result.motions_used = 0;
  const int dof = n - 2;  // samples' worth of residuals left by the 12 parameters

  NoiseModel model;
  model.robot_free_or_given = any_robot_stated;
  Solution s;
  s.X = X0, s.Y = Y0;
  bool chi2_failed = false;
  if (given) {
    problem.gauss_newton(model, 0.0, s);
    const int residual_dof = 6 * n - 12;
    if (residual_dof >= 6) {
      // chi2 against its 99.9% bound (Wilson-Hilferty).
      const double v = 2.0 / (9.0 * residual_dof);
      const double bound = residual_dof * std::pow(1.0 - v + options.chi2_test_z * std::sqrt(v), 3);
      chi2_failed = s.chi2 > bound;
      result.residual_checks.push_back({"chi2/dof of the stated noise", s.chi2 / residual_dof, bound / residual_dof, !chi2_failed});
      if (chi2_failed && !options.estimate_missing_noise) {
        chi2_failed = false;
        Warning w;
        w.kind = Warning::Kind::AboveStatedNoise;
        w.chi2_per_dof = s.chi2 / residual_dof;
        result.warnings.push_back(w);
      }
    }
  } else if (n < 4) {
    throw HandEyeError(ErrorCode::NoiseUnidentifiable,
                       "no noise was given and " + std::to_string(n) +
                           " samples are too few to estimate the noise from the residuals (need >= 4)",
                       "input", "add a `noise` block with the pose covariances, or record more samples");
  }

  std::vector<Free> free = free_components(given, chi2_failed, any_camera_stated, dof, options);
  std::vector<std::string> inseparable;  // robot components the camera's can mimic
  double inflation = 1.0, pattern_inflation = 1.0;  // X's and Y's
  if (!free.empty()) {
    problem.keep_robot_jacobians();
    if (std::any_of(free.begin(), free.end(), [](const Free& c) { return c.kind == Kind::CameraScale; })) {
      problem.set_camera_roots();
    }
    for (const Free& c : free) {
      model.robot_free_or_given = model.robot_free_or_given || robot_kind_of(c.kind);
    }
    const bool homogeneous = !given && !any_camera_stated && !any_robot_stated;  // S_i is linear in theta, no fixed part
    NoiseFit fitted = fit_noise(problem, free, model, s, homogeneous, given, dof, options);
    // Candidates beyond it, each one number more (joint_estimator.h, Noise): a view's
    // planar-target shape, for poses given without a noise. (With detections'
    // covariances, their scale is the missing part that follows the view; a constant
    // camera noise beside it never paid for its numbers on the real sessions, score
    // 0-2.6 against 5, and its tests made the honesty check 2.5x slower.) Each is
    // fitted when its score test at the current model promises more than BIC's price
    // of one number, and kept when BIC says so; the best-scoring first.
    const double price = std::log(6.0 * n - 12.0);
    const auto bic_of = [&](double log_likelihood, std::size_t numbers) { return -2.0 * log_likelihood + price * static_cast<double>(numbers); };
    double fitted_log_likelihood = restricted_log_likelihood(fitted.s);
    double fitted_bic = bic_of(fitted_log_likelihood, fitted.free.size());
    const auto describe = [](const std::vector<Free>& numbers) {
      bool camera = false, scale = false, robot = false;
      for (const Free& c : numbers) {
        camera = camera || c.kind == Kind::CameraAxis || c.kind == Kind::CameraTranslation || c.kind == Kind::CameraRotation;
        scale = scale || c.kind == Kind::CameraScale;
        robot = robot || c.kind == Kind::RobotRotation || c.kind == Kind::RobotTranslation;
      }
      std::string out = scale ? "stated camera noise scaled" : camera ? "camera variances" : "";
      if (robot) out += std::string(out.empty() ? "" : ", ") + "robot noise";
      return out.empty() ? std::string("none") : out;
    };
    result.noise_candidates.push_back({describe(fitted.free), static_cast<int>(fitted.free.size()), 0.0, true, true,
                                       fitted_log_likelihood, fitted_bic});
    std::vector<Free> candidates;
    if (options.view_following && homogeneous && dof >= options.view_following_min_dof &&
        problem.set_view_shapes(view_points(samples.rig))) {
      candidates.push_back({Kind::ViewShape, 0, 0, {"view-following image noise", 0.0}});
    }
    bool view_screened_in = false;  // the view's shape passed screen_view
    while (!candidates.empty()) {
      // Each candidate's score test at the current fit.
      std::size_t best = 0;
      ScoreTest best_test;
      for (std::size_t c = 0; c < candidates.size(); ++c) {
        if (candidates[c].kind == Kind::ViewShape) {  // a one-pass screen first
          // The view's shape is fitted beside the model when it looks worth one number
          // locally, or when on its own it comes within two numbers' price of the model by BIC.
          const ViewScreen screen = screen_view(problem, fitted.s);
          const double pure_bic = -2.0 * screen.pure_log_likelihood + price;
          if (screen.score_bound <= price && !(pure_bic < fitted_bic + 2.0 * price)) {
            if (c == 0 || screen.score_bound > best_test.statistic) best = c, best_test = ScoreTest{screen.score_bound, 0.0};
            continue;
          }
          view_screened_in = true;
        }
        std::vector<Free> extended = fitted.free;
        extended.push_back(candidates[c]);
        Eigen::VectorXd theta(extended.size());
        theta << fitted.theta, 0.0;
        const ScoreTest test = score_test(component_data(problem, extended, fitted.model, fitted.s), theta,
                                          static_cast<int>(extended.size()) - 1);
        if (c == 0 || test.statistic > best_test.statistic) best = c, best_test = test;
      }
      Calibration::NoiseCandidate tried{"+ " + candidates[best].component.name, static_cast<int>(fitted.free.size()) + 1,
                                        best_test.statistic};
      if (best_test.statistic <= price && !view_screened_in) {  // none of them pays for its number
        for (const Free& c : candidates) {
          if (&c != &candidates[best]) result.noise_candidates.push_back({"+ " + c.component.name, tried.numbers, 0.0});
        }
        result.noise_candidates.push_back(tried);
        break;
      }
      std::vector<Free> extended = fitted.free;
      extended.push_back(candidates[best]);
      Eigen::VectorXd theta(extended.size());
      theta << fitted.theta, best_test.step;
      NoiseFit candidate = fit_noise(problem, extended, fitted.model, fitted.s, homogeneous, given, dof, options, &theta);
      tried.fitted = true;
      tried.log_likelihood = restricted_log_likelihood(candidate.s);
      tried.bic = bic_of(tried.log_likelihood, candidate.free.size());
      candidates.erase(candidates.begin() + static_cast<long>(best));
      if (tried.bic < fitted_bic) {
        for (Calibration::NoiseCandidate& c : result.noise_candidates) c.chosen = false;
        tried.chosen = true;
        fitted = std::move(candidate);
        fitted_log_likelihood = tried.log_likelihood, fitted_bic = tried.bic;
      }
      result.noise_candidates.push_back(tried);
    }
    free = std::move(fitted.free);
    inseparable = std::move(fitted.inseparable);
    model = fitted.model;
    s = std::move(fitted.s);
    const Eigen::VectorXd& theta = fitted.theta;
    const VarianceComponentFit& fit = fitted.fit;
    const NoisePass& pass = fitted.pass;
    inflation = pass.inflation_x, pattern_inflation = pass.inflation_y;

    result.noise_origin = given ? NoiseOrigin::Given : NoiseOrigin::EstimatedFromResiduals;
    NoiseModelChoice& choice = result.noise_model.emplace();
    for (std::size_t k = 0; k < free.size(); ++k) {
      const Free& c = free[k];
      const double v = theta[static_cast<Eigen::Index>(k)], var = fit.covariance(static_cast<Eigen::Index>(k), static_cast<Eigen::Index>(k));
      Calibration::NoiseComponent out;
      out.name = c.component.name;
      out.supported = !fit.at_bound[k];
      if (c.kind == Kind::CameraScale) {
        out.value = v, out.sigma = std::sqrt(std::max(var, 0.0));
      } else if (c.kind == Kind::CameraPair) {  // as a correlation coefficient
        const double norm = std::sqrt(std::max(model.camera(c.a, c.a) * model.camera(c.b, c.b), 1e-300));
        out.name += " correlation";
        out.value = v / norm, out.sigma = std::sqrt(std::max(var, 0.0)) / norm;
      } else {  // a variance: report the sigma, and its uncertainty by the delta method
        out.unit = c.kind == Kind::CameraRotation || c.kind == Kind::RobotRotation || c.kind == Kind::ViewShape ||
                           (c.kind == Kind::CameraAxis && c.a >= 3)
                       ? "rad"
                       : "m";
        out.value = std::sqrt(std::max(v, 0.0));
        out.sigma = out.value > 0.0 ? std::sqrt(std::max(var, 0.0)) / (2.0 * out.value) : 0.0;
      }
      result.noise_components.push_back(out);
      choice.correlation.push_back(c.kind == Kind::CameraPair);
    }
    choice.stated_too_small = given;
    if (given) choice.stated_chi2_per_dof = result.residual_checks.back().statistic;
    choice.camera = dof >= options.full_noise_min_dof      ? NoiseModelChoice::Camera::Full
                    : dof >= options.per_axis_noise_min_dof ? NoiseModelChoice::Camera::PerAxis
                                                            : NoiseModelChoice::Camera::TranslationAndRotation;
    choice.robot_rotation = dof >= options.robot_noise_min_dof;
    choice.residual_dof = dof;
    choice.inseparable = inseparable;
    choice.bic_price = price;
    choice.inflation = inflation, choice.pattern_inflation = pattern_inflation;
    if (given) {
      Warning w;
      w.kind = Warning::Kind::StatedNoiseTooSmall;
      w.chi2_per_dof = result.residual_checks.back().statistic;
      result.warnings.push_back(w);
    }
  } else if (given) {
    result.noise = samples.noise ? *samples.noise : MeasurementNoise{};
  }
  if (!free.empty()) {
    Matrix6d camera_mean = Matrix6d::Zero(), robot_mean = Matrix6d::Zero();
    for (const Term& t : problem.terms()) camera_mean += t.camera() / n, robot_mean += t.robot() / n;
    result.noise.camera = PoseNoise::from_pose_covariance(model.camera_scale * camera_mean + model.camera);
    result.noise.robot = PoseNoise::from_pose_covariance(robot_mean + model.robot);
  }

  result.residual_noise = Calibration::ResidualNoise{model.camera_scale, model.camera, model.robot, model.view_scale,
                                                     model.view_scale != 0.0 ? problem.view_points() : std::vector<Eigen::Vector3d>{}};

  // Robust mode: heavy-tailed residuals get Huber's loss and the sandwich.
  const Matrix12d information_inverse = covariance_of(s);
  // X's block by X's inflation, Y's by Y's, X-Y by their geometric mean: D Sigma D stays a covariance.
  Eigen::Matrix<double, 12, 1> root_inflation;
  root_inflation << Vector6d::Constant(std::sqrt(inflation)), Vector6d::Constant(std::sqrt(pattern_inflation));
  Matrix12d covariance = root_inflation.asDiagonal() * information_inverse * root_inflation.asDiagonal();
  bool robust = options.robust == JointOptions::Robust::On;
  // Residuals at round-off (noise-free input) have no tails to judge.
  double largest_residual = 0.0;
  for (const Linearized& l : s.lin) largest_residual = std::max(largest_residual, l.e.cwiseAbs().maxCoeff());
  if (n >= 8 && options.robust != JointOptions::Robust::Off && largest_residual > 1e-10) {
    const std::vector<double> d2 = corrected_distances(s, information_inverse);  // leverage-corrected squared Mahalanobis residuals
    const double z = kurtosis_z(d2);
    const bool passed = z <= options.kurtosis_test_z;
    result.residual_checks.push_back({"kurtosis z of the Mahalanobis residuals", z, options.kurtosis_test_z, passed});
    robust = robust || !passed;
    if (robust && n > 12) {
      const double scale = std::sqrt(std::max(median(d2) / kChi2SixDofMedian, 1e-12));
      const double k_scaled = std::sqrt(options.huber_threshold_squared) * scale;
      for (int round = 0; round < options.max_robust_rounds; ++round) {
        const std::vector<double> before = s.weight;
        problem.gauss_newton(model, k_scaled, s);
        double change = 0.0;
        for (std::size_t i = 0; i < before.size(); ++i) change = std::max(change, std::abs(before[i] - s.weight[i]));
        if (round > 0 && change < 1e-6) break;
      }
      const double small_sample = n / (n - 7.0);  // n > 12 here
      covariance = sandwich(s, k_scaled) * small_sample;
      inflation = pattern_inflation = small_sample;
      result.loss = Loss::Huber;
      result.covariance_kind = CovarianceKind::Sandwich;
      result.downweighted = static_cast<int>(std::count_if(s.weight.begin(), s.weight.end(), [](double w) { return w < 1.0; }));
    }
  }
  result.covariance_inflation = inflation;
  result.pattern_covariance_inflation = pattern_inflation;

  if (!covariance.allFinite() || !(covariance.diagonal().array() > 0.0).all()) {
    throw HandEyeError(ErrorCode::PoorlyConstrained, "the samples do not determine X and the pattern pose together",
                       "input", "add samples that rotate the flange about different axes");
  }
  const Matrix12d symmetric = 0.5 * (covariance + covariance.transpose());
  result.T_parent_camera = s.X;
  set_pose_covariance(result, symmetric.topLeftCorner<6, 6>());
  result.pattern = PoseWithCovariance{s.Y, symmetric.bottomRightCorner<6, 6>()};
  result.cross_covariance = symmetric.topRightCorner<6, 6>();
  result.rotation_stage = result.translation_stage = s.diagnostics;

  const double rotation_sigma = max_sigma(result.rotation_covariance);
  if (!(rotation_sigma <= options.checks.max_rotation_sigma)) {
    throw HandEyeError(ErrorCode::PoorlyConstrained,
                       "the samples constrain the rotation only to " + number_text(degrees(rotation_sigma)) +
                           " deg (1 sigma); a first-order covariance is not valid there",
                       "input", "add samples with larger rotations about different axes, or reduce the noise");
  }
  return result;
}

std::vector<Matrix6d> residual_covariances(const SampleSet& samples, const Calibration& calibration) {
  const Eigen::Isometry3d& X = calibration.T_parent_camera;
  const Eigen::Isometry3d Y = calibration.pattern ? calibration.pattern->pose : pattern_pose(samples, X);
  const MeasurementNoise global = samples.noise ? *samples.noise : MeasurementNoise{};
  std::vector<Matrix6d> out;
  out.reserve(samples.samples.size());
  for (const PoseSample& sample : samples.samples) {
    const Matrix6d D = joint_residual(samples.rig, sample, X, Y).d_effector;
    Matrix6d S;
    if (const auto& model = calibration.residual_noise) {
      const MeasurementNoise& stated = sample.noise ? *sample.noise : global;
      S = model->camera_scale * stated.camera.as_pose_covariance() + model->camera +
          D * (stated.robot.as_pose_covariance() + model->robot) * D.transpose();
      if (model->view_scale != 0.0) S += model->view_scale * planar_view_covariance(sample.T_camera_pattern, model->view_points);
    } else {
      const MeasurementNoise& noise = sample.noise ? *sample.noise : calibration.noise;
      S = noise.camera.as_pose_covariance() + D * noise.robot.as_pose_covariance() * D.transpose();
    }
    out.push_back(0.5 * (S + S.transpose()));
  }
  return out;
}

}  // namespace handeye
