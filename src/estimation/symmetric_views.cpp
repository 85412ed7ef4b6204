#include "handeye_covariance/estimation/solve.h"
#include "handeye_covariance/estimation/symmetric_views.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>

#include <Eigen/Eigenvalues>

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/core/statistics.h"
#include "handeye_covariance/estimation/noise_estimation.h"
#include "handeye_covariance/estimation/outliers.h"

namespace handeye {

using Eigen::Isometry3d;
using Eigen::Vector3d;

namespace {

const char* const kWhere = "decide_half_turns";

/// F is the identity: the target has one candidate per view.
bool is_identity(const Isometry3d& F) { return F.matrix().isApprox(Eigen::Matrix4d::Identity(), 1e-12); }

/// NonFinite for a pose with NaN or Inf; InvalidLayout for an F that is no half turn.
void check_input(const SampleSet& samples, const Isometry3d& F) {
  if (!F.matrix().allFinite()) {
    throw HandEyeError(ErrorCode::NonFinite, "the half turn F has NaN or Inf", kWhere,
                       "pass half_turn(target) (core/target.h)");
  }
  const Eigen::Matrix3d& R = F.linear();
  const bool rotation = (R.transpose() * R - Eigen::Matrix3d::Identity()).norm() < 1e-9 && R.determinant() > 0.0;
  if (!rotation || !(F * F).matrix().isApprox(Eigen::Matrix4d::Identity(), 1e-9) || is_identity(F)) {
    throw HandEyeError(ErrorCode::InvalidLayout, "F is not a turn by 180 degrees (F F must be the identity, F not)",
                       kWhere, "pass half_turn(target) (core/target.h): the turn about the target face's normal");
  }
  for (std::size_t i = 0; i < samples.samples.size(); ++i) {
    const PoseSample& s = samples.samples[i];
    if (!s.T_base_effector.matrix().allFinite() || !s.T_camera_pattern.matrix().allFinite()) {
      throw HandEyeError(ErrorCode::NonFinite, "a pose has NaN or Inf", "sample " + std::to_string(i),
                         "drop the sample or fix the detector's or the robot's output");
    }
  }
}

/// A rigid motion as a screw: its angle in [0, pi], its unit axis, and its pitch
/// omega . t (m; the translation along the axis).
struct Screw {
  double angle = 0.0;
  double pitch = 0.0;
};

Screw screw(const Isometry3d& T) {
  const Eigen::AngleAxisd a(T.linear());
  return {a.angle(), a.axis().dot(T.translation())};
}

/// How far apart A's and B's screws are: angle, and pitch when both rotate enough
/// for a stable axis. Near pi the axis' sign is arbitrary (a turn by pi - e about
/// w is one by pi + e about -w), so the pitches are compared without their signs.
struct ScrewDifference {
  double angle = 0.0;
  double pitch = 0.0;
  bool has_pitch = false;
};

ScrewDifference difference(const Screw& a, const Screw& b, const HalfTurnOptions& o) {
  ScrewDifference d;
  d.angle = std::abs(a.angle - b.angle);
  if (std::min(a.angle, b.angle) > o.min_pitch_angle) {
    d.has_pitch = true;
    const bool near_pi = std::min(a.angle, b.angle) > M_PI - 0.05;
    d.pitch = near_pi ? std::abs(std::abs(a.pitch) - std::abs(b.pitch)) : std::abs(a.pitch - b.pitch);
  }
  return d;
}

/// One pair i < j under both hypotheses: the two views show the same candidate,
/// or one of them is turned.
struct PairFit {
  int i = 0, j = 0;
  double same_squared = 0.0, turned_squared = 0.0;  // squared robust sigmas (angle, and pitch when there)
  bool fits_same = false, fits_turned = false;      // within the gate on each difference
  double evidence = 0.0;                            // + same, - turned; 0 when neither fits
};

struct PairTable {
  std::vector<PairFit> pairs;
  double angle_sigma = 0.0, pitch_sigma = 0.0;
};

PairTable pair_table(const SampleSet& samples, const Isometry3d& F, const HalfTurnOptions& o) {
  const int n = static_cast<int>(samples.samples.size());
  struct Raw {
    ScrewDifference same, turned;
  };
  std::vector<Raw> raw;
  raw.reserve(static_cast<std::size_t>(n) * std::max(n - 1, 0) / 2);
  std::vector<double> angles, pitches;
  std::vector<Isometry3d> inverse(n), turned_inverse(n);
  for (int i = 0; i < n; ++i) {
    inverse[i] = samples.samples[i].T_camera_pattern.inverse();
    turned_inverse[i] = F * inverse[i];  // (P_i F)^-1 = F^-1 P_i^-1, F^-1 = F
  }
  for (int i = 0; i < n; ++i) {
    for (int j = i + 1; j < n; ++j) {
      const Screw a = screw(samples.rig.robot_motion(samples.samples[i].T_base_effector, samples.samples[j].T_base_effector));
      const Isometry3d& P_j = samples.samples[j].T_camera_pattern;
      Raw r{difference(a, screw(P_j * inverse[i]), o), difference(a, screw(P_j * turned_inverse[i]), o)};
      // The scales from the hypothesis that fits better by angle: the right one
      // wherever the pair can tell them apart.
      const ScrewDifference& better = r.same.angle <= r.turned.angle ? r.same : r.turned;
      angles.push_back(better.angle);
      if (better.has_pitch) pitches.push_back(better.pitch);
      raw.push_back(r);
    }
  }
  PairTable table;
  table.angle_sigma = std::max(o.min_angle_sigma, robust_sigma(angles));
  table.pitch_sigma = std::max(o.min_pitch_sigma, robust_sigma(pitches));
  const double gate = o.pair_gate_sigmas;
  std::size_t k = 0;
  for (int i = 0; i < n; ++i) {
    for (int j = i + 1; j < n; ++j, ++k) {
      PairFit p;
      p.i = i, p.j = j;
      const auto judge = [&](const ScrewDifference& d, double& squared, bool& fits) {
        const double za = d.angle / table.angle_sigma, zp = d.has_pitch ? d.pitch / table.pitch_sigma : 0.0;
        squared = za * za + zp * zp;
        fits = za <= gate && zp <= gate;
      };
      judge(raw[k].same, p.same_squared, p.fits_same);
      judge(raw[k].turned, p.turned_squared, p.fits_turned);
      if (p.fits_same || p.fits_turned) {
        p.evidence = std::clamp(0.5 * (p.turned_squared - p.same_squared), -o.max_pair_evidence, o.max_pair_evidence);
      }
      table.pairs.push_back(p);
    }
  }
  return table;
}

/// Each view's share of its informative pairs (exactly one hypothesis fits) whose
/// fitting hypothesis contradicts the labels; 1 for a view without any (nothing
/// vouches for it).
std::vector<double> disagreement(const PairTable& table, const std::vector<bool>& turned) {
  const std::size_t n = turned.size();
  std::vector<int> informative(n, 0), against(n, 0);
  for (const PairFit& p : table.pairs) {
    if (p.fits_same == p.fits_turned) continue;
    const bool labelled_same = turned[p.i] == turned[p.j];
    const bool contradicts = labelled_same != p.fits_same;
    for (int v : {p.i, p.j}) {
      ++informative[v];
      against[v] += contradicts ? 1 : 0;
    }
  }
  std::vector<double> share(n, 1.0);
  for (std::size_t v = 0; v < n; ++v) {
    if (informative[v] > 0) share[v] = static_cast<double>(against[v]) / informative[v];
  }
  return share;
}

/// The view's pose under its label: P, or P F. Turned, its stated camera noise
/// follows: a pose's translation error is its origin's, and the turned frame's
/// origin sits a lever arm a = R_P t_F away, so xi_t' = xi_t - [a]x xi_R
/// (compose_jacobian_left(P, F); the rotation error is the same). A sample without
/// its own noise gets the set's block so moved (`global`). Its corners are given in
/// the turned frame (p' = F^-1 p = F p), each moved onto the view's own point there
/// when it has one (a symmetric target's: its coordinates and id), so that every
/// image's points stay the target's (the corner estimator matches them by coordinates).
PoseSample candidate(const PoseSample& sample, const Isometry3d& F, bool turned,
                     const std::optional<MeasurementNoise>& global) {
  if (!turned) return sample;
  PoseSample out = sample;
  out.T_camera_pattern = sample.T_camera_pattern * F;
  if (const std::optional<MeasurementNoise>& stated = sample.noise ? sample.noise : global) {
    const Matrix6d J = compose_jacobian_left(sample.T_camera_pattern, F);
    out.noise = *stated;
    out.noise->camera = PoseNoise::from_pose_covariance(J * stated->camera.as_pose_covariance() * J.transpose());
  }
  if (sample.corners) {
    auto corners = std::make_shared<TargetCorners>(*sample.corners);
    const PointCorrespondences& given = sample.corners->points;
    PointCorrespondences& points = corners->points;
    double spacing = std::numeric_limits<double>::infinity();  // the closest two points: the snapping tolerance
    for (std::size_t a = 0; a < given.object.size() && a < 64; ++a) {
      for (std::size_t b = a + 1; b < given.object.size(); ++b) {
        spacing = std::min(spacing, (given.object[a] - given.object[b]).norm());
      }
    }
    const double tolerance = std::isfinite(spacing) ? 1e-3 * spacing : 1e-9;
    for (std::size_t k = 0; k < given.object.size(); ++k) {
      const Vector3d moved = F * given.object[k];
      points.object[k] = moved;
      for (std::size_t m = 0; m < given.object.size(); ++m) {
        if ((given.object[m] - moved).norm() <= tolerance) {
          points.object[k] = given.object[m];
          if (m < given.ids.size() && k < points.ids.size()) points.ids[k] = given.ids[m];
          break;
        }
      }
    }
    out.corners = corners;
  }
  return out;
}

}  // namespace

SampleSet apply_half_turns(const SampleSet& samples, const Isometry3d& F, const std::vector<bool>& turned) {
  if (turned.size() != samples.samples.size()) {
    throw HandEyeError(ErrorCode::WrongLength,
                       "one turn label per sample is needed: " + std::to_string(turned.size()) + " for " +
                           std::to_string(samples.samples.size()) + " samples",
                       "turned", "give a label for every sample");
  }
  SampleSet out = samples;
  for (std::size_t i = 0; i < out.samples.size(); ++i) out.samples[i] = candidate(samples.samples[i], F, turned[i], samples.noise);
  return out;
}

namespace {

SampleSet subset(const SampleSet& samples, const std::vector<int>& which) {
  SampleSet out = samples;
  out.samples.clear();
  for (int i : which) out.samples.push_back(samples.samples[i]);
  return out;
}

/// Wrong labels make the start refuse an angle mismatch, or leave a fit too loose
/// for a first-order covariance: those are retried without the least trusted view.
bool retried(ErrorCode code) {
  return code == ErrorCode::AngleMismatch || code == ErrorCode::PoorlyConstrained || code == ErrorCode::NotConverged;
}

/// The joint solve of `fit` (indices into `set`), dropping the view of highest
/// `distrust` while the estimator refuses with a code a wrong label causes.
Calibration solve_core(const SampleSet& set, std::vector<int>& fit, const std::vector<double>& distrust,
                       const JointOptions& joint) {
  for (;;) {
    try {
      return estimate(subset(set, fit), Method::Joint, joint);
    } catch (const HandEyeError& e) {
      if (!retried(e.code()) || fit.size() <= 4) throw;
      const auto worst = std::max_element(fit.begin(), fit.end(), [&](int a, int b) { return distrust[a] < distrust[b]; });
      fit.erase(worst);
    }
  }
}

/// Squared Mahalanobis length of e under C (a tiny floor on the diagonal for a
/// noise-free axis: never NaN).
double mahalanobis_squared(const Vector6d& e, Matrix6d C) {
  C = 0.5 * (C + C.transpose());
  for (int a = 0; a < 6; ++a) C(a, a) += 1e-18;
  const Eigen::LDLT<Matrix6d> ldlt(C);
  const double d = e.dot(ldlt.solve(e));
  return std::isfinite(d) ? std::max(0.0, d) : std::numeric_limits<double>::infinity();
}

/// Every view's two candidates against the calibration's prediction P_hat_i =
/// X^-1 V_i Y: squared Mahalanobis lengths under S_i (the fitted noise model, at
/// each candidate) plus the prediction's own covariance J Cov(X, Y) J^T (the
/// view's own share in the fit is not removed: a view in the fit is judged a
/// little leniently, one outside it exactly).
void judge_views(const SampleSet& as_given, const SampleSet& turned_all, const Calibration& c,
                 std::vector<double>& given_squared, std::vector<double>& turned_squared) {
  const Isometry3d& X = c.T_parent_camera;
  const Isometry3d Y = c.pattern ? c.pattern->pose : pattern_pose(as_given, X);
  const Eigen::Matrix<double, 12, 12> XY = joint_covariance(c);
  const std::vector<Matrix6d> S_given = residual_covariances(as_given, c), S_turned = residual_covariances(turned_all, c);
  const std::size_t n = as_given.samples.size();
  given_squared.assign(n, 0.0);
  turned_squared.assign(n, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    const Isometry3d V = as_given.rig.robot_link(as_given.samples[i].T_base_effector);
    const Isometry3d P_hat = as_given.rig.predicted_view(as_given.samples[i].T_base_effector, X, Y);
    Eigen::Matrix<double, 6, 12> J;
    J.leftCols<6>() = compose_jacobian_left(X.inverse(), V * Y) * inverse_jacobian(X);
    J.rightCols<6>() = compose_jacobian_right(X.inverse() * V);
    const Matrix6d prediction = J * XY * J.transpose();
    given_squared[i] = mahalanobis_squared(pose_error(as_given.samples[i].T_camera_pattern, P_hat), S_given[i] + prediction);
    turned_squared[i] =
        mahalanobis_squared(pose_error(turned_all.samples[i].T_camera_pattern, P_hat), S_turned[i] + prediction);
  }
}

TurnDecision unchanged(const SampleSet& samples) {
  TurnDecision d;
  const std::size_t n = samples.samples.size();
  d.turned.assign(n, false);
  d.samples = samples;
  for (std::size_t i = 0; i < n; ++i) d.kept.push_back(static_cast<int>(i));
  d.candidates.assign(n, {});
  return d;
}

/// Stage 2 on the pairs' verdicts: the signs of W's leading eigenvector.
TurnSynchronisation synchronise(const PairTable& table, int n) {
  TurnSynchronisation s;
  s.turned.assign(n, false);
  s.support.assign(n, 0.0);
  s.angle_sigma = table.angle_sigma;
  s.pitch_sigma = table.pitch_sigma;
  Eigen::MatrixXd W = Eigen::MatrixXd::Zero(n, n);
  for (const PairFit& p : table.pairs) {
    ++s.pairs;
    if (p.fits_same != p.fits_turned) ++s.decisive_pairs;
    if (p.fits_same && p.fits_turned) ++s.undecidable_pairs;
    if (!p.fits_same && !p.fits_turned) ++s.misfit_pairs;
    W(p.i, p.j) = W(p.j, p.i) = p.evidence;
  }
  if (n == 0) return s;
  // Consistent pairs make W = D (l l^T - I)-like, l the labels (+-1) and every
  // pair weighed: its leading eigenvector's signs are the labels, all at once.
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(W);
  Eigen::VectorXd v = eigen.eigenvectors().col(n - 1);
  int negative = 0;
  for (int i = 0; i < n; ++i) negative += v[i] < 0.0 ? 1 : 0;
  if (2 * negative > n) v = -v;  // the larger group as it was detected
  for (int i = 0; i < n; ++i) {
    s.support[i] = std::isfinite(v[i]) ? v[i] : 0.0;
    s.turned[i] = s.support[i] < 0.0;
  }
  return s;
}

}  // namespace

TurnSynchronisation synchronise_half_turns(const SampleSet& samples, const Isometry3d& F, const HalfTurnOptions& o) {
  const int n = static_cast<int>(samples.samples.size());
  if (is_identity(F)) {
    TurnSynchronisation s;
    s.turned.assign(n, false);
    s.support.assign(n, 0.0);
    return s;
  }
  check_input(samples, F);
  return synchronise(pair_table(samples, F, o), n);
}

TurnDecision refine_half_turns(const SampleSet& given, const Isometry3d& F, const std::vector<bool>& initial,
                               const JointOptions& joint, const HalfTurnOptions& o) {
  const int n = static_cast<int>(given.samples.size());
  if (static_cast<int>(initial.size()) != n) {
    throw HandEyeError(ErrorCode::WrongLength,
                       std::to_string(initial.size()) + " labels for " + std::to_string(n) + " samples", kWhere,
                       "give one label per sample (synchronise_half_turns' turned)");
  }
  if (is_identity(F)) return unchanged(given);
  check_input(given, F);
  const SampleSet samples = with_default_noise(given);
  const PairTable table = pair_table(samples, F, o);
  std::vector<bool> turned = initial;
  const SampleSet turned_all = apply_half_turns(samples, F, std::vector<bool>(n, true));

  // The first solve: the views whose labels agree with the pairs' (up to a global
  // turn: the larger of agreeing and disagreeing, so that labels half wrong still
  // leave a consistent core), and whose informative pairs mostly agree with them.
  const std::vector<bool> pairs_say = synchronise(table, n).turned;
  int agreeing = 0;
  for (int i = 0; i < n; ++i) agreeing += turned[i] == pairs_say[i] ? 1 : 0;
  const bool flipped = 2 * agreeing < n;
  std::vector<bool> aligned(n);
  for (int i = 0; i < n; ++i) aligned[i] = pairs_say[i] != flipped;
  std::vector<double> distrust = disagreement(table, aligned);
  std::vector<int> fit;
  for (int i = 0; i < n; ++i) {
    if (turned[i] != aligned[i]) distrust[i] = 1.0 + distrust[i];  // dropped first on a refusal
    if (turned[i] == aligned[i] && distrust[i] <= o.disagreeing_share) fit.push_back(i);
  }
  if (fit.size() < 4) {  // too few vouched for: the most trusted half
    std::vector<int> order(n);
    for (int i = 0; i < n; ++i) order[i] = i;
    std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return distrust[a] < distrust[b]; });
    fit.assign(order.begin(), order.begin() + std::min(n, std::max(4, n / 2)));
    std::sort(fit.begin(), fit.end());
  }

  TurnDecision d;
  std::vector<double> given_squared, turned_squared;
  double gate = o.view_gate;
  for (d.rounds = 1;; ++d.rounds) {
    const SampleSet set = apply_half_turns(samples, F, turned);
    const Calibration c = solve_core(set, fit, distrust, joint);
    judge_views(samples, turned_all, c, given_squared, turned_squared);
    std::vector<bool> next(n);
    std::vector<double> best(n);
    for (int i = 0; i < n; ++i) {
      next[i] = turned_squared[i] < given_squared[i];
      best[i] = std::min(given_squared[i], turned_squared[i]);
    }
    gate = o.view_gate * residual_scale(best);
    std::vector<int> next_fit;
    for (int i = 0; i < n; ++i) {
      if (best[i] <= gate && std::max(given_squared[i], turned_squared[i]) > gate) next_fit.push_back(i);
    }
    const bool settled = next == turned && next_fit == fit;
    turned = next;
    distrust = best;  // a later refusal drops the worst-fitting view
    if (settled || d.rounds >= o.max_rounds || next_fit.size() < 4) break;
    fit = next_fit;
  }

  // The gate, on the last solve's distances.
  d.gate_sigmas = std::sqrt(gate);
  d.turned.assign(n, false);
  d.candidates.resize(n);
  std::vector<int> kept;
  for (int i = 0; i < n; ++i) {
    d.candidates[i] = {std::sqrt(given_squared[i]), std::sqrt(turned_squared[i])};
    const bool given_fits = given_squared[i] <= gate, turned_fits = turned_squared[i] <= gate;
    if (given_fits == turned_fits) {
      d.undecided.push_back({i, given_fits});
    } else {
      kept.push_back(i);
      d.turned[i] = turned_fits;
    }
  }
  // A global turn moves Y only: the fewer turned, so that views detected right stay.
  int count = 0;
  for (int i : kept) count += d.turned[i] ? 1 : 0;
  if (2 * count > static_cast<int>(kept.size())) {
    for (int i : kept) d.turned[i] = !d.turned[i];
    count = static_cast<int>(kept.size()) - count;
  }
  d.turned_count = count;
  d.kept = kept;
  d.samples = given;  // its noise block as given
  d.samples.samples.clear();
  for (int i : kept) d.samples.samples.push_back(candidate(given.samples[i], F, d.turned[i], given.noise));
  return d;
}

TurnDecision decide_half_turns(const SampleSet& samples, const Isometry3d& F, const JointOptions& joint,
                               const HalfTurnOptions& o) {
  if (is_identity(F)) return unchanged(samples);
  return refine_half_turns(samples, F, synchronise_half_turns(samples, F, o).turned, joint, o);
}

Calibration::Rejected undecided_rejection(const TurnDecision& d, const TurnDecision::Undecided& u) {
  Calibration::Rejected r;
  r.index = u.index;
  r.why = u.both_fit ? Calibration::Rejected::Why::AmbiguousBothFit : Calibration::Rejected::Why::AmbiguousNeitherFits;
  const TurnDecision::Candidates& fit = d.candidates.at(static_cast<std::size_t>(u.index));
  r.sigmas = fit.as_given_sigmas, r.turned_sigmas = fit.turned_sigmas, r.gate_sigmas = d.gate_sigmas;
  return r;
}

}  // namespace handeye
