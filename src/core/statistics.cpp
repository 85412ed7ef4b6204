#include "handeye_covariance/core/statistics.h"

#include <algorithm>
#include <cmath>
#include <cstddef>

#include <boost/math/distributions/chi_squared.hpp>

namespace handeye {

double median(std::vector<double> values) {
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

double robust_sigma(std::vector<double> values) {
  if (values.empty()) return 0.0;
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(values.size() / 4), values.end());
  return values[values.size() / 4] / kHalfNormalLowerQuartile;
}

double linear_quantile(std::vector<double> values, double p) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const double at = p * static_cast<double>(values.size() - 1);
  const std::size_t below = static_cast<std::size_t>(std::floor(at));
  const std::size_t above = std::min(below + 1, values.size() - 1);
  return values[below] + (at - static_cast<double>(below)) * (values[above] - values[below]);
}

double chi2_quantile(double dof, double level) { return boost::math::quantile(boost::math::chi_squared(dof), level); }

double chi2_upper_tail(double dof, double statistic) {
  return boost::math::cdf(boost::math::complement(boost::math::chi_squared(dof), std::max(statistic, 0.0)));
}

}  // namespace handeye
