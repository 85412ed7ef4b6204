#include "handeye_covariance/simulation/check_study.h"

#include <algorithm>
#include <limits>
#include <random>
#include <vector>

#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/gamma.hpp>
#include <boost/math/distributions/fisher_f.hpp>
#include <boost/math/distributions/non_central_f.hpp>
#include <boost/math/distributions/non_central_chi_squared.hpp>
#include <boost/math/special_functions/bessel.hpp>

#include "handeye_covariance/core/lie.h"
#include "handeye_covariance/core/units.h"
#include "handeye_covariance/estimation/joint_estimator.h"

namespace handeye {

namespace {

/// A new view at robot pose `E` of the rig whose true X and Y are given, with the noise.
PoseSample observe(Rng& rng, const Rig& rig, const Eigen::Isometry3d& E, const Eigen::Isometry3d& X,
                   const Eigen::Isometry3d& Y, const MeasurementNoise& noise) {
  PoseSample sample;
  sample.T_base_effector = perturb(rng, E, noise.robot);
  sample.T_camera_pattern = perturb(rng, rig.predicted_view(E, X, Y), noise.camera);
  return sample;
}

/// log((g(T_X) + g(T_Y)) / 2): the likelihood ratio of "X or Y changed (even odds) by
/// noncentrality lambda in a direction uniform on the sphere" over "nothing changed".
double log_change_likelihood_ratio(double T_X, double T_Y, double noncentrality) {
  // log g(T): the noncentral over the central chi2(6) density at T with the direction
  // averaged over the sphere, exp(-lambda / 2) Gamma(3) (2 / r)^2 I_2(r), r = sqrt(lambda T).
  const auto log_g = [&](double T) {
    const double r = std::sqrt(noncentrality * std::max(T, 0.0));
    if (r < 1e-4) return -0.5 * noncentrality + r * r / 12.0;  // I_2(r) = r^2 / 8 (1 + r^2 / 12 + ...)
    // I_2(r) e^-r is bounded: the log stays finite for any r.
    return -0.5 * noncentrality + r + std::log(8.0 / (r * r) * boost::math::cyl_bessel_i(2, r) * std::exp(-r));
  };
  const double a = log_g(T_X), b = log_g(T_Y);
  return std::max(a, b) + std::log(0.5 * (1.0 + std::exp(-std::abs(a - b))));
}

Eigen::Vector3d random_direction(Rng& rng) {
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::Vector3d u(normal(rng), normal(rng), normal(rng));
  return u.normalized();
}

/// Six standard normals, drawn in order (the bounds' Monte-Carlos).
Vector6d standard_normal6(Rng& rng, std::normal_distribution<double>& normal) {
  Vector6d x;
  for (int a = 0; a < 6; ++a) x(a) = normal(rng);
  return x;
}

/// The level-alpha threshold of a Monte-Carlo null: the sorted draws' 1 - alpha point.
double upper_quantile(std::vector<double>& draws, double alpha) {
  std::sort(draws.begin(), draws.end());
  return draws[static_cast<std::size_t>((1.0 - alpha) * (static_cast<double>(draws.size()) - 1.0))];
}

}  // namespace

MeasurementNoise check_study_noise() {
  const double deg = kRadiansPerDegree, mm = kMetresPerMillimetre;
  MeasurementNoise noise;
  noise.camera.rotation = std::pow(0.05 * deg, 2) * Eigen::Matrix3d::Identity();
  noise.camera.translation = std::pow(0.5 * mm, 2) * Eigen::Matrix3d::Identity();
  noise.robot.rotation = std::pow(0.01 * deg, 2) * Eigen::Matrix3d::Identity();
  noise.robot.translation = std::pow(0.05 * mm, 2) * Eigen::Matrix3d::Identity();
  return noise;
}

bool moves_X(PlantedChange change) {
  return change == PlantedChange::XTranslation || change == PlantedChange::XAnyDirection;
}

double CheckStudyResult::named_right() const {
  if (changed == 0) return 0.0;
  const int right = planted == PlantedChange::None ? 0 : moves_X(planted) ? named_X : named_Y;
  return static_cast<double>(right) / changed;
}

double chi2_test_power(int dof, double noncentrality, double alpha) {
  const double threshold = boost::math::quantile(boost::math::chi_squared(dof), 1.0 - alpha);
  if (noncentrality <= 0.0) return alpha;
  return boost::math::cdf(
      boost::math::complement(boost::math::non_central_chi_squared(dof, noncentrality), threshold));
}

double f_test_power(int dof, double scale_dof, double noncentrality, double alpha) {
  if (scale_dof <= 0.0) return chi2_test_power(dof, noncentrality, alpha);
  const double threshold = boost::math::quantile(boost::math::fisher_f(dof, scale_dof), 1.0 - alpha);
  if (noncentrality <= 0.0) return alpha;
  return boost::math::cdf(
      boost::math::complement(boost::math::non_central_f(dof, scale_dof, noncentrality), threshold));
}

TwoHypothesisFrontier two_hypothesis_frontier(const Vector6d& cosines, double noncentrality, double alpha, unsigned seed,
                                               int draws) {
  const double root_lambda = std::sqrt(noncentrality);
  const auto log_ratio = [&](const Vector6d& u, const Vector6d& v) {
    return log_change_likelihood_ratio(u.squaredNorm(), v.squaredNorm(), noncentrality);
  };
  const auto larger = [](const Vector6d& u, const Vector6d& v) { return std::max(u.squaredNorm(), v.squaredNorm()); };
  const Vector6d c = cosines.cwiseMin(1.0).cwiseMax(0.0);
  const Vector6d s = (Vector6d::Ones() - c.cwiseProduct(c)).cwiseSqrt();
  Rng rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  const auto gaussian = [&] { return standard_normal6(rng, normal); };
  // In the principal bases the two projections are u and v = c u + s w (u, w white).
  std::vector<double> null_ratios(static_cast<std::size_t>(draws)), null_larger(null_ratios.size());
  for (std::size_t d = 0; d < null_ratios.size(); ++d) {
    const Vector6d u = gaussian();
    const Vector6d v = c.cwiseProduct(u) + s.cwiseProduct(gaussian());
    null_ratios[d] = log_ratio(u, v), null_larger[d] = larger(u, v);
  }
  const double threshold = upper_quantile(null_ratios, alpha), larger_threshold = upper_quantile(null_larger, alpha);
  int detected = 0, detected_by_larger = 0;
  double named_right = 0.0;
  for (int d = 0; d < draws; ++d) {
    const Vector6d theta = gaussian().normalized() * root_lambda;
    Vector6d u = gaussian() + theta;  // X changed: the signal is in u's subspace
    Vector6d v = c.cwiseProduct(u) + s.cwiseProduct(gaussian());
    // Before the swap u is the changed one's; a tie (identical subspaces) is a coin's toss.
    const double right = u.squaredNorm() > v.squaredNorm() ? 1.0 : u.squaredNorm() == v.squaredNorm() ? 0.5 : 0.0;
    if (d % 2 == 1) std::swap(u, v);  // Y changed: the same with the roles swapped
    if (log_ratio(u, v) > threshold) ++detected;
    if (larger(u, v) > larger_threshold) ++detected_by_larger, named_right += right;
  }
  TwoHypothesisFrontier frontier;
  frontier.bound = static_cast<double>(detected) / draws;
  frontier.larger_power = static_cast<double>(detected_by_larger) / draws;
  frontier.larger_named_right = detected_by_larger ? named_right / detected_by_larger : 0.0;
  frontier.detected_and_named = named_right / draws;
  return frontier;
}

double two_hypothesis_power_bound_estimated_scale(const Vector6d& cosines, double noncentrality, double scale_dof,
                                                  double alpha, unsigned seed, int draws) {
  const Vector6d c = cosines.cwiseMin(1.0).cwiseMax(0.0);
  const Vector6d s = (Vector6d::Ones() - c.cwiseProduct(c)).cwiseSqrt();
  const int r = 6 + static_cast<int>((s.array() > 1e-9).count());  // the span's dimension
  // The standard Gamma((nu + r) / 2) at 32 mid-probabilities: x = those / rate.
  constexpr int kNodes = 32;
  const boost::math::gamma_distribution<double> standard(0.5 * (scale_dof + r), 1.0);
  std::vector<double> nodes(kNodes);
  for (int k = 0; k < kNodes; ++k) nodes[static_cast<std::size_t>(k)] = boost::math::quantile(standard, (k + 0.5) / kNodes);
  Rng rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::chi_squared_distribution<double> chi2(scale_dof);
  const auto gaussian = [&] { return standard_normal6(rng, normal); };
  // One draw's log likelihood ratio: u, w the white coordinates (X's subspace, the rest of
  // the span), divided by the scale's draw; v = c u + s w the Y projection.
  const auto log_ratio = [&](const Vector6d& theta, bool y_changed) {
    Vector6d u = gaussian() + theta, w = gaussian();
    const double scale = std::sqrt(std::max(chi2(rng), 1e-300) / scale_dof);
    u /= scale, w /= scale;
    Vector6d v = c.cwiseProduct(u) + s.cwiseProduct(w);
    double norm2 = u.squaredNorm();
    for (int a = 0; a < 6; ++a) norm2 += s(a) > 1e-9 ? w(a) * w(a) : 0.0;
    // "Y changed": a reflection of the span swaps the subspaces and keeps the noise, so its
    // draws are X's with the roles swapped (the ratio is symmetric in them: the same power).
    if (y_changed) std::swap(u, v);
    const double rate = 0.5 * (scale_dof + norm2);
    double most = -std::numeric_limits<double>::infinity();
    std::vector<double> terms(kNodes);
    for (int k = 0; k < kNodes; ++k) {
      const double x = nodes[static_cast<std::size_t>(k)] / rate;
      terms[static_cast<std::size_t>(k)] = log_change_likelihood_ratio(x * u.squaredNorm(), x * v.squaredNorm(), noncentrality);
      most = std::max(most, terms[static_cast<std::size_t>(k)]);
    }
    double sum = 0.0;
    for (double term : terms) sum += std::exp(term - most);
    return most + std::log(sum / kNodes);
  };
  std::vector<double> null(static_cast<std::size_t>(draws));
  for (double& value : null) value = log_ratio(Vector6d::Zero(), false);
  const double threshold = upper_quantile(null, alpha);
  const double root_lambda = std::sqrt(noncentrality);
  int detected = 0;
  for (int d = 0; d < draws; ++d) detected += log_ratio(gaussian().normalized() * root_lambda, d % 2 == 1) > threshold;
  return static_cast<double>(detected) / draws;
}

double two_hypothesis_power_bound(const Vector6d& cosines, double noncentrality, double alpha, unsigned seed, int draws) {
  return two_hypothesis_frontier(cosines, noncentrality, alpha, seed, draws).bound;
}

CheckStudyResult run_check_study(const CheckStudyOptions& options) {
  const MeasurementNoise noise =
      options.noise.camera.translation.isZero() ? check_study_noise() : options.noise;
  const Eigen::Isometry3d X = typical_X(options.setup);
  CheckStudyResult result;
  result.planted = options.change;
  result.bound = chi2_test_power(6, options.change == PlantedChange::None ? 0.0 : options.multiple * options.multiple,
                                 options.check.alpha);
  // A set of views at the robot's true poses, as options.observe or the pose-level noise sees them.
  const auto observed = [&](Rng& rng, const Rig& rig, const std::vector<Eigen::Isometry3d>& effectors,
                            const Eigen::Isometry3d& X_true, const Eigen::Isometry3d& Y_true) {
    if (options.observe) return options.observe(rng, rig, effectors, X_true, Y_true);
    SampleSet set;
    set.rig = rig;
    if (options.noise_given) set.noise = noise;
    for (const Eigen::Isometry3d& E : effectors) set.samples.push_back(observe(rng, rig, E, X_true, Y_true, noise));
    return set;
  };
  Rng rng(options.seed);
  for (int trial = 0; trial < options.checks; ++trial) {
    SimulatedSession session = simulate_session(rng, options.setup, X, options.calibration_samples,
                                                options.observe ? MeasurementNoise{} : noise, options.viewpoints);
    const Rig rig = session.samples.rig;  // a copy: the observed path replaces session.samples
    const Eigen::Isometry3d Y = session.T_world_pattern;
    if (options.observe) {  // the session's robot poses are the truth: observe them
      std::vector<Eigen::Isometry3d> effectors;
      for (const PoseSample& s : session.samples.samples) effectors.push_back(s.T_base_effector);
      session.samples = observed(rng, rig, effectors, X, Y);
    } else if (!options.noise_given) {
      session.samples.noise.reset();
    }
    Calibration calibration = solve_joint(session.samples);
    if (options.prediction) {
      calibration.prediction = prediction_check(session.samples, [](const SampleSet& s) { return solve_joint(s); });
    }

    std::vector<Eigen::Isometry3d> effectors;
    SampleSet views;
    if (options.observe) {
      for (int i = 0; i < options.views; ++i) effectors.push_back(rig.effector_for_view(X, Y, random_view(rng, options.viewpoints)));
      views = observed(rng, rig, effectors, X, Y);
    } else {  // each view drawn and observed in turn (the seeded figures of BENCHMARKS.md)
      views.rig = rig;
      if (options.noise_given) views.noise = noise;
      for (int i = 0; i < options.views; ++i) {
        effectors.push_back(rig.effector_for_view(X, Y, random_view(rng, options.viewpoints)));
        views.samples.push_back(observe(rng, rig, effectors.back(), X, Y, noise));
      }
    }
    Eigen::Isometry3d X_now = X, Y_now = Y;
    if (options.change != PlantedChange::None) {
      // The move along u, in units of the check's own 1 sigma of the change along u.
      const CalibrationCheck unchanged = check_calibration(calibration, views, options.check);
      const bool x = moves_X(options.change);
      const Matrix6d& covariance = x ? unchanged.X_alone.X_change->covariance : unchanged.Y_alone.Y_change->covariance;
      Eigen::Isometry3d& moved = x ? X_now : Y_now;
      if (options.change == PlantedChange::XTranslation || options.change == PlantedChange::YTranslation) {
        Vector6d u = Vector6d::Zero();
        u.head<3>() = random_direction(rng);
        const double sigma = options.sigma_as_printed ? std::sqrt(u.dot(covariance * u))
                                                      : 1.0 / std::sqrt(u.dot(covariance.ldlt().solve(u)));
        moved.translation() += options.multiple * sigma * u.head<3>();  // a left perturbation's translation part
      } else {  // u = L w moves by 1 sigma along itself: u' Cov^-1 u = |w|^2 = 1
        std::normal_distribution<double> normal(0.0, 1.0);
        const Vector6d w = standard_normal6(rng, normal).normalized();
        const Matrix6d L = Eigen::LLT<Matrix6d>(covariance).matrixL();
        const Vector6d xi = options.multiple * (L * w);
        moved.linear() = so3::exp(xi.tail<3>()) * moved.linear();  // the left perturbation, as the check's
        moved.translation() += xi.head<3>();
      }
      views = observed(rng, rig, effectors, X_now, Y_now);
    }
    const CalibrationCheck check = check_calibration(calibration, views, options.check);
    ++result.checks;
    if (!check.left_out.empty()) ++result.left_out;
    const double lambda = options.change == PlantedChange::None ? 0.0 : options.multiple * options.multiple;
    result.noise_dof_bound +=
        f_test_power(6, calibration.prediction ? std::max(calibration.prediction->dof, 5.0) : 0.0, lambda,
                     options.check.alpha) / options.checks;
    if (options.change != PlantedChange::None && options.bound_draws > 0) {
      const TwoHypothesisFrontier frontier =
          two_hypothesis_frontier(check.x_y_cosines, options.multiple * options.multiple, options.check.alpha,
                                  options.seed + trial, options.bound_draws);
      result.two_hypothesis_bound += frontier.bound / options.checks;
      result.best_detected_and_named += frontier.detected_and_named / options.checks;
    }
    result.mean_chi2_over_dof += check.chi2 / check.dof / options.checks;
    result.mean_x_y_cosine += check.x_y_cosines.mean() / options.checks;
    if (options.change != PlantedChange::None) {
      result.mean_planted_drop += (moves_X(options.change) ? check.X_alone : check.Y_alone).chi2_drop / options.checks;
    }
    if (check.changed) {
      ++result.changed;
      if (check.change.what == ChangedPose::X) ++result.named_X;
      if (check.change.what == ChangedPose::Y) ++result.named_Y;
      if (check.change.what == ChangedPose::Both) ++result.named_both;
    }
  }
  return result;
}

}  // namespace handeye
