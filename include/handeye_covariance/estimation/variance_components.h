// Noise from the residuals: variance components of 6-vector residuals, by REML
// Fisher scoring (Harville 1977; the "variance components" of linear mixed models).
//
// Each sample i has a residual e_i (6) whose covariance is modelled as
//     S_i(theta) = S0_i + sum_k theta_k F_ik F_ik^T,
// with S0_i known (a stated noise, or zero) and each component k given per
// sample by a factor F_ik (6 x r_k): a camera axis (e_j), a robot block mapped
// into the residual (D_i's columns), a stated covariance to be scaled (its
// square root), ... The fit is restricted maximum likelihood: the residuals come
// from a fit that absorbed some of them, so each sample's scatter e e^T is
// completed by what the fit took, M_i = e_i e_i^T + J_i Sigma J_i^T (J_i the
// residual's Jacobian to the fitted parameters, Sigma their covariance). The
// REML score and expected information are then, per component,
//     g_k  = 1/2 sum_i tr(A_i F_k F_k^T A_i (M_i - S_i)),      A_i = S_i^-1,
//     F_kl = 1/2 sum_i ||F_ik^T A_i F_il||_F^2,
// and theta <- theta + F^-1 g, halved while the likelihood does not rise or a
// bound is crossed. F^-1 at the solution is the covariance of theta_hat: how
// well the residuals determine each component, and whether two of them can be
// told apart (their correlation).
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "handeye_covariance/core/lie.h"

namespace handeye {

struct VarianceComponent {
  std::string name;
  /// theta_k >= lower (a variance: 0; a scale of a stated noise: > 0). Components
  /// with lower = -infinity (covariances between axes) are kept by checking that
  /// every S_i stays positive definite instead.
  double lower = 0.0;
};

/// Every component's factor side by side: at most kMaxFactorColumns columns (no heap):
/// a camera scale or a view's shape (6), the robot's translation and rotation (3 + 3),
/// or the camera's translation and rotation (3 + 3).
constexpr int kMaxFactorColumns = 18;
using ComponentFactors = Eigen::Matrix<double, 6, Eigen::Dynamic, 0, 6, kMaxFactorColumns>;

struct VarianceComponentData {
  std::vector<Matrix6d> fixed;     // S0_i
  std::vector<Matrix6d> scatter;   // M_i = e e^T + J Sigma J^T
  /// factors[i] holds the factors of every component side by side (6 x sum r_k);
  /// columns[k] is where component k's factor starts, ranks[k] its width.
  std::vector<ComponentFactors> factors;
  std::vector<int> columns, ranks;
  /// A component with rank 0 is one entry of a covariance shared by every sample:
  /// entries[k] = (a, b) adds theta_k (e_a e_b^T + e_b e_a^T), or theta_k e_a e_a^T
  /// when a == b. Its score and information come from S_i^-1's own entries.
  std::vector<std::pair<int, int>> entries;
  /// Optional: each S_i(theta0)^-1's factor L^-1 (S_i = L L^T) at the start theta0,
  /// when the caller has just computed it (a solve under theta0 whitens with the
  /// same S_i): the first evaluation then skips its Cholesky factors. Empty: computed.
  std::vector<Matrix6d> start_whitening;
};

struct VarianceComponentFit {
  Eigen::VectorXd theta;
  Eigen::MatrixXd covariance;   // of theta_hat: the inverse expected information (0 for components at a bound)
  Eigen::MatrixXd information;  // the expected information at theta_hat
  double log_likelihood = 0.0;  // the REML criterion at theta (up to a constant)
  int iterations = 0;
  bool converged = false;
  std::vector<bool> at_bound;  // theta_k at its lower bound: the residuals do not support it
};

struct VarianceComponentOptions {
  int max_iterations = 30;
  double tolerance = 1e-3;  // stop when every |step_k| < tolerance * sqrt(covariance_kk)
  /// Take the last iteration's step without an evaluation to confirm it, for a
  /// caller that checks the fit by other means. The step is shortened so that no
  /// number loses more than half of its distance to its bound and every S_i stays
  /// positive definite; the covariance is the one at the point it started from.
  bool confirm_last_step = true;
};

/// Fisher scoring from theta0 (within the bounds). Throws nothing; a component
/// whose information is zero stays where it started and is reported at_bound.
VarianceComponentFit fit_variance_components(const std::vector<VarianceComponent>& components,
                                             const VarianceComponentData& data, const Eigen::VectorXd& theta0,
                                             const VarianceComponentOptions& options = {});

/// S = L L^T (Cholesky, written out for 6x6) and L^-1 (lower triangular); false
/// when S is not positive definite. Eigen's LLT solves route fixed 6x12 and 6x6
/// right-hand sides through its large-matrix kernels, which cost more than the
/// arithmetic at this size; the estimators call this for every sample.
bool inverse_cholesky(const Matrix6d& S, Matrix6d& L_inverse);

/// L^-1 for the lower triangle of L, by forward substitution; with unit_diagonal,
/// L's diagonal is read as ones (an LDLT's L). For the small inverses whose Eigen
/// solves against the identity take its blocked kernels.
template <typename Matrix>
Matrix lower_triangular_inverse(const Matrix& L, bool unit_diagonal) {
  const Eigen::Index n = L.rows();
  Matrix inverse = Matrix::Zero(n, n);
  for (Eigen::Index j = 0; j < n; ++j) {
    inverse(j, j) = unit_diagonal ? 1.0 : 1.0 / L(j, j);
    for (Eigen::Index i = j + 1; i < n; ++i) {
      double sum = 0.0;
      for (Eigen::Index k = j; k < i; ++k) sum += L(i, k) * inverse(k, j);
      inverse(i, j) = unit_diagonal ? -sum : -sum / L(i, i);
    }
  }
  return inverse;
}

/// The one-sided score test of component k at its lower bound, the others held at
/// theta (theta_k is read as the bound): is the component worth fitting? With g_k
/// the REML score and I the expected information, I_eff = I_kk - I_ko I_oo^-1 I_ok
/// (what k adds beside the others), the statistic is g_k^2 / I_eff when g_k > 0 and
/// 0 otherwise: to first order the rise of twice the log-likelihood a fit of k would
/// bring (a half chi2(1) mixture when k adds nothing). `step` is g_k / I_eff, a
/// Fisher step from the bound, a start for that fit.
struct ScoreTest {
  double statistic = 0.0;
  double step = 0.0;
};
ScoreTest score_test(const VarianceComponentData& data, const Eigen::VectorXd& theta, int k);

/// Adds a component to `data` (factor columns, or a shared covariance entry).
void add_factor_component(VarianceComponentData& data, int rank);
void add_entry_component(VarianceComponentData& data, int a, int b);

/// S_i at theta.
Matrix6d component_covariance(const VarianceComponentData& data, std::size_t i, const Eigen::VectorXd& theta);

}  // namespace handeye
