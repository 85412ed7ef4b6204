// The test helpers that need more than a header's worth of code (boost's chi2
// quantiles): compiled once into the tests' support objects (CMakeLists.txt).
#include "test_helpers.h"

#include <boost/math/distributions/chi_squared.hpp>

namespace handeye {
namespace test {

std::pair<double, double> nees_band_under_estimated_sigma(const std::vector<int>& dof, int dim, double coverage) {
  Rng rng(20261123);
  std::chi_squared_distribution<double> error(dim);
  struct Session {
    std::chi_squared_distribution<double> pooled;  // RSS / sigma^2, chi2(nu)
    double scale;  // covariance_variance / sigma^2 = pooled x scale: nu / (nu - 2) / nu, capped as production
  };
  std::vector<Session> sessions;
  for (const int dof_k : dof) {
    const double nu = std::max(dof_k, 1), capped = std::max(nu, 3.0);  // as PixelNoise::covariance_variance
    sessions.push_back({std::chi_squared_distribution<double>(nu), capped / (capped - 2.0) / nu});
  }
  std::vector<double> means(200000);
  for (double& mean : means) {
    mean = 0.0;
    for (Session& s : sessions) mean += error(rng) / (s.pooled(rng) * s.scale) / static_cast<double>(sessions.size());
  }
  std::sort(means.begin(), means.end());
  const auto quantile = [&](double p) { return means[static_cast<std::size_t>(p * (means.size() - 1))]; };
  return {quantile((1.0 - coverage) / 2.0), quantile((1.0 + coverage) / 2.0)};
}

std::pair<double, double> chi2_mean_band(int draws, int dim, double coverage) {
  const boost::math::chi_squared sum(static_cast<double>(dim) * draws);
  return {boost::math::quantile(sum, (1.0 - coverage) / 2.0) / draws,
          boost::math::quantile(sum, (1.0 + coverage) / 2.0) / draws};
}

}  // namespace test
}  // namespace handeye
