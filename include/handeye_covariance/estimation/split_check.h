// The split-half check: is the covariance honest on this session? (No truth
// needed, so it works on real data.)
//
// The samples are split at random into two halves a and b, each is solved, and
// the difference of their X is judged under the sum of their covariances (the
// halves share no sample, so their errors are independent):
//     d = (t_a - t_b, log(R_a R_b^T)),   NEES = d^T (Sigma_a + Sigma_b)^-1 d.
// Over many random splits the mean NEES is about 6 when the covariance is
// honest; well above (> 7.5) it is overconfident, well below (< 5) too cautious.
// Each half holds n/2 samples, so it says how honest the covariance of an n/2-pose
// session of this kind is.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "handeye_covariance/estimation/estimator.h"

namespace handeye {

struct SplitCheck {
  int splits = 0;           // random splits solved
  int failed = 0;           // splits where a half could not be solved (too few or degenerate samples)
  int half_size = 0;        // samples in the smaller half
  double mean_nees = 0.0;   // 6-dof, over the solved splits
  double mean_nees_translation = 0.0, mean_nees_rotation = 0.0;  // 3-dof blocks
  std::vector<double> nees;  // each split's
  /// Each solved split's d (ROS order, m and rad) and the 1 sigma per axis its
  /// covariance Sigma_a + Sigma_b predicts: the per-axis check (report.h).
  std::vector<Vector6d> differences, difference_sigmas;
  std::string first_failure;  // the first half's error, when some failed
};

/// `splits` random halves (seeded) of `samples`, each solved by `solve`.
/// Throws HandEyeError(TooFewMotions) for fewer than 8 samples.
SplitCheck split_check(const SampleSet& samples, const std::function<Calibration(const SampleSet&)>& solve, int splits,
                       unsigned seed);

}  // namespace handeye
