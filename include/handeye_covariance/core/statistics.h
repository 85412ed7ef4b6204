// Order statistics and the distribution constants the estimators and studies use,
// in one place. The robust scales divide by the constants as rounded here.
#pragma once

#include <vector>

namespace handeye {

/// chi2(6)'s median (5.3481...): a squared Mahalanobis distance of a pose's 6 dof.
constexpr double kChi2SixDofMedian = 5.348;
/// The 25% point of |N(0, 1)| (0.31864...): the half-normal's lower quartile.
constexpr double kHalfNormalLowerQuartile = 0.3186;
/// A normal's sigma over its median absolute deviation (1 / 0.67449...).
constexpr double kNormalSigmaPerMad = 1.4826;

/// The median (the upper one of an even count); values must not be empty.
double median(std::vector<double> values);

/// Robust sigma of |differences| (half-normal) from their lower quartile: it holds
/// while fewer than 75% of the values are bad (the median breaks at 50%, which 30%
/// bad samples already reach in pairs: 1 - 0.7^2 = 51%). 0 for none.
double robust_sigma(std::vector<double> values);

/// The p-quantile of `values`, linear between order statistics (0 for none).
double linear_quantile(std::vector<double> values, double p);

/// The `level` quantile of chi2(dof) (boost.math).
double chi2_quantile(double dof, double level);
/// P(chi2(dof) > statistic) (boost.math); 1 for a statistic <= 0.
double chi2_upper_tail(double dof, double statistic);

}  // namespace handeye
