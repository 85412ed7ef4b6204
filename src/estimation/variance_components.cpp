#include "handeye_covariance/estimation/variance_components.h"

#include <Eigen/Cholesky>
#include <cmath>
#include <limits>

namespace handeye {

using Eigen::MatrixXd;
using Eigen::VectorXd;

namespace {

/// theta expanded to one weight per factor column, and the shared entries' matrix.
VectorXd column_weights(const VarianceComponentData& data, const VectorXd& theta) {
  int width = 0;
  for (std::size_t k = 0; k < data.columns.size(); ++k) width = std::max(width, data.columns[k] + data.ranks[k]);
  VectorXd w(width);
  for (std::size_t k = 0; k < data.columns.size(); ++k) {
    if (data.ranks[k] > 0) w.segment(data.columns[k], data.ranks[k]).setConstant(theta[k]);
  }
  return w;
}

Matrix6d shared_entries(const VarianceComponentData& data, const VectorXd& theta) {
  Matrix6d C = Matrix6d::Zero();
  for (std::size_t k = 0; k < data.entries.size(); ++k) {
    const auto [a, b] = data.entries[k];
    if (a < 0) continue;
    C(a, b) += theta[k];
    if (a != b) C(b, a) += theta[k];
  }
  return C;
}

/// S_i(theta) = fixed_i + shared + F_i diag(w) F_i^T, from theta's column weights
/// and shared entries (read once per evaluation, not per sample).
Matrix6d sample_covariance(const VarianceComponentData& data, std::size_t i, const VectorXd& w, const Matrix6d& shared) {
  const ComponentFactors& F = data.factors[i];
  Matrix6d S = data.fixed[i] + shared;
  // Column by column (fixed 6-vector updates): Eigen's outer product of a
  // dynamic-width factor's column takes about twice the instructions.
  for (int c = 0; c < static_cast<int>(F.cols()); ++c) {
    const Vector6d f = w[c] * F.col(c);
    for (int b = 0; b < 6; ++b) S.col(b) += F(b, c) * f;
  }
  return S;
}

struct Evaluation {
  double log_likelihood = -std::numeric_limits<double>::infinity();  // -inf: some S_i not positive definite
  VectorXd score;
  MatrixXd information;          // expected: 1/2 tr(A G_k A G_l), for the covariance of theta
  MatrixXd average_information;  // AI-REML: 1/2 tr(A G_k A G_l A M), for the steps (near Newton's)
};

/// One (entry k, entry l <= k) pair of the information's entry block, with its
/// indices read once per evaluation rather than per sample.
struct EntryPair {
  int k, l, a, b, c, d;
  double half;
};

/// The REML criterion at theta with its score, expected and average information
/// (every caller needs the derivatives at the point it evaluates).
Evaluation evaluate(const VarianceComponentData& data, const VectorXd& theta, bool at_start = false) {
  const int K = static_cast<int>(data.columns.size());
  const VectorXd w = column_weights(data, theta);
  const Matrix6d shared = shared_entries(data, theta);
  std::vector<int> factor_components, entry_components;
  for (int k = 0; k < K; ++k) (data.ranks[k] > 0 ? factor_components : entry_components).push_back(k);
  // Pairs of diagonal entries (the per-axis variances) are summed as whole 6x6
  // matrices, A o A and A o Q, and read out after the loop; the others per pair.
  std::vector<EntryPair> pairs, diagonal_pairs;
  for (int k : entry_components) {
    for (int l : entry_components) {
      if (l > k) continue;
      const auto [a, b] = data.entries[k];
      const auto [c, d] = data.entries[l];
      (a == b && c == d ? diagonal_pairs : pairs).push_back({k, l, a, b, c, d, (a == b ? 0.5 : 1.0) * (c == d ? 0.5 : 1.0)});
    }
  }
  // A diagonal entry k = (a, a) against a factor l: 1/2 sum_c (A F)_ac^2 and
  // 1/2 sum_c (A F)_ac (Q F)_ac over l's columns, summed per row a.
  std::vector<int> diagonal_entries, other_entries;
  for (int k : entry_components) (data.entries[k].first == data.entries[k].second ? diagonal_entries : other_entries).push_back(k);
  Matrix6d sum_AA = Matrix6d::Zero(), sum_AQ = Matrix6d::Zero(), sum_B = Matrix6d::Zero();
  using Columns = Eigen::Matrix<double, 6, kMaxFactorColumns>;
  Columns rows_AA = Columns::Zero(), rows_AQ = Columns::Zero();
  std::vector<double> pair_information(pairs.size(), 0.0), pair_average(pairs.size(), 0.0);
  Evaluation ev;
  double log_likelihood = 0.0;
  ev.score = VectorXd::Zero(K), ev.information = MatrixXd::Zero(K, K), ev.average_information = MatrixXd::Zero(K, K);
  // The factors are handled column by column (fixed 6-vectors), so that no
  // product runs through Eigen's dynamic-size kernels.
  Columns AF, QF;
  Eigen::Matrix<double, kMaxFactorColumns, kMaxFactorColumns> Z, W;  // F^T A F, F^T Q F
  for (std::size_t i = 0; i < data.fixed.size(); ++i) {
    const ComponentFactors& F = data.factors[i];
    const int width = static_cast<int>(F.cols());
    Matrix6d L_inverse;
    if (at_start) L_inverse = data.start_whitening[i];
    else if (!inverse_cholesky(sample_covariance(data, i, w, shared), L_inverse)) return ev;
    const Matrix6d A = L_inverse.transpose().lazyProduct(L_inverse);
    // log det S = -2 log prod diag(L^-1): one log per sample (the product of six
    // reciprocal standard deviations stays far inside double's range).
    log_likelihood -= 0.5 * (-2.0 * std::log(L_inverse.diagonal().prod()) + A.cwiseProduct(data.scatter[i]).sum());
    const Matrix6d AM = A.lazyProduct(data.scatter[i]);  // evaluated: a nested lazy product recomputes it per entry
    const Matrix6d Q = AM.lazyProduct(A);                // A M A; the score's kernel is Q - A
    const Matrix6d B = Q - A;
    for (int c = 0; c < width; ++c) AF.col(c).noalias() = A * F.col(c), QF.col(c).noalias() = Q * F.col(c);
    for (int c1 = 0; c1 < width; ++c1) {
      for (int c2 = 0; c2 < width; ++c2) Z(c1, c2) = F.col(c1).dot(AF.col(c2)), W(c1, c2) = F.col(c1).dot(QF.col(c2));
    }
    // Score 1/2 tr(B G_k), information 1/2 tr(A G_k A G_l), average information
    // 1/2 tr(A G_k A G_l Q), by the kind of G. G_ab = e_a e_b^T + e_b e_a^T, or
    // e_a e_a^T when a == b (each diagonal counts half).
    for (int k : factor_components) {
      const int ck = data.columns[k], rk = data.ranks[k];
      double score = 0.0;
      for (int c = ck; c < ck + rk; ++c) score += F.col(c).dot(QF.col(c) - AF.col(c));
      ev.score[k] += 0.5 * score;
      for (int l : factor_components) {
        if (l > k) continue;
        const auto z = Z.block(ck, data.columns[l], rk, data.ranks[l]);
        ev.information(k, l) += 0.5 * z.squaredNorm();
        ev.average_information(k, l) += 0.5 * z.cwiseProduct(W.block(ck, data.columns[l], rk, data.ranks[l])).sum();
      }
    }
    sum_B += B;
    if (!diagonal_pairs.empty()) sum_AA.noalias() += A.cwiseProduct(A), sum_AQ.noalias() += A.cwiseProduct(Q);
    if (!diagonal_entries.empty()) {
      for (int c = 0; c < width; ++c) {
        rows_AA.col(c).noalias() += AF.col(c).cwiseProduct(AF.col(c));
        rows_AQ.col(c).noalias() += AF.col(c).cwiseProduct(QF.col(c));
      }
    }
    for (int k : other_entries) {
      const auto [a, b] = data.entries[k];
      for (int l : factor_components) {
        const int cl = data.columns[l], rl = data.ranks[l];
        const double half = a == b ? 0.5 : 1.0;
        double e = 0.0, ai = 0.0;
        for (int c = cl; c < cl + rl; ++c) {
          e += AF(a, c) * AF(b, c);
          ai += AF(b, c) * QF(a, c) + AF(a, c) * QF(b, c);
        }
        const int r = std::max(k, l), col = std::min(k, l);
        ev.information(r, col) += half * e;
        ev.average_information(r, col) += half * 0.5 * ai;
      }
    }
    for (std::size_t p = 0; p < pairs.size(); ++p) {
      const auto& [k, l, a, b, c, d, half] = pairs[p];
      pair_information[p] += half * (A(a, c) * A(b, d) + A(a, d) * A(b, c));
      pair_average[p] += 0.5 * half * (A(b, c) * Q(d, a) + A(b, d) * Q(c, a) + A(a, c) * Q(d, b) + A(a, d) * Q(c, b));
    }
  }
  for (std::size_t p = 0; p < pairs.size(); ++p) {
    ev.information(pairs[p].k, pairs[p].l) += pair_information[p];
    ev.average_information(pairs[p].k, pairs[p].l) += pair_average[p];
  }
  // The whole-matrix sums: for (a, a) and (c, c), 1/2 A_ac^2 and 1/2 A_ac Q_ca.
  for (const EntryPair& p : diagonal_pairs) {
    ev.information(p.k, p.l) += 0.5 * sum_AA(p.a, p.c);
    ev.average_information(p.k, p.l) += 0.5 * sum_AQ(p.a, p.c);
  }
  for (int k : entry_components) {
    const auto [a, b] = data.entries[k];
    ev.score[k] += a == b ? 0.5 * sum_B(a, a) : sum_B(a, b);
  }
  for (int k : diagonal_entries) {
    const int a = data.entries[k].first;
    for (int l : factor_components) {
      const int r = std::max(k, l), col = std::min(k, l);
      ev.information(r, col) += 0.5 * rows_AA.row(a).segment(data.columns[l], data.ranks[l]).sum();
      ev.average_information(r, col) += 0.5 * rows_AQ.row(a).segment(data.columns[l], data.ranks[l]).sum();
    }
  }
  ev.information = ev.information.selfadjointView<Eigen::Lower>();
  ev.average_information = ev.average_information.selfadjointView<Eigen::Lower>();
  ev.log_likelihood = log_likelihood;
  return ev;
}

/// The inverse of a small symmetric matrix from its LDLT, P^T L^-T D^-1 L^-1 P, with a
/// zero pivot's reciprocal taken as 0 as LDLT::solve does. Solving against the
/// identity takes Eigen's blocked solver, several times the work at a fit's size.
MatrixXd inverse_of(const Eigen::LDLT<MatrixXd>& ldlt) {
  const Eigen::Index n = ldlt.rows();
  const MatrixXd L_inverse = lower_triangular_inverse(ldlt.matrixLDLT(), true);  // unit L below the diagonal
  VectorXd d_inverse(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const double d = ldlt.vectorD()[i];
    d_inverse[i] = std::abs(d) > std::numeric_limits<double>::min() ? 1.0 / d : 0.0;
  }
  // (L D L^T)^-1 entry by entry (products of this size would take Eigen's GEMM path),
  // then A^-1 = P^T (L D L^T)^-1 P.
  const Eigen::PermutationMatrix<Eigen::Dynamic> P(ldlt.transpositionsP());
  const auto& where = P.indices();  // (P x)_where[i] = x_i
  MatrixXd out(n, n);
  for (Eigen::Index a = 0; a < n; ++a) {
    for (Eigen::Index b = 0; b <= a; ++b) {
      double sum = 0.0;
      for (Eigen::Index k = a; k < n; ++k) sum += L_inverse(k, a) * d_inverse[k] * L_inverse(k, b);
      out(b, a) = sum;
    }
  }
  MatrixXd inverse(n, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    for (Eigen::Index j = 0; j < n; ++j) {
      const Eigen::Index a = std::max(where[i], where[j]), b = std::min(where[i], where[j]);
      inverse(i, j) = out(b, a);
    }
  }
  return inverse;
}

/// Whether every S_i(theta) is positive definite (what an evaluation would find
/// first), for a step taken without one.
bool positive_definite(const VarianceComponentData& data, const VectorXd& theta) {
  const VectorXd w = column_weights(data, theta);
  const Matrix6d shared = shared_entries(data, theta);
  // A positive diagonal shared part plus covariances (the fixed part, factors
  // with non-negative weights) is positive definite: no need to look further.
  if (shared.isDiagonal(0.0) && (shared.diagonal().array() > 0.0).all() && (w.array() >= 0.0).all()) return true;
  for (std::size_t i = 0; i < data.fixed.size(); ++i) {
    if (Eigen::LLT<Matrix6d>(sample_covariance(data, i, w, shared)).info() != Eigen::Success) return false;
  }
  return true;
}

}  // namespace

namespace {

// Column J of L (S = L L^T), by fixed-size blocks so that every product unrolls.
template <int J>
bool cholesky_columns(const Matrix6d& S, Matrix6d& L, double* reciprocal) {
  if constexpr (J == 6) {
    return true;
  } else {
    double diagonal = S(J, J);
    if constexpr (J > 0) diagonal -= L.template block<1, J>(J, 0).squaredNorm();
    if (!(diagonal > 0.0)) return false;
    L(J, J) = std::sqrt(diagonal);
    reciprocal[J] = 1.0 / L(J, J);  // one division per column, the rest multiplications
    if constexpr (J < 5) {
      auto below = L.template block<5 - J, 1>(J + 1, J);
      below = S.template block<5 - J, 1>(J + 1, J);
      if constexpr (J > 0) below.noalias() -= L.template block<5 - J, J>(J + 1, 0) * L.template block<1, J>(J, 0).transpose();
      below *= reciprocal[J];
    }
    return cholesky_columns<J + 1>(S, L, reciprocal);
  }
}

// Row I of L^-1 by forward substitution: L(I, :I) X(:I, :) + L(I, I) X(I, :) = e_I^T.
template <int I>
void inverse_rows(const Matrix6d& L, const double* reciprocal, Matrix6d& L_inverse) {
  if constexpr (I < 6) {
    Eigen::Matrix<double, 1, 6> row = Eigen::Matrix<double, 1, 6>::Zero();
    row(I) = 1.0;
    if constexpr (I > 0) row.noalias() -= L.template block<1, I>(I, 0) * L_inverse.template topRows<I>();
    L_inverse.row(I) = row * reciprocal[I];
    inverse_rows<I + 1>(L, reciprocal, L_inverse);
  }
}

}  // namespace

bool inverse_cholesky(const Matrix6d& S, Matrix6d& L_inverse) {
  Matrix6d L = Matrix6d::Zero();
  double reciprocal[6];
  if (!cholesky_columns<0>(S, L, reciprocal)) return false;
  inverse_rows<0>(L, reciprocal, L_inverse);
  return true;
}

ScoreTest score_test(const VarianceComponentData& data, const VectorXd& theta, int k) {
  VectorXd at = theta;
  at[k] = 0.0;
  const Evaluation ev = evaluate(data, at);
  ScoreTest out;
  const double g = ev.score[k];
  if (!std::isfinite(ev.log_likelihood) || !(g > 0.0)) return out;
  // The others' information block, those with any (a number at a bound still counts).
  std::vector<int> others;
  for (int l = 0; l < static_cast<int>(theta.size()); ++l) {
    if (l != k && ev.information(l, l) > 0.0) others.push_back(l);
  }
  double effective = ev.information(k, k);
  if (!others.empty()) {
    MatrixXd I_oo(others.size(), others.size());
    VectorXd I_ok(others.size());
    for (std::size_t a = 0; a < others.size(); ++a) {
      I_ok[a] = ev.information(others[a], k);
      for (std::size_t b = 0; b < others.size(); ++b) I_oo(a, b) = ev.information(others[a], others[b]);
    }
    effective -= I_ok.dot(I_oo.ldlt().solve(I_ok));
  }
  if (!(effective > 0.0)) return out;
  out.statistic = g * g / effective;
  out.step = g / effective;
  return out;
}

void add_factor_component(VarianceComponentData& data, int rank) {
  int column = 0;
  for (std::size_t k = 0; k < data.columns.size(); ++k) column = std::max(column, data.columns[k] + data.ranks[k]);
  data.columns.push_back(column), data.ranks.push_back(rank), data.entries.emplace_back(-1, -1);
}

void add_entry_component(VarianceComponentData& data, int a, int b) {
  int column = 0;
  for (std::size_t k = 0; k < data.columns.size(); ++k) column = std::max(column, data.columns[k] + data.ranks[k]);
  data.columns.push_back(column), data.ranks.push_back(0), data.entries.emplace_back(a, b);
}

Matrix6d component_covariance(const VarianceComponentData& data, std::size_t i, const VectorXd& theta) {
  return sample_covariance(data, i, column_weights(data, theta), shared_entries(data, theta));
}

VarianceComponentFit fit_variance_components(const std::vector<VarianceComponent>& components,
                                             const VarianceComponentData& data, const VectorXd& theta0,
                                             const VarianceComponentOptions& options) {
  const int K = static_cast<int>(components.size());
  VarianceComponentFit fit;
  fit.theta = theta0;
  Evaluation current = evaluate(data, fit.theta, data.start_whitening.size() == data.fixed.size());
  for (int iteration = 1; iteration <= options.max_iterations && std::isfinite(current.log_likelihood); ++iteration) {
    fit.iterations = iteration;
    // Active set: a component at its bound stays there when its score, or its
    // Newton step given the others, points outwards; the step is then re-solved.
    std::vector<int> free;
    for (int k = 0; k < K; ++k) {
      const bool held = fit.theta[k] <= components[k].lower && current.score[k] <= 0.0;
      if (!held && current.average_information(k, k) > 0.0) free.push_back(k);
    }
    VectorXd step, variance;
    for (;;) {
      MatrixXd information(free.size(), free.size());
      VectorXd score(free.size());
      for (std::size_t a = 0; a < free.size(); ++a) {
        score[a] = current.score[free[a]];
        for (std::size_t b = 0; b < free.size(); ++b) information(a, b) = current.average_information(free[a], free[b]);
      }
      // Jacobi-scaled: translation and rotation variances differ by ~1e10.
      const VectorXd scale = information.diagonal().cwiseSqrt().cwiseInverse();
      const Eigen::LDLT<MatrixXd> ldlt(scale.asDiagonal() * information * scale.asDiagonal());
      step = scale.asDiagonal() * ldlt.solve(scale.asDiagonal() * score);
      variance = inverse_of(ldlt).diagonal().cwiseProduct(scale.cwiseAbs2());
      int outward = -1;
      for (std::size_t a = 0; a < free.size(); ++a) {
        if (fit.theta[free[a]] <= components[free[a]].lower && step[a] < 0.0) outward = static_cast<int>(a);
      }
      if (outward < 0) break;
      free.erase(free.begin() + outward);
    }
    if (free.empty()) {
      fit.converged = true;
      break;
    }
    if (!step.allFinite()) break;
    bool small = true;
    for (std::size_t a = 0; a < free.size(); ++a) {
      small = small && std::abs(step[a]) <= options.tolerance * std::sqrt(std::max(variance[a], 0.0));
    }
    // theta + alpha step, each number kept within its bound.
    const auto stepped = [&](double alpha) {
      VectorXd theta = fit.theta;
      for (std::size_t a = 0; a < free.size(); ++a) {
        const int k = free[a];
        theta[k] = std::max(components[k].lower, theta[k] + alpha * step[a]);
      }
      return theta;
    };
    if (small) {
      // Within the tolerance of each number's sigma: taken without an evaluation to
      // confirm it (the likelihood is flat there to second order), as Gauss-Newton does.
      fit.theta = stepped(1.0);
      fit.converged = true;
      break;
    }
    if (iteration == options.max_iterations && !options.confirm_last_step) {
      // Unconfirmed, so kept where the quadratic model holds: no number loses more
      // than half of its distance to its bound (clamped onto a variance's bound,
      // S_i can come out nearly singular, which only an evaluation would see), and
      // no S_i leaves the positive definite (an entry of a full 6x6 is unbounded):
      // halved until every S_i takes a Cholesky factor.
      double alpha = 1.0;
      for (std::size_t a = 0; a < free.size(); ++a) {
        const double room = fit.theta[free[a]] - components[free[a]].lower;
        if (step[a] < 0.0 && std::isfinite(room)) alpha = std::min(alpha, 0.5 * room / -step[a]);
      }
      bool inside = positive_definite(data, stepped(alpha));
      for (int halving = 0; halving < 30 && !inside; ++halving) alpha *= 0.5, inside = positive_definite(data, stepped(alpha));
      if (inside) fit.theta = stepped(alpha);
      break;
    }
    double alpha = 1.0;
    bool moved = false;
    for (int halving = 0; halving < 30; ++halving, alpha *= 0.5) {
      VectorXd theta = stepped(alpha);
      // With its derivatives at once: the full step is nearly always taken, and
      // the next iteration needs them at the point taken.
      Evaluation next = evaluate(data, theta);
      if (next.log_likelihood >= current.log_likelihood - 1e-12 * std::abs(current.log_likelihood)) {
        // A rise of 1e-6 in log-likelihood is nothing statistically: converged.
        small = next.log_likelihood - current.log_likelihood < 1e-6;
        fit.theta = theta;
        current = std::move(next);
        moved = true;
        break;
      }
    }
    if (small || !moved) {
      fit.converged = true;
      break;
    }
  }
  fit.log_likelihood = current.log_likelihood;
  fit.information = current.information;
  fit.at_bound.assign(K, false);
  for (int k = 0; k < K; ++k) fit.at_bound[k] = fit.theta[k] <= components[k].lower;
  // The covariance of the components that are not at a bound (those at one are held).
  fit.covariance = MatrixXd::Zero(K, K);
  if (std::isfinite(current.log_likelihood)) {
    std::vector<int> free;
    for (int k = 0; k < K; ++k) {
      if (!fit.at_bound[k] && current.information(k, k) > 0.0) free.push_back(k);
    }
    MatrixXd information(free.size(), free.size());
    for (std::size_t a = 0; a < free.size(); ++a) {
      for (std::size_t b = 0; b < free.size(); ++b) information(a, b) = current.information(free[a], free[b]);
    }
    const VectorXd scale = information.diagonal().cwiseSqrt().cwiseInverse();
    const MatrixXd inverse = scale.asDiagonal() * inverse_of((scale.asDiagonal() * information * scale.asDiagonal()).ldlt()) * scale.asDiagonal();
    for (std::size_t a = 0; a < free.size(); ++a) {
      for (std::size_t b = 0; b < free.size(); ++b) fit.covariance(free[a], free[b]) = inverse(a, b);
    }
  }
  return fit;
}

}  // namespace handeye
