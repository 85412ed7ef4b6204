#include "handeye_covariance/estimation/split_check.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <numeric>
#include <random>

namespace handeye {

SplitCheck split_check(const SampleSet& samples, const std::function<Calibration(const SampleSet&)>& solve, int splits,
                       unsigned seed) {
  const int n = static_cast<int>(samples.samples.size());
  if (n < 8) {
    throw HandEyeError(ErrorCode::TooFewMotions,
                       "the split-half check needs at least 8 samples (two halves of 4), got " + std::to_string(n),
                       "samples", "record more samples; the check is meaningful from about 20");
  }
  SplitCheck check;
  check.half_size = n / 2;
  std::mt19937_64 rng(seed);
  std::vector<int> order(static_cast<std::size_t>(n));
  std::iota(order.begin(), order.end(), 0);
  for (int split = 0; split < splits; ++split) {
    std::shuffle(order.begin(), order.end(), rng);
    SampleSet halves[2] = {samples, samples};
    halves[0].samples.clear(), halves[1].samples.clear();
    for (int k = 0; k < n; ++k) {
      halves[k < n / 2 ? 0 : 1].samples.push_back(samples.samples[static_cast<std::size_t>(order[static_cast<std::size_t>(k)])]);
    }
    Calibration a, b;
    try {
      a = solve(halves[0]);
      b = solve(halves[1]);
    } catch (const HandEyeError& e) {
      if (check.first_failure.empty()) check.first_failure = e.what();
      ++check.failed;
      continue;
    }
    const Vector6d d = pose_error(a.T_parent_camera, b.T_parent_camera);
    const Matrix6d S = a.pose_covariance + b.pose_covariance;
    const double nees = d.dot(S.ldlt().solve(d));
    check.nees.push_back(nees);
    check.differences.push_back(d);
    check.difference_sigmas.push_back(S.diagonal().cwiseMax(0.0).cwiseSqrt());
    check.mean_nees_translation += d.head<3>().dot(S.topLeftCorner<3, 3>().ldlt().solve(d.head<3>()));
    check.mean_nees_rotation += d.tail<3>().dot(S.bottomRightCorner<3, 3>().ldlt().solve(d.tail<3>()));
  }
  check.splits = static_cast<int>(check.nees.size());
  if (check.splits > 0) {
    check.mean_nees = std::accumulate(check.nees.begin(), check.nees.end(), 0.0) / check.splits;
    check.mean_nees_translation /= check.splits;
    check.mean_nees_rotation /= check.splits;
  }
  return check;
}

}  // namespace handeye
