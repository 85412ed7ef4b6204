#include "handeye_covariance/estimation/estimator.h"

#include <Eigen/Cholesky>
#include <Eigen/SVD>
#include <algorithm>
#include <array>
#include <cmath>

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/core/statistics.h"
#include "handeye_covariance/core/units.h"
#include "handeye_covariance/core/validation.h"

namespace handeye {

const char* to_string(StopReason reason) {
  switch (reason) {
    case StopReason::StepBelowTolerance: return "step_below_tolerance";
    case StopReason::CostChangeBelowTolerance: return "cost_change_below_tolerance";
    case StopReason::MaxIterations: return "max_iterations";
  }
  return "unknown";
}

const char* to_string(Method method) {
  switch (method) {
    case Method::Pairs: return "pairs";
    case Method::Joint: return "joint";
    case Method::Corners: return "corners";
  }
  return "unknown";
}

const char* to_string(NoiseOrigin origin) { return origin == NoiseOrigin::Given ? "given" : "estimated_from_residuals"; }

const char* to_string(Loss loss) { return loss == Loss::Huber ? "huber" : "squared"; }

const char* to_string(CovarianceKind kind) {
  switch (kind) {
    case CovarianceKind::Information: return "information";
    case CovarianceKind::Sandwich: return "sandwich";
    case CovarianceKind::SharedRobotError: return "shared_robot_error";
  }
  return "information";
}

HandEyeError corners_need_images() {
  return HandEyeError(ErrorCode::MalformedFile,
                      "method `corners` needs the images' corners and the corner estimator, which this program does not have",
                      "method",
                      "use the calibration node with the target detector, `handeye images --method corners` or `handeye bag` "
                      "with method: corners; or use joint here");
}

Method method_from_string(const std::string& name) {
  if (name == "pairs") return Method::Pairs;
  if (name == "joint") return Method::Joint;
  if (name == "corners") return Method::Corners;
  throw HandEyeError(ErrorCode::MalformedFile, "unknown method `" + name + "`", "method",
                     "use joint (X and the pattern pose from the absolute poses), pairs (the paper's AX = XB) or corners "
                     "(every image corner's reprojection error; needs the detector's corners)");
}

namespace {

using Eigen::Isometry3d;
using Eigen::Matrix3d;
using Eigen::Vector3d;

// ---------------------------------------------------------------------------
// The problem: motions plus the independent noise inputs that perturb them.
// ---------------------------------------------------------------------------

/// How one noise input perturbs one motion's A (robot) or B (camera), ROS order.
struct Influence {
  int motion = 0;
  bool on_robot = true;
  int jacobian = -1;  // index into Problem::jacobians; -1: identity (a motion's own noise)
};

/// An independent noise input: a motion's own A or B noise (motion input), or
/// one sample's effector or pattern pose noise (pose input: it touches every
/// motion that uses the sample, up to 2 x pair_window of them).
struct NoiseInput {
  Matrix6d covariance = Matrix6d::Zero();  // ROS order, with the cross block when the source gives one
  bool robot = true;  // robot/effector noise or camera/pattern noise
  std::vector<Influence> influences;
  int count = 0;
  void add(const Influence& influence) {
    influences.push_back(influence);
    ++count;
  }
};

struct Problem {
  std::vector<Isometry3d> A, B;
  std::vector<NoiseInput> inputs;
  std::vector<Matrix6d> jacobians;  // kept apart so motion input stays small in memory
  bool noise_given = true;
  int samples = 0;  // > 0: pose input; motion m runs from sample pairs[m].first to .second
  std::vector<std::pair<int, int>> pairs;
  std::size_t size() const { return A.size(); }
  int add_jacobian(const Matrix6d& J) {
    jacobians.push_back(J);
    return static_cast<int>(jacobians.size()) - 1;
  }
  /// Where motion i came from, for messages (built only when needed).
  std::string label(std::size_t i) const {
    return samples > 0 ? "samples[" + std::to_string(pairs[i].first) + "] -> samples[" + std::to_string(pairs[i].second) + "]"
                       : "motions[" + std::to_string(i) + "]";
  }
};

/// Per-kind multipliers on the input covariances. 1 when the noise is given;
/// estimated from the residuals otherwise (robot noise is then zero).
struct NoiseScale {
  double rotation = 1.0;
  double translation = 1.0;
  /// The scaled 6x6: blocks times their multiplier, the cross block times both roots.
  Matrix6d apply(const Matrix6d& covariance) const {
    if (rotation == 1.0 && translation == 1.0) return covariance;
    Vector6d root;
    root << Vector3d::Constant(std::sqrt(translation)), Vector3d::Constant(std::sqrt(rotation));
    return root.asDiagonal() * covariance * root.asDiagonal();
  }
};

/// The marginal blocks of each motion's A and B covariance that the solver
/// uses as weights (the R-t cross blocks only enter through propagate()).
struct Marginals {
  std::vector<Matrix3d> A_translation, A_rotation, B_translation, B_rotation;
};

Marginals marginals(const Problem& problem, const NoiseScale& scale) {
  const std::size_t k = problem.size();
  Marginals m;
  for (auto* v : {&m.A_translation, &m.A_rotation, &m.B_translation, &m.B_rotation}) v->assign(k, Matrix3d::Zero());
  for (const NoiseInput& input : problem.inputs) {
    const Matrix6d sigma = scale.apply(input.covariance);
    for (int j = 0; j < input.count; ++j) {
      const Influence& inf = input.influences[j];
      Matrix3d& translation = (inf.on_robot ? m.A_translation : m.B_translation)[inf.motion];
      Matrix3d& rotation = (inf.on_robot ? m.A_rotation : m.B_rotation)[inf.motion];
      if (inf.jacobian < 0) {
        translation += sigma.topLeftCorner<3, 3>();
        rotation += sigma.bottomRightCorner<3, 3>();
        continue;
      }
      const Matrix6d& J = problem.jacobians[inf.jacobian];
      translation += J.topRows<3>() * sigma * J.topRows<3>().transpose();
      rotation += J.bottomRows<3>() * sigma * J.bottomRows<3>().transpose();
    }
  }
  return m;
}

/// Sum over inputs of (sum over influences of gain * J) Sigma (...)^T: the exact
/// first-order covariance of an estimate whose sensitivity (Rows x 6, to a
/// ROS-order perturbation) to motion i's A or B is written by
/// `gain(i, on_robot, out)`. Gains are made on the fly: storing them costs
/// megabytes at large k, and fresh pages are expensive on some kernels.
template <int Rows, typename GainFn>
Eigen::Matrix<double, Rows, Rows> propagate(const Problem& problem, const NoiseScale& scale,
                                            const GainFn& gain) {
  using Total = Eigen::Matrix<double, Rows, 6>;
  Eigen::Matrix<double, Rows, Rows> covariance = Eigen::Matrix<double, Rows, Rows>::Zero();
  Total G, one;
  for (const NoiseInput& input : problem.inputs) {
    const Influence& first = input.influences[0];
    if (input.count == 1 && first.jacobian < 0) {  // a motion's own noise
      gain(first.motion, first.on_robot, G);
    } else {  // a sample's noise: chain through the Jacobians of both motions it touches
      G.setZero();
      for (int j = 0; j < input.count; ++j) {
        const Influence& inf = input.influences[j];
        gain(inf.motion, inf.on_robot, one);
        if (inf.jacobian < 0) {
          G += one;
        } else {
          G.noalias() += one * problem.jacobians[inf.jacobian];
        }
      }
    }
    covariance.noalias() += G * scale.apply(input.covariance) * G.transpose();
  }
  return 0.5 * (covariance + covariance.transpose());
}

/// Inverse of a symmetric 3x3 matrix that must be positive definite (checked by
/// Sylvester's criterion; the closed-form inverse is ~10x faster than a solve).
Matrix3d inverse_spd(const Matrix3d& C, std::size_t motion, const Problem& problem) {
  const double minor2 = C(0, 0) * C(1, 1) - C(0, 1) * C(1, 0);
  const double det = C.determinant();
  const double scale = C.trace();
  // Relative thresholds: a covariance 1e-14 below full rank counts as singular.
  // Written so that NaN or Inf anywhere fails the test as well.
  if (!(C(0, 0) > 0.0 && minor2 > 1e-28 * scale * scale && det > 1e-42 * scale * scale * scale)) {
    const std::string where = problem.label(motion);
    throw HandEyeError(ErrorCode::InvalidNoise,
                       "the combined robot + camera noise of this motion is singular", where,
                       "give a non-zero rotation and translation noise for the camera (pattern) "
                       "or the robot (effector), or omit the noise block to estimate it");
  }
  return C.inverse();
}

// ---------------------------------------------------------------------------
// Rotation stage, eq. (13-35).
// ---------------------------------------------------------------------------

struct RotationData {
  std::vector<Vector3d> alpha, beta;              // log R_A, log R_B (eq. 13)
  std::vector<Matrix3d> J_alpha, J_beta;          // J_l^-1(alpha), J_l^-1(beta)
  std::vector<Matrix3d> sigma_alpha, sigma_beta;  // eq. (14-15)
};

RotationData rotation_data(const Problem& problem) {
  RotationData d;
  const std::size_t k = problem.size();
  d.alpha.resize(k);
  d.beta.resize(k);
  d.J_alpha.resize(k);
  d.J_beta.resize(k);
  d.sigma_alpha.resize(k);
  d.sigma_beta.resize(k);
  for (std::size_t i = 0; i < k; ++i) {
    d.alpha[i] = so3::log(problem.A[i].linear());
    d.beta[i] = so3::log(problem.B[i].linear());
    d.J_alpha[i] = so3::left_jacobian_inverse(d.alpha[i]);
    d.J_beta[i] = so3::left_jacobian_inverse(d.beta[i]);
  }
  return d;
}

void update_log_covariances(RotationData& d, const Marginals& m) {
  for (std::size_t i = 0; i < d.alpha.size(); ++i) {
    d.sigma_alpha[i] = d.J_alpha[i] * m.A_rotation[i] * d.J_alpha[i].transpose();
    d.sigma_beta[i] = d.J_beta[i] * m.B_rotation[i] * d.J_beta[i].transpose();
  }
}

/// The reduced (beta-eliminated) rotation problem linearised at R.
struct RotationLinearization {
  std::vector<Matrix3d> L;          // d residual / d xi_R = [R beta_hat_i]  (eq. 24)
  std::vector<Matrix3d> C_inverse;  // (Sigma_alpha + R Sigma_beta R^T)^-1
  Matrix3d information = Matrix3d::Zero();  // U - W Z^-1 W^T  (eq. 35)
  Vector3d gradient = Vector3d::Zero();
  double cost = 0.0;
};

/// Fills `lin` in place: its per-motion vectors are reused between iterations,
/// so large k does not churn the allocator (mmap + page faults above 128 KB).
void linearize_rotation(const Matrix3d& R, const RotationData& d, const Problem& problem,
                        RotationLinearization& lin) {
  lin.information.setZero();
  lin.gradient.setZero();
  lin.cost = 0.0;
  const std::size_t k = d.alpha.size();
  lin.L.resize(k);
  lin.C_inverse.resize(k);
  for (std::size_t i = 0; i < k; ++i) {
    const Matrix3d C = d.sigma_alpha[i] + R * d.sigma_beta[i] * R.transpose();
    const Matrix3d Ci = inverse_spd(C, i, problem);
    const Vector3d e = d.alpha[i] - R * d.beta[i];  // residual of eq. (17)
    // beta_hat minimises the joint cost for this R (eq. 34 at convergence);
    // linearising at R beta_hat gives the joint problem's exact gradient.
    const Vector3d beta_hat = d.beta[i] + d.sigma_beta[i] * R.transpose() * (Ci * e);
    lin.L[i] = so3::hat(R * beta_hat);
    lin.C_inverse[i] = Ci;
    lin.information += lin.L[i].transpose() * Ci * lin.L[i];
    lin.gradient += lin.L[i].transpose() * Ci * e;
    lin.cost += e.dot(Ci * e);
  }
}

/// The weighted residual sum of squares at the solution and its dof (3k - 3).
void finish(StageDiagnostics& diagnostics, double cost, const Problem& problem) {
  diagnostics.chi2 = cost;
  diagnostics.dof = 3 * static_cast<int>(problem.size()) - 3;
}

bool converged_by_cost(double previous, double current, double tolerance) {
  return std::abs(previous - current) <= tolerance * std::max(previous, 1e-300);
}

/// Near pi the log's axis sign is arbitrary; pick for each beta_i the
/// representative (angle theta or theta - 2 pi) that agrees with alpha_i under R.
void align_representatives(const Matrix3d& R, RotationData& d) {
  for (std::size_t i = 0; i < d.alpha.size(); ++i) {
    const Vector3d other = so3::other_representative(d.beta[i]);
    if ((d.alpha[i] - R * other).norm() < (d.alpha[i] - R * d.beta[i]).norm()) {
      d.beta[i] = other;
      d.J_beta[i] = so3::left_jacobian_inverse(other);
    }
  }
}

struct RotationResult {
  Matrix3d R = Matrix3d::Identity();
  RotationLinearization linearization;  // at R: gives eq. (35) and the gains
  StageDiagnostics diagnostics;
};

/// Gauss-Newton on SO(3) with step halving; eq. (20) R <- exp([xi]) R, eq. (33).
RotationResult solve_rotation(const Matrix3d& R0, const RotationData& d, const Problem& problem,
                              const SolverOptions& options) {
  RotationResult result;
  result.R = R0;
  linearize_rotation(result.R, d, problem, result.linearization);
  RotationLinearization next;
  for (int iteration = 1; iteration <= options.max_iterations; ++iteration) {
    result.diagnostics.iterations = iteration;
    const RotationLinearization& lin = result.linearization;
    const double previous_cost = lin.cost;
    Vector3d xi = -lin.information.ldlt().solve(lin.gradient);
    const double step = xi.dot(lin.information * xi);
    if (step < options.step_tolerance) {
      // < 1e-4 sigma: take it; the current linearisation is as good to first order.
      result.R = so3::exp(xi) * result.R;
      result.diagnostics.stop_reason = StopReason::StepBelowTolerance;
      break;
    }
    Matrix3d candidate = so3::exp(xi) * result.R;
    linearize_rotation(candidate, d, problem, next);
    for (int halving = 0; halving < 30 && next.cost > previous_cost * (1.0 + 1e-12); ++halving) {
      xi *= 0.5;
      candidate = so3::exp(xi) * result.R;
      linearize_rotation(candidate, d, problem, next);
    }
    if (next.cost <= previous_cost * (1.0 + 1e-12)) {
      result.R = candidate;
      std::swap(result.linearization, next);
    }
    if (converged_by_cost(previous_cost, result.linearization.cost, options.cost_tolerance)) {
      result.diagnostics.stop_reason = StopReason::CostChangeBelowTolerance;
      break;
    }
  }
  finish(result.diagnostics, result.linearization.cost, problem);
  return result;
}

/// First-order sensitivity of xi_R to each motion's rotation noise:
/// xi_R = -S^-1 sum L_i^T C_i^-1 (J^-1(alpha_i) xi_RA - R J^-1(beta_i) xi_RB).
struct RotationGains {
  std::vector<Matrix3d> from_robot, from_camera;
};

RotationGains rotation_gains(const Matrix3d& R, const RotationLinearization& lin, const RotationData& d) {
  const Matrix3d S_inverse = lin.information.inverse();
  RotationGains g;
  g.from_robot.resize(d.alpha.size());
  g.from_camera.resize(d.alpha.size());
  for (std::size_t i = 0; i < d.alpha.size(); ++i) {
    const Matrix3d common = S_inverse * lin.L[i].transpose() * lin.C_inverse[i];
    g.from_robot[i] = -common * d.J_alpha[i];
    g.from_camera[i] = common * R * d.J_beta[i];
  }
  return g;
}

Matrix3d rotation_covariance(const Problem& problem, const NoiseScale& scale,
                             const RotationGains& g) {
  return propagate<3>(problem, scale, [&](int i, bool on_robot, Eigen::Matrix<double, 3, 6>& out) {
    out.leftCols<3>().setZero();
    out.rightCols<3>() = on_robot ? g.from_robot[i] : g.from_camera[i];
  });
}

// ---------------------------------------------------------------------------
// Translation stage, eq. (36-56).
// ---------------------------------------------------------------------------

struct TranslationLinearization {
  std::vector<Matrix3d> M;          // R_hat_Ai - I  (eq. 46)
  std::vector<Matrix3d> C_inverse;  // (Sigma_qi + [R_A t] Sigma_RA [R_A t]^T)^-1
  std::vector<Matrix3d> lever_A;    // [R_hat_Ai t]  (eq. 47)
  std::vector<Vector3d> reduced_residual;
  Matrix3d information = Matrix3d::Zero();  // eq. (56) before inversion
  Vector3d rhs = Vector3d::Zero();
  double cost = 0.0;
};

struct TranslationState {
  Vector3d t = Vector3d::Zero();
  std::vector<Vector3d> adjustment;  // xi_RAi of eq. (41)
};

/// What the translation stage needs per motion that does not change while R is fixed.
struct TranslationConstants {
  std::vector<Vector3d> q;        // q_i = R t_Bi - t_Ai  (eq. 36)
  std::vector<Matrix3d> sigma_q;  // eq. (37): Sigma_tA + R Sigma_tB R^T + [R t_B] Sigma_R [R t_B]^T
};

TranslationConstants translation_constants(const Matrix3d& R, const Matrix3d& sigma_R, const Marginals& m,
                                           const Problem& problem) {
  const std::size_t k = problem.size();
  TranslationConstants c;
  c.q.resize(k);
  c.sigma_q.resize(k);
  for (std::size_t i = 0; i < k; ++i) {
    const Vector3d RtB = R * problem.B[i].translation();
    const Matrix3d lever_B = so3::hat(RtB);
    c.q[i] = RtB - problem.A[i].translation();
    c.sigma_q[i] = m.A_translation[i] + R * m.B_translation[i] * R.transpose() +
                   lever_B * sigma_R * lever_B.transpose();
  }
  return c;
}

/// Fills `lin` in place (see linearize_rotation).
void linearize_translation(const TranslationState& s, const TranslationConstants& c, const Marginals& m,
                           const Problem& problem, TranslationLinearization& lin) {
  lin.information.setZero();
  lin.rhs.setZero();
  lin.cost = 0.0;
  const std::size_t k = problem.size();
  lin.M.resize(k);
  lin.C_inverse.resize(k);
  lin.lever_A.resize(k);
  lin.reduced_residual.resize(k);
  for (std::size_t i = 0; i < k; ++i) {
    const Matrix3d R_A = s.adjustment[i].isZero(0.0) ? problem.A[i].linear()
                                                     : Matrix3d(so3::exp(s.adjustment[i]) * problem.A[i].linear());
    const Matrix3d lever_A = so3::hat(R_A * s.t);
    // Sigma_q (eq. 37) plus the eliminated R_Ai block [R_A t] Sigma_RA [R_A t]^T (eq. 47 via Schur).
    const Matrix3d C = c.sigma_q[i] + lever_A * m.A_rotation[i] * lever_A.transpose();
    lin.M[i] = R_A - Matrix3d::Identity();
    lin.lever_A[i] = lever_A;
    lin.C_inverse[i] = inverse_spd(C, i, problem);
    // Linearised residual of q_i with the adjustment folded in (see solve_translation).
    lin.reduced_residual[i] = c.q[i] - lin.M[i] * s.t - lever_A * s.adjustment[i];
    lin.information += lin.M[i].transpose() * lin.C_inverse[i] * lin.M[i];
    lin.rhs += lin.M[i].transpose() * lin.C_inverse[i] * lin.reduced_residual[i];
    lin.cost += lin.reduced_residual[i].dot(lin.C_inverse[i] * lin.reduced_residual[i]);
  }
}

struct TranslationResult {
  TranslationState state;
  TranslationLinearization linearization;
  StageDiagnostics diagnostics;
};

/// Joint Gauss-Newton on (t, xi_RA1..k), eq. (40-49), with the xi_RA block
/// eliminated per pair. For a step dt the optimal adjustment is
///   eta_i = -Sigma_RA [R_A t]^T C_i^-1 (u_i - M_i dt),  u_i = the reduced residual.
TranslationResult solve_translation(const Vector3d& t0, const Matrix3d& R, const Matrix3d& sigma_R,
                                    const Marginals& m, const Problem& problem,
                                    const SolverOptions& options) {
  TranslationResult result;
  result.state.t = t0;
  result.state.adjustment.assign(problem.size(), Vector3d::Zero());
  const TranslationConstants constants = translation_constants(R, sigma_R, m, problem);
  linearize_translation(result.state, constants, m, problem, result.linearization);
  for (int iteration = 1; iteration <= options.max_iterations; ++iteration) {
    result.diagnostics.iterations = iteration;
    const TranslationLinearization& lin = result.linearization;
    const Vector3d dt = lin.information.ldlt().solve(lin.rhs);  // eq. (48)
    const double step = dt.dot(lin.information * dt);
    if (step < options.step_tolerance) {  // as in solve_rotation
      result.state.t += dt;
      result.diagnostics.stop_reason = StopReason::StepBelowTolerance;
      break;
    }
    for (std::size_t i = 0; i < problem.size(); ++i) {  // eq. (49)
      result.state.adjustment[i] = -m.A_rotation[i] * lin.lever_A[i].transpose() *
                                   lin.C_inverse[i] * (lin.reduced_residual[i] - lin.M[i] * dt);
    }
    result.state.t += dt;  // eq. (40)
    const double previous_cost = lin.cost;
    linearize_translation(result.state, constants, m, problem, result.linearization);
    if (converged_by_cost(previous_cost, result.linearization.cost, options.cost_tolerance)) {
      result.diagnostics.stop_reason = StopReason::CostChangeBelowTolerance;
      break;
    }
  }
  finish(result.diagnostics, result.linearization.cost, problem);
  return result;
}

/// Least-squares t for a fixed R with unit weights (Park-Martin's second step).
Vector3d unweighted_translation(const Matrix3d& R, const std::vector<Isometry3d>& A, const std::vector<Isometry3d>& B) {
  Matrix3d normal = Matrix3d::Zero();
  Vector3d rhs = Vector3d::Zero();
  for (std::size_t i = 0; i < A.size(); ++i) {
    const Matrix3d M = A[i].linear() - Matrix3d::Identity();
    normal += M.transpose() * M;
    rhs += M.transpose() * (R * B[i].translation() - A[i].translation());
  }
  return normal.ldlt().solve(rhs);
}

/// The full 6x6 first-order covariance of (t, xi_R) in ROS order. With
/// N_i = H^-1 M_i^T C_i^-1 and the noise part of the reduced residual
///   n_i = R xi_tBi - [R t_Bi] xi_R - xi_tAi + [R_Ai t] xi_RAi,
/// dt = sum_i N_i n_i, and xi_R = sum_i (K_Ai xi_RAi + K_Bi xi_RBi) is the
/// rotation estimate's own error, shared by every pair.
Matrix6d pose_covariance(const Problem& problem, const NoiseScale& scale, const Matrix3d& R,
                         const TranslationResult& translation, const RotationGains& g) {
  const TranslationLinearization& lin = translation.linearization;
  const Matrix3d H_inverse = lin.information.inverse();
  const std::size_t k = problem.size();
  std::vector<Matrix3d> N(k);
  Matrix3d D = Matrix3d::Zero();  // dt / d xi_R = -D
  for (std::size_t i = 0; i < k; ++i) {
    N[i] = H_inverse * lin.M[i].transpose() * lin.C_inverse[i];
    D += N[i] * so3::hat(R * problem.B[i].translation());
  }
  const Vector3d& t = translation.state.t;
  return propagate<6>(problem, scale, [&](int i, bool on_robot, Matrix6d& out) {
    out.bottomLeftCorner<3, 3>().setZero();
    if (on_robot) {
      out.topLeftCorner<3, 3>() = -N[i];
      out.topRightCorner<3, 3>().noalias() = N[i] * so3::hat(problem.A[i].linear() * t);
      out.topRightCorner<3, 3>().noalias() -= D * g.from_robot[i];
      out.bottomRightCorner<3, 3>() = g.from_robot[i];
    } else {
      out.topLeftCorner<3, 3>().noalias() = N[i] * R;
      out.topRightCorner<3, 3>().noalias() = -D * g.from_camera[i];
      out.bottomRightCorner<3, 3>() = g.from_camera[i];
    }
  });
}

// ---------------------------------------------------------------------------
// Degeneracy checks.
// ---------------------------------------------------------------------------

/// 1-sigma of the rotation angle of a motion: the angle moves along the axis.
double angle_sigma(const Vector3d& v, const Matrix3d& sigma) {
  const double n = v.norm();
  if (n == 0.0) return std::sqrt(std::max(0.0, sigma.trace() / 3.0));
  const Vector3d axis = v / n;
  return std::sqrt(std::max(0.0, axis.dot(sigma * axis)));
}

}  // namespace

void check_motion_rotations(const MotionRotations& m, const SolverOptions& options) {
  const std::size_t k = m.alpha.size();
  if (k < 2) {
    throw HandEyeError(ErrorCode::TooFewMotions,
                       "got " + std::to_string(k) + " motion(s); at least 2 are needed", "input",
                       "record more samples (10-30 poses rotating about different axes is typical)");
  }
  const bool noise_given = m.noise_given;
  const std::vector<double>& sigma = m.sigma;
  std::vector<double> normalized(k);
  double largest_angle = 0.0;
  for (std::size_t i = 0; i < k; ++i) {
    const double a = m.alpha[i].norm(), b = m.beta[i].norm();
    largest_angle = std::max({largest_angle, a, b});
    normalized[i] = std::abs(a - b) / (noise_given ? std::max(sigma[i], 1e-300) : 1.0);
  }
  // A motion is refused when its A/B angle mismatch is far beyond the noise AND
  // far beyond the other motions' (robust spread: 1.4826 x median). Uniformly
  // understated noise is therefore not blamed on one motion; the chi^2 warning
  // reports it instead.
  double spread = noise_given ? 1.0 : INFINITY;
  if (k >= 6) spread = kNormalSigmaPerMad * median(normalized);
  if (noise_given) spread = std::max(spread, 1.0);
  for (std::size_t i = 0; i < k; ++i) {
    const double scale = noise_given ? sigma[i] : 1.0;
    const double limit = std::max(options.angle_mismatch_sigmas * spread * scale,
                                  noise_given ? 1e-9 : options.min_angle_mismatch_without_noise);
    const double mismatch = normalized[i] * scale;
    if (mismatch > limit) {
      throw HandEyeError(
          ErrorCode::AngleMismatch,
          "robot and camera rotation angles differ by " + number_text(degrees(mismatch)) + " deg (" +
              number_text(degrees(m.alpha[i].norm())) + " vs " + number_text(degrees(m.beta[i].norm())) +
              " deg), far beyond the noise and the other motions (limit " + number_text(degrees(limit)) + " deg)",
          m.label(i),
          "the two poses of this motion were not taken at the same time, or the pattern detection "
          "is wrong; remove the sample, or check that the effector and pattern poses are paired");
    }
  }

  std::vector<std::size_t> informative;
  int above_floor = 0;
  for (std::size_t i = 0; i < k; ++i) {
    const double angle = std::min(m.alpha[i].norm(), m.beta[i].norm());
    if (angle <= options.min_rotation_angle) continue;
    ++above_floor;
    if (angle > options.min_rotation_sigmas * sigma[i]) informative.push_back(i);
  }
  if (above_floor == 0) {
    throw HandEyeError(ErrorCode::PureTranslation,
                       "no motion rotates by more than " + number_text(degrees(options.min_rotation_angle)) +
                           " deg (largest: " + number_text(degrees(largest_angle)) + " deg)",
                       "input",
                       "the robot only translated; rotate the flange between samples, 10-30 deg about "
                       "at least two different axes");
  }
  if (informative.size() < 2 && above_floor >= 2) {
    throw HandEyeError(ErrorCode::RotationTooSmallForNoise,
                       std::to_string(above_floor - informative.size()) +
                           " motion(s) rotate by less than " + number_text(options.min_rotation_sigmas) +
                           " sigma of the stated rotation noise; " + std::to_string(informative.size()) +
                           " usable motion(s) remain, 2 are needed",
                       "input", "use larger rotations between samples, or check the noise block (it holds variances, rad^2)");
  }
  if (informative.size() < 2) {
    throw HandEyeError(ErrorCode::ParallelRotationAxes,
                       "only " + std::to_string(informative.size()) +
                           " motion rotates enough; 2 motions with non-parallel rotation axes are needed",
                       "input", "add samples that rotate the flange about a different axis");
  }
  // Axes: compare each to the axis of the largest rotation, which is the best known.
  std::size_t reference = informative.front();
  for (std::size_t i : informative)
    if (m.alpha[i].norm() > m.alpha[reference].norm()) reference = i;
  const Vector3d axis = m.alpha[reference].normalized();
  double widest = 0.0, needed = options.min_axis_angle;
  for (std::size_t i : informative) {
    const double between = std::asin(std::min(1.0, axis.cross(m.alpha[i].normalized()).norm()));
    const double limit = std::max(options.min_axis_angle,
                                  options.min_rotation_sigmas *
                                      (sigma[reference] / m.alpha[reference].norm() + sigma[i] / m.alpha[i].norm()));
    if (between - limit > widest - needed) {
      widest = between;
      needed = limit;
    }
  }
  if (widest <= needed) {
    throw HandEyeError(ErrorCode::ParallelRotationAxes,
                       "all " + std::to_string(informative.size()) +
                           " rotating motions turn about the same axis (widest spread " +
                           number_text(degrees(widest)) + " deg, need > " + number_text(degrees(needed)) + " deg)",
                       "input",
                       "the rotation about that axis and the translation along it are unobservable; "
                       "add samples that rotate the flange about a second, different axis");
  }
}

namespace {

/// What the degeneracy checks read, from a pairs problem: each motion's angle
/// sigma from its marginal log covariances.
MotionRotations motion_rotations(const Problem& problem, const RotationData& d) {
  MotionRotations m;
  m.alpha = d.alpha, m.beta = d.beta, m.noise_given = problem.noise_given;
  m.sigma.assign(problem.size(), 0.0);
  if (problem.noise_given) {
    for (std::size_t i = 0; i < problem.size(); ++i) {
      m.sigma[i] = std::hypot(angle_sigma(d.alpha[i], d.sigma_alpha[i]), angle_sigma(d.beta[i], d.sigma_beta[i]));
    }
  }
  m.label = [&problem](std::size_t i) { return problem.label(i); };
  return m;
}

// ---------------------------------------------------------------------------
// Building problems from the two kinds of input.
// ---------------------------------------------------------------------------

MeasurementNoise unit_camera_noise() {
  // Shape used when no noise is given: isotropic camera noise, exact robot.
  // Only its shape matters; the scale is estimated from the residuals.
  MeasurementNoise noise;
  noise.camera.rotation = Matrix3d::Identity();
  noise.camera.translation = Matrix3d::Identity();
  return noise;
}

void check_noise_block(const MeasurementNoise& noise, const std::string& where) {
  check_covariance(noise.robot, where + ".robot");
  check_covariance(noise.camera, where + ".camera");
}

/// Per-item noise, with the rules shared by both inputs.
MeasurementNoise noise_for(const std::optional<MeasurementNoise>& item,
                           const std::optional<MeasurementNoise>& global, const std::string& where) {
  if (item) {
    if (!global) {
      throw HandEyeError(ErrorCode::InvalidNoise,
                         "a per-item noise is given but there is no global noise block", where,
                         "add a global `noise` block (it is the default for the other items), or "
                         "remove the per-item noise to have all noise estimated from the residuals");
    }
    check_noise_block(*item, where + ".noise");
    return *item;
  }
  return global ? *global : unit_camera_noise();
}

Problem build(const MotionSet& set) {
  Problem p;
  p.A.reserve(set.motions.size());
  p.B.reserve(set.motions.size());
  p.inputs.reserve(2 * set.motions.size());
  p.noise_given = set.noise.has_value();
  if (set.noise) check_noise_block(*set.noise, "noise");
  for (std::size_t i = 0; i < set.motions.size(); ++i) {
    const MotionPair& motion = set.motions[i];
    const std::string where = "motions[" + std::to_string(i) + "]";
    check_pose(motion.A, where + ".A");
    check_pose(motion.B, where + ".B");
    const MeasurementNoise noise = noise_for(motion.noise, set.noise, where);
    p.A.push_back(motion.A);
    p.B.push_back(motion.B);
    NoiseInput robot, camera;
    robot.covariance = noise.robot.as_pose_covariance();
    robot.robot = true;
    robot.add({static_cast<int>(i), true, -1});
    camera.covariance = noise.camera.as_pose_covariance();
    camera.robot = false;
    camera.add({static_cast<int>(i), false, -1});
    p.inputs.push_back(robot);
    p.inputs.push_back(camera);
  }
  return p;
}

Problem build(const SampleSet& set, int pair_window) {
  Problem p;
  p.noise_given = set.noise.has_value();
  p.samples = static_cast<int>(set.samples.size());
  if (set.noise) check_noise_block(*set.noise, "noise");
  const int n = static_cast<int>(set.samples.size());
  for (int s = 0; s < n; ++s) {
    const std::string where = "samples[" + std::to_string(s) + "]";
    check_pose(set.samples[s].T_base_effector, where + ".effector");
    check_pose(set.samples[s].T_camera_pattern, where + ".pattern");
  }
  // Each sample pairs with the next pair_window samples: all pairs for short
  // sessions (more, and more varied, motions), O(n w) for long streams.
  const int window = std::max(1, pair_window);
  for (int i = 0; i + 1 < n; ++i) {
    for (int j = i + 1; j < n && j - i <= window; ++j) p.pairs.push_back({i, j});
  }
  p.A.reserve(p.pairs.size());
  p.B.reserve(p.pairs.size());
  p.jacobians.reserve(4 * p.pairs.size());
  std::vector<NoiseInput> effector(n), pattern(n);
  for (int s = 0; s < n; ++s) {
    const MeasurementNoise noise = noise_for(set.samples[s].noise, set.noise, "samples[" + std::to_string(s) + "]");
    effector[s].covariance = noise.robot.as_pose_covariance();
    effector[s].robot = true;
    pattern[s].covariance = noise.camera.as_pose_covariance();
    pattern[s].robot = false;
  }
  for (std::size_t m = 0; m < p.pairs.size(); ++m) {
    const auto [i, j] = p.pairs[m];
    const MotionPair motion = motion_between(set.rig, set.samples[i], set.samples[j]);
    p.A.push_back(motion.A);
    p.B.push_back(motion.B);
    const Isometry3d& Pi = set.samples[i].T_camera_pattern;
    const Isometry3d& Pj = set.samples[j].T_camera_pattern;
    // A = V_j V_i^-1 (rig.h); B = Pj Pi^-1.
    const auto [dA_dEi, dA_dEj] = set.rig.robot_motion_jacobians(set.samples[i].T_base_effector, set.samples[j].T_base_effector);
    const int motion_index = static_cast<int>(m);
    effector[j].add({motion_index, true, p.add_jacobian(dA_dEj)});
    effector[i].add({motion_index, true, p.add_jacobian(dA_dEi)});
    pattern[j].add({motion_index, false, p.add_jacobian(compose_jacobian_left(Pj, Pi.inverse()))});
    pattern[i].add({motion_index, false, p.add_jacobian(compose_jacobian_right(Pj) * inverse_jacobian(Pi))});
  }
  for (int s = 0; s < n; ++s) {
    p.inputs.push_back(std::move(effector[s]));
    p.inputs.push_back(std::move(pattern[s]));
  }
  return p;
}

// ---------------------------------------------------------------------------
// The pipeline.
// ---------------------------------------------------------------------------

Matrix3d park_martin_rotation(const std::vector<Vector3d>& alpha, const std::vector<Vector3d>& beta) {
  // Motions near pi have an ambiguous log sign; leave them out of the closed
  // form when enough others remain (they are used by the iterative stage).
  Matrix3d M = Matrix3d::Zero();
  int used = 0;
  for (std::size_t i = 0; i < alpha.size(); ++i) {
    if (std::max(alpha[i].norm(), beta[i].norm()) < M_PI - 0.3) {
      M += beta[i] * alpha[i].transpose();
      ++used;
    }
  }
  if (used < 2) {
    M.setZero();
    for (std::size_t i = 0; i < alpha.size(); ++i) M += beta[i] * alpha[i].transpose();
  }
  // R = (M^T M)^-1/2 M^T, computed as the closest rotation to M^T (polar factor).
  Eigen::JacobiSVD<Matrix3d> svd(M.transpose(), Eigen::ComputeFullU | Eigen::ComputeFullV);
  Matrix3d D = Matrix3d::Identity();
  D(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1.0 : 1.0;
  return svd.matrixU() * D * svd.matrixV().transpose();
}

struct StageSolution {
  Matrix3d R;
  StageDiagnostics rotation_stage;
  RotationGains gains;
  Matrix3d sigma_R;
  Matrix3d per_pair_rotation_covariance;  // eq. (35)
  TranslationResult translation;
};

StageSolution solve_stages(const Problem& problem, RotationData& d, const Matrix3d& R0,
                           const NoiseScale& scale, const SolverOptions& options) {
  StageSolution s;
  const Marginals m = marginals(problem, scale);
  update_log_covariances(d, m);
  const RotationResult rotation = solve_rotation(R0, d, problem, options);
  s.R = rotation.R;
  s.rotation_stage = rotation.diagnostics;
  s.gains = rotation_gains(s.R, rotation.linearization, d);
  s.sigma_R = rotation_covariance(problem, scale, s.gains);
  s.per_pair_rotation_covariance = rotation.linearization.information.inverse();
  s.translation = solve_translation(unweighted_translation(s.R, problem.A, problem.B), s.R, s.sigma_R, m,
                                    problem, options);
  return s;
}

Calibration solve_problem(const Problem& problem, const SolverOptions& options) {
  RotationData d = rotation_data(problem);
  NoiseScale scale;
  update_log_covariances(d, marginals(problem, scale));
  check_motion_rotations(motion_rotations(problem, d), options);

  const Matrix3d R0 = park_martin_rotation(d.alpha, d.beta);
  align_representatives(R0, d);

  Calibration result;
  result.initial_guess = se3::make_pose(R0, unweighted_translation(R0, problem.A, problem.B));
  result.motions_used = static_cast<int>(problem.size());
  result.samples_used = problem.samples;

  // The expected chi^2 of each stage at its minimum: 3k minus what the fit
  // absorbs, tr(S Sigma) with S the stage's information and Sigma the sandwich
  // covariance. For independent motions that is 3k - 3; correlated motions
  // (pose streams, above all with many pairs) absorb much more, and dividing
  // by 3k - 3 would underestimate the noise.
  const auto expected_chi2 = [&](const StageSolution& st, const Matrix6d& covariance) {
    const double all = 3.0 * static_cast<double>(problem.size());
    const Matrix3d S = st.per_pair_rotation_covariance.inverse();
    return std::pair<double, double>{
        std::max(1.0, all - (S * covariance.bottomRightCorner<3, 3>()).trace()),
        std::max(1.0, all - (st.translation.linearization.information * covariance.topLeftCorner<3, 3>()).trace())};
  };

  StageSolution s;
  if (problem.noise_given) {
    s = solve_stages(problem, d, R0, scale, options);
  } else {
    // Variance-component estimation: scale the rotation noise until the
    // rotation chi^2 equals its expectation, then the translation noise likewise.
    const int dof = 3 * static_cast<int>(problem.size()) - 3;
    if (dof < 6) {
      throw HandEyeError(ErrorCode::NoiseUnidentifiable,
                         "no noise was given and " + std::to_string(problem.size()) +
                             " motions are too few to estimate it from the residuals (need >= 3)",
                         "input", "add a `noise` block with the pose covariances, or record more samples");
    }
    constexpr double kFloor = 1e-24;  // (1e-12 rad or m)^2: noise-free input
    scale.translation = 1e-6;
    s = solve_stages(problem, d, R0, scale, options);
    scale.rotation = std::max(
        kFloor, s.rotation_stage.chi2 /
                    expected_chi2(s, pose_covariance(problem, scale, s.R, s.translation, s.gains)).first);
    for (int round = 0; round < 30; ++round) {
      s = solve_stages(problem, d, s.R, scale, options);
      const double ratio = s.translation.diagnostics.chi2 /
                           expected_chi2(s, pose_covariance(problem, scale, s.R, s.translation, s.gains)).second;
      scale.translation = std::max(kFloor, scale.translation * ratio);
      if (std::abs(ratio - 1.0) < 1e-3 || scale.translation == kFloor) break;
    }
    s = solve_stages(problem, d, s.R, scale, options);
    result.noise_origin = NoiseOrigin::EstimatedFromResiduals;
    MeasurementNoise estimated;
    estimated.camera.rotation = scale.rotation * Matrix3d::Identity();
    estimated.camera.translation = scale.translation * Matrix3d::Identity();
    result.noise = estimated;
  }
  if (problem.noise_given) {
    // The global block is representative; per-item overrides are not summarised.
    for (const NoiseInput& input : problem.inputs) {
      (input.robot ? result.noise.robot : result.noise.camera) = PoseNoise::from_pose_covariance(input.covariance);
    }
  }

  result.T_parent_camera = se3::make_pose(s.R, s.translation.state.t);
  result.rotation_stage = s.rotation_stage;
  result.translation_stage = s.translation.diagnostics;
  set_pose_covariance(result, pose_covariance(problem, scale, s.R, s.translation, s.gains));
  result.per_pair_covariance.rotation = s.per_pair_rotation_covariance;
  result.per_pair_covariance.translation = s.translation.linearization.information.inverse();
  const auto [expected_rotation, expected_translation] = expected_chi2(s, result.pose_covariance);
  result.rotation_stage.dof = static_cast<int>(std::lround(expected_rotation));
  result.translation_stage.dof = static_cast<int>(std::lround(expected_translation));

  const double rotation_sigma = max_sigma(result.rotation_covariance);
  if (!(rotation_sigma <= options.max_rotation_sigma)) {
    throw HandEyeError(ErrorCode::PoorlyConstrained,
                       "the motions constrain the rotation only to " + number_text(degrees(rotation_sigma)) +
                           " deg (1 sigma); a first-order covariance is not valid there",
                       "input", "add samples with larger rotations about different axes, or reduce the noise");
  }
  if (problem.noise_given) {
    for (const auto* stage : {&result.rotation_stage, &result.translation_stage}) {
      const double ratio = stage->chi2 / std::max(1, stage->dof);
      if (stage->dof >= 9 && ratio > 3.0) {
        Warning w;
        w.kind = Warning::Kind::StageAboveStatedNoise;
        w.rotation_stage = stage == &result.rotation_stage;
        w.chi2_per_dof = ratio;
        result.warnings.push_back(w);
      }
    }
  }
  return result;
}

}  // namespace

void set_pose_covariance(Calibration& c, const Matrix6d& covariance) {
  c.pose_covariance = covariance;
  c.translation_covariance = covariance.topLeftCorner<3, 3>();
  c.rotation_covariance = covariance.bottomRightCorner<3, 3>();
}

void scale_covariances(Calibration& c, double k) {
  c.pose_covariance *= k;
  c.rotation_covariance *= k;
  c.translation_covariance *= k;
  c.cross_covariance *= k;
  if (c.pattern) c.pattern->covariance *= k;
}

Eigen::Matrix<double, 12, 12> joint_covariance(const Calibration& calibration) {
  Eigen::Matrix<double, 12, 12> sigma = Eigen::Matrix<double, 12, 12>::Zero();
  sigma.topLeftCorner<6, 6>() = calibration.pose_covariance;
  if (calibration.pattern) {
    sigma.bottomRightCorner<6, 6>() = calibration.pattern->covariance;
    sigma.topRightCorner<6, 6>() = calibration.cross_covariance;
    sigma.bottomLeftCorner<6, 6>() = calibration.cross_covariance.transpose();
  }
  return 0.5 * (sigma + sigma.transpose());
}

Eigen::Isometry3d park_martin(const std::vector<MotionPair>& motions) {
  MotionSet set;
  set.motions = motions;
  const Problem problem = build(set);
  if (problem.size() < 2) {
    throw HandEyeError(ErrorCode::TooFewMotions, "Park-Martin needs at least 2 motions", "input",
                       "record more samples");
  }
  RotationData d = rotation_data(problem);
  const Matrix3d R = park_martin_rotation(d.alpha, d.beta);
  return se3::make_pose(R, unweighted_translation(R, problem.A, problem.B));
}

Eigen::Isometry3d checked_initial_guess(const SampleSet& samples, const SolverOptions& options) {
  const std::size_t n = samples.samples.size();
  if (n < 3) {
    throw HandEyeError(ErrorCode::TooFewMotions,
                       "got " + std::to_string(n) + " sample(s); at least 3 are needed (2 motions)", "samples",
                       "record more samples (10-30 poses rotating about different axes is typical)");
  }
  if (samples.noise) check_noise_block(*samples.noise, "noise");
  // Consecutive motions, O(n): the rotation angles with the sigma of their
  // difference (rotation blocks only: B = P_j P_i^-1 has Sigma_Pj + R_B Sigma_Pi R_B^T,
  // A likewise through the rig's Jacobians), then Park-Martin.
  const Rig& rig = samples.rig;
  MotionRotations m;
  m.noise_given = samples.noise.has_value();
  std::vector<Isometry3d> A(n - 1), B(n - 1);
  m.alpha.resize(n - 1), m.beta.resize(n - 1), m.sigma.assign(n - 1, 0.0);
  const auto noise_of = [&](std::size_t i) -> const MeasurementNoise& {
    return samples.samples[i].noise ? *samples.samples[i].noise : *samples.noise;
  };
  for (std::size_t i = 0; i + 1 < n; ++i) {
    const PoseSample &from = samples.samples[i], &to = samples.samples[i + 1];
    A[i] = rig.robot_motion(from.T_base_effector, to.T_base_effector);
    B[i] = to.T_camera_pattern * from.T_camera_pattern.inverse();
    m.alpha[i] = so3::log(A[i].linear());
    m.beta[i] = so3::log(B[i].linear());
    if (!m.noise_given) continue;
    const Matrix3d sigma_A = rig.robot_motion_rotation_covariance(from.T_base_effector, to.T_base_effector,
                                                                  noise_of(i).robot.rotation, noise_of(i + 1).robot.rotation);
    const Matrix3d& R_B = B[i].linear();
    const Matrix3d sigma_B = noise_of(i + 1).camera.rotation + R_B * noise_of(i).camera.rotation * R_B.transpose();
    m.sigma[i] = std::hypot(angle_sigma(m.alpha[i], sigma_A), angle_sigma(m.beta[i], sigma_B));
  }
  m.label = [](std::size_t i) { return "samples[" + std::to_string(i) + "] -> samples[" + std::to_string(i + 1) + "]"; };
  check_motion_rotations(m, options);
  const Matrix3d R = park_martin_rotation(m.alpha, m.beta);
  return se3::make_pose(R, unweighted_translation(R, A, B));
}

Calibration solve(const MotionSet& motions, const SolverOptions& options) {
  return solve_problem(build(motions), options);
}

Calibration solve(const SampleSet& samples, const SolverOptions& options) {
  if (samples.samples.size() < 3) {
    throw HandEyeError(ErrorCode::TooFewMotions,
                       "got " + std::to_string(samples.samples.size()) +
                           " sample(s); at least 3 are needed (2 motions)",
                       "samples", "record more samples (10-30 poses rotating about different axes is typical)");
  }
  return solve_problem(build(samples, options.pair_window), options);
}

}  // namespace handeye
