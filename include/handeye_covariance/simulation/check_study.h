// The Monte-Carlo study of the calibration check (estimation/calibration_check.h):
// false alarms without a change, detection of a planted change of X or Y, and
// whether the check names the right one. For test_calibration_check and
// handeye_check_study (BENCHMARKS.md).
//
// One trial: a calibration from `calibration_samples` simulated views (the noise
// estimated from the residuals unless `noise_given`), then `views` new views of the
// same rig. A change moves X's (or Y's) translation along a random direction u by
// `multiple` times the combined 1 sigma of the change estimate along u, as the check
// reports it at these views: 1 / sqrt(u^T Cov(d)^-1 u), so that the planted change's
// noncentrality is multiple^2 and a 6-dof test at alpha can detect it no more often
// than the noncentral chi2(6, multiple^2) beyond the chi2(6) 1 - alpha quantile.
//
// By default a view is observed at the pose level (each pose perturbed by `noise`);
// `observe` can see it otherwise: handeye_check_study --rendered renders each set of
// views and detects them as `handeye images` does (simulation/rendered_views.h).
#pragma once

#include <functional>

#include "handeye_covariance/estimation/calibration_check.h"
#include "handeye_covariance/simulation/simulation.h"

namespace handeye {

/// What a study moves: X's or Y's translation along a direction uniform on the sphere
/// (the figure BENCHMARKS.md shows first), or X or Y along a direction uniform in its 6 dof as the check
/// weighs them (u = L w, L L^T the check's covariance of the change, w uniform on the
/// 6-sphere: the family two_hypothesis_power_bound is the bound for).
enum class PlantedChange { None, XTranslation, YTranslation, XAnyDirection, YAnyDirection };

/// True when `change` moves X (the camera on its mount), false when it moves Y or nothing.
bool moves_X(PlantedChange change);

struct CheckStudyOptions {
  Setup setup = Setup::EyeInHand;
  int calibration_samples = 20;
  int views = 5;
  ViewpointOptions viewpoints;  // of the calibration's views and the new ones
  int checks = 2000;
  unsigned seed = 1;
  bool noise_given = false;
  MeasurementNoise noise;  // default: the `handeye sim` noise (0.5 mm, 0.05 deg camera; 0.05 mm, 0.01 deg robot)
  PlantedChange change = PlantedChange::None;
  double multiple = 5.0;
  /// The 1 sigma a translation is moved by `multiple` of. false: along u given the rest of
  /// the change, 1 / sqrt(u' Cov^-1 u), so that the noncentrality is multiple^2 (the
  /// bounds' reading); true: as the check prints it beside a change, sqrt(u' Cov_tt u),
  /// the translation's own spread along u (at least the first: rotation and translation
  /// estimates correlate).
  bool sigma_as_printed = false;
  CheckOptions check;
  /// Each calibration measures its own prediction by leave-one-out (Calibration::prediction),
  /// as the session does; false: the check draws each estimated noise number instead.
  bool prediction = true;
  int bound_draws = 5000;  // of the two-hypothesis bound per check (0: not computed; +-0.4% each)
  /// How a set of views is observed: the rig, the robot's true poses and the true X and
  /// Y to the samples with their noise (a view may be left out). Unset: each pose
  /// perturbed by `noise`, stated as `noise_given` says.
  std::function<SampleSet(Rng& rng, const Rig& rig, const std::vector<Eigen::Isometry3d>& effectors,
                          const Eigen::Isometry3d& X, const Eigen::Isometry3d& Y)>
      observe;
};

struct CheckStudyResult {
  int checks = 0;
  int changed = 0;             // the check said changed
  int named_X = 0, named_Y = 0, named_both = 0;  // of those, what it named
  int left_out = 0;            // the check left a view out as a wrong detection (and said consistent)
  double mean_chi2_over_dof = 0.0;  // the omnibus chi2 / dof (1 when the noise model holds)
  double mean_x_y_cosine = 0.0;     // the mean of each check's six principal cosines between X's and Y's subspaces
  /// The moved one's chi2 drop (X's when X moved), averaged: 6 + multiple^2 when each move
  /// is as large as planted in the check's own noise (its drop is noncentral chi2(6)).
  double mean_planted_drop = 0.0;
  /// The bound: P(noncentral chi2(6, multiple^2) > chi2(6) quantile 1 - alpha); alpha without a change.
  double bound = 0.0;
  /// The bound for a test that must catch a change of X or of Y (either, in any direction,
  /// at the same alpha): the Neyman-Pearson power against their even mixture at each
  /// check's views (two_hypothesis_power_bound), averaged. No test's power against both
  /// X and Y changes exceeds it.
  double two_hypothesis_bound = 0.0;
  /// The most any level-alpha test with any naming detects and names right at each
  /// check's views, for a direction uniform in 6 dof (two_hypothesis_frontier), averaged.
  double best_detected_and_named = 0.0;
  /// The 6-dof bound (knows which) when the views' noise is known only up to one scale,
  /// estimated from as many dof as the calibration's own views give its leave-one-out
  /// prediction (Calibration::prediction's dof, at most 6 a view, floored at 5 as the
  /// check floors it; f_test_power) whether or not the check scaled by it, averaged; the
  /// chi2 bound for a calibration without one. An idealisation (one scale for the whole
  /// noise): a calibration that estimated its noise cannot be checked better than its
  /// views know that noise.
  double noise_dof_bound = 0.0;
  double rate() const { return checks ? static_cast<double>(changed) / checks : 0.0; }
  /// The share of detected checks that named the planted change (X or Y).
  double named_right() const;
  PlantedChange planted = PlantedChange::None;
};

MeasurementNoise check_study_noise();

CheckStudyResult run_check_study(const CheckStudyOptions& options);

/// P(noncentral chi2(dof, noncentrality) > the chi2(dof) 1 - alpha quantile): the power
/// of the best test of a known-dimension change.
double chi2_test_power(int dof, double noncentrality, double alpha);

/// The same test with the noise known only up to one scale, estimated from
/// `scale_dof` dof independent of the views: P(noncentral F(dof, scale_dof,
/// noncentrality) > the F(dof, scale_dof) 1 - alpha quantile), the power of the F test,
/// the most powerful test invariant to that scale and to the change's direction within
/// its `dof` (Lehmann and Romano, Testing Statistical Hypotheses, 7.1). scale_dof <= 0:
/// the scale known (chi2_test_power).
double f_test_power(int dof, double scale_dof, double noncentrality, double alpha);

/// The most powerful level-alpha test of "no change" against "X or Y changed by
/// noncentrality lambda, each with probability 1/2, in a direction uniform in its 6 dof",
/// at views whose X and Y subspaces have principal cosines `cosines`: its power, by a
/// seeded Monte-Carlo (the likelihood ratio (g(|u|^2) + g(|v|^2)) / 2, u and v the
/// whitened residual's projections, g the noncentral chi2(6) density ratio). Any test's
/// smaller power of the two (X, Y) is at most this average's optimum.
double two_hypothesis_power_bound(const Vector6d& cosines, double noncentrality, double alpha, unsigned seed = 1,
                                  int draws = 40000);

/// The same with the noise known only up to one scale sigma^2, estimated independently
/// from `scale_dof` dof (S = sigma^2 chi2(nu) / nu; the change lambda in units of the true
/// sigma): the power of the most powerful test invariant to that scale, the Neyman-Pearson
/// test on t = y / sqrt(S) (y the whitened projection onto X's and Y's span, r dims), whose
/// likelihood ratio over "no change" is E_x[(g(x |P_X t|^2) + g(x |P_Y t|^2)) / 2] with x
/// ~ Gamma((nu + r) / 2, rate (nu + |t|^2) / 2) (g as above; x at 32 quantiles, which
/// leaves the statistic a shade short of the optimum: the figure understates the bound
/// slightly, beside its Monte-Carlo error). The scale
/// group is amenable, so by Hunt and Stein no test's smallest power over the unknown
/// scale exceeds it (a test may do better at one particular scale). Seeded Monte-Carlo;
/// identical subspaces give f_test_power's F test.
double two_hypothesis_power_bound_estimated_scale(const Vector6d& cosines, double noncentrality, double scale_dof,
                                                  double alpha, unsigned seed = 1, int draws = 40000);

/// The same Monte-Carlo (its bound identical, draw for draw) with the check's own test
/// beside the bound: the larger of |u|^2 and |v|^2 (the larger chi2 drop), named by the
/// larger. For "X or Y changed, even odds, lambda, a direction uniform in each's 6 dof" the
/// densities over "no change" are g(|u|^2) and g(|v|^2), g increasing, so for any test R
/// and any naming, P(detected and named right) <= 1/2 of the integral over R of
/// max(f_X, f_Y), which by Neyman-Pearson's lemma is largest on {max(|u|^2, |v|^2) > t}
/// named by the larger: the check's own. So "detects a share p and names a share q of its
/// detections right" needs bound >= p and detected_and_named >= p q.
struct TwoHypothesisFrontier {
  double bound = 0.0;               // two_hypothesis_power_bound: the most any test detects
  double larger_power = 0.0;        // the check's statistic's power at its own alpha
  double larger_named_right = 0.0;  // the share of its detections it names right
  double detected_and_named = 0.0;  // P(detected and named right): the most any test with any naming reaches
};
TwoHypothesisFrontier two_hypothesis_frontier(const Vector6d& cosines, double noncentrality, double alpha,
                                               unsigned seed = 1, int draws = 40000);

}  // namespace handeye
