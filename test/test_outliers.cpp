// Outlier rejection: 10% gross outliers of the two kinds users meet (a flipped
// tag pose, a detection paired with the wrong robot pose) must not move X
// beyond 3 sigma, and clean sessions must keep their samples.
#include "handeye_covariance/estimation/outliers.h"
#include "handeye_covariance/estimation/solve.h"

#include <boost/math/distributions/normal.hpp>
#include <set>

#include "handeye_covariance/core/statistics.h"
#include "handeye_covariance/simulation/monte_carlo.h"
#include "test_helpers.h"

namespace handeye {
namespace {

/// The planar-target ambiguity of PnP: the pattern seen tilted the other way
/// (its normal mirrored about the line of sight), at the same position.
Eigen::Isometry3d flipped(const Eigen::Isometry3d& T_camera_pattern) {
  const Eigen::Vector3d sight = T_camera_pattern.translation().normalized();
  const Eigen::Vector3d normal = T_camera_pattern.linear().col(2);
  const Eigen::Vector3d mirrored = 2.0 * normal.dot(sight) * sight - normal;
  Eigen::Isometry3d out = T_camera_pattern;
  out.linear() = Eigen::Quaterniond::FromTwoVectors(normal, mirrored).toRotationMatrix() * T_camera_pattern.linear();
  return out;
}

struct Injected {
  SampleSet samples;
  std::vector<int> outliers;
};

/// n samples; every 10th has a flipped pattern pose or another sample's pattern pose.
Injected with_outliers(Rng& rng, handeye::Setup setup, int n, bool estimated_noise) {
  SimulatedSession s = simulate_session(rng, setup, typical_X(setup), n, test::sim_noise());
  Injected out{s.samples, {}};
  for (int i = 5; i < n; i += 10) {
    PoseSample& sample = out.samples.samples[i];
    sample.T_camera_pattern = (i / 10) % 2 == 0 ? flipped(sample.T_camera_pattern)
                                                : s.samples.samples[i - 3].T_camera_pattern;  // wrong stamp
    out.outliers.push_back(i);
  }
  if (estimated_noise) out.samples.noise.reset();
  return out;
}

/// The robust scales' constants are their distributions' own, to the digits written.
TEST(Statistics, ConstantsAreTheirDistributionsOwn) {
  const boost::math::normal normal;
  EXPECT_NEAR(kChi2SixDofMedian, chi2_quantile(6, 0.5), 5e-4);
  EXPECT_NEAR(kHalfNormalLowerQuartile, boost::math::quantile(normal, 0.625), 5e-5);
  EXPECT_NEAR(kNormalSigmaPerMad, 1.0 / boost::math::quantile(normal, 0.75), 5e-5);
  EXPECT_NEAR(chi2_quantile(3, 0.95), 7.814727903251178, 1e-12);
  EXPECT_NEAR(chi2_quantile(6, 0.95), 12.591587243743977, 1e-12);
  EXPECT_NEAR(chi2_upper_tail(6, chi2_quantile(6, 0.95)), 0.05, 1e-12);
  EXPECT_EQ(chi2_upper_tail(6, -1.0), 1.0);
}

/// median, robust_sigma and linear_quantile on values whose answers are known.
TEST(Statistics, OrderStatistics) {
  EXPECT_EQ(median({3.0, 1.0, 2.0}), 2.0);
  EXPECT_EQ(median({4.0, 1.0, 3.0, 2.0}), 3.0);  // the upper one of an even count
  EXPECT_EQ(linear_quantile({}, 0.5), 0.0);
  EXPECT_DOUBLE_EQ(linear_quantile({0.0, 10.0, 20.0}, 0.25), 5.0);
  EXPECT_DOUBLE_EQ(linear_quantile({5.0, 0.0, 10.0}, 1.0), 10.0);
  EXPECT_EQ(robust_sigma({}), 0.0);
  // |N(0, 2^2)|: its lower quartile gives sigma 2; a third of the values bad (1e3) moves it to
  // the half-normal's 37.5% point, 2 x 0.4888 / 0.3186 = 3.07, not towards 1e3.
  Rng rng(7);
  std::normal_distribution<double> n(0.0, 2.0);
  std::vector<double> values;
  for (int i = 0; i < 20000; ++i) values.push_back(std::abs(n(rng)));
  EXPECT_NEAR(robust_sigma(values), 2.0, 0.05);
  values.insert(values.end(), 10000, 1e3);
  EXPECT_NEAR(robust_sigma(values), 3.07, 0.08);
}

TEST(Outliers, TenPercentGrossOutliersAreRejectedAndXStaysWithin3Sigma) {
  int sessions = 0, missed = 0, false_rejections = 0, beyond = 0;
  for (handeye::Setup setup : {Setup::EyeInHand, Setup::EyeToHand}) {
    for (bool estimated : {false, true}) {
      for (unsigned seed = 1; seed <= 10; ++seed) {
        Rng rng(seed + (setup == Setup::EyeToHand ? 100 : 0));
        const Injected in = with_outliers(rng, setup, 30, estimated);
        std::optional<Calibration> plain;  // the plain estimator refuses most of these (AngleMismatch)
        try {
          plain = solve(in.samples);
        } catch (const HandEyeError&) {
        }
        const Calibration robust = solve_robust(in.samples);
        const Eigen::Isometry3d X = typical_X(setup);
        std::vector<int> rejected;
        for (const auto& r : robust.rejected) rejected.push_back(r.index);
        for (int o : in.outliers) missed += std::count(rejected.begin(), rejected.end(), o) ? 0 : 1;
        for (int r : rejected) false_rejections += std::count(in.outliers.begin(), in.outliers.end(), r) ? 0 : 1;
        // The robust result is the outlier-free solve (the samples removed by hand) ...
        SampleSet oracle = in.samples;
        oracle.samples.clear();
        for (int i = 0; i < 30; ++i) {
          if (!std::count(in.outliers.begin(), in.outliers.end(), i)) oracle.samples.push_back(in.samples.samples[i]);
        }
        const Calibration o = estimate(oracle, Method::Joint);  // the default estimator
        EXPECT_TRUE(robust.T_parent_camera.isApprox(o.T_parent_camera, 1e-9)) << seed;
        EXPECT_TRUE(robust.pose_covariance.isApprox(o.pose_covariance, 1e-9)) << seed;
        // ... so X is within "3 sigma" of the truth: the 6-dof Mahalanobis distance
        // below the chi2(6) quantile of 3 sigma's two-sided probability, 0.9973.
        const Vector6d e = pose_error(robust.T_parent_camera, X);
        if (e.dot(robust.pose_covariance.ldlt().solve(e)) > 20.06) ++beyond;
        ++sessions;
        if (seed == 1) {
          char without[96] = "refused by the plain estimator";
          if (plain) {
            const Vector6d ep = pose_error(plain->T_parent_camera, X);
            std::snprintf(without, sizeof without, "off by %.2f mm / %.3f deg without rejection",
                          ep.head<3>().norm() * 1e3, ep.tail<3>().norm() * 180 / M_PI);
          }
          std::printf("%s, noise %s: %s; with it off by %.3f mm / %.4f deg (1 sigma %.3f mm / %.4f deg), %zu rejected\n",
                      to_string(setup), estimated ? "estimated" : "given", without, e.head<3>().norm() * 1e3,
                      e.tail<3>().norm() * 180 / M_PI, max_sigma(robust.translation_covariance) * 1e3,
                      max_sigma(robust.rotation_covariance) * 180 / M_PI, robust.rejected.size());
        }
      }
    }
  }
  std::printf("%d sessions: %d outliers missed, %d good samples rejected, %d X beyond 3 sigma (6-dof)\n", sessions,
              missed, false_rejections, beyond);
  EXPECT_EQ(missed, 0);
  EXPECT_LE(false_rejections, sessions / 10);
  EXPECT_LE(beyond, 1);  // 0.0027 x 40 sessions: about 0.1 expected
}

TEST(Outliers, CleanSessionsKeepTheirSamplesAndTheirCovariance) {
  int false_rejections = 0;
  for (unsigned seed = 1; seed <= 20; ++seed) {
    Rng rng(100 + seed);
    const SimulatedSession s = simulate_session(rng, Setup::EyeInHand, typical_X(Setup::EyeInHand), 25, test::sim_noise());
    const Calibration robust = solve_robust(s.samples);
    false_rejections += static_cast<int>(robust.rejected.size());
    if (robust.rejected.empty()) {
      EXPECT_TRUE(robust.pose_covariance.isApprox(estimate(s.samples, Method::Joint).pose_covariance, 1e-12));
    }
  }
  EXPECT_LE(false_rejections, 1) << "the gates are at chi2 0.9999 and 6 robust sigmas";
}

TEST(Outliers, EachSampleFitsItsCalibrationAsItsPredictedCovarianceSays) {
  // Every sample's fit (~status, the panel's table, the report): the residual of a good
  // sample is chi2(6) in sigmas^2 (a little less in-sample: the fit absorbs part of it),
  // a planted outlier stands far out, judged against the rest.
  double sum = 0.0;
  int good = 0;
  for (unsigned seed = 1; seed <= 10; ++seed) {
    Rng rng(300 + seed);
    const Injected in = with_outliers(rng, Setup::EyeInHand, 30, false);
    const Calibration c = solve_robust(in.samples);
    const std::vector<SampleFit> fits = sample_fits(in.samples, c);
    ASSERT_EQ(fits.size(), in.samples.samples.size());
    for (std::size_t i = 0; i < fits.size(); ++i) {
      const bool outlier = std::count(in.outliers.begin(), in.outliers.end(), static_cast<int>(i)) > 0;
      EXPECT_NEAR(fits[i].translation, fits[i].error.head<3>().norm(), 1e-15);
      EXPECT_NEAR(fits[i].rotation, fits[i].error.tail<3>().norm(), 1e-15);
      if (outlier) {
        EXPECT_GT(fits[i].sigmas, 20.0) << "seed " << seed << ", planted outlier " << i;
      } else {
        EXPECT_GT(fits[i].sigmas, 0.0);
        sum += fits[i].sigmas * fits[i].sigmas;
        ++good;
      }
    }
  }
  const double mean = sum / good;
  std::printf("sample fits: mean squared sigmas %.2f over %d good samples (chi2(6): 6)\n", mean, good);
  EXPECT_GT(mean, 4.5);
  EXPECT_LT(mean, 6.5);
}

TEST(Outliers, TooManyDisagreeingSamplesAreRefused) {
  Rng rng(7);
  SimulatedSession s = simulate_session(rng, Setup::EyeInHand, typical_X(Setup::EyeInHand), 12, test::sim_noise());
  for (int i = 0; i < 5; ++i) s.samples.samples[2 * i + 1].T_camera_pattern = random_view(rng, {});
  try {
    solve_robust(s.samples);
    FAIL() << "5 of 12 random pattern poses accepted";
  } catch (const HandEyeError& e) {
    EXPECT_EQ(e.code(), ErrorCode::TooManyOutliers) << e.what();
    EXPECT_NE(std::string(e.what()).find("stamp pairing"), std::string::npos) << e.what();
  }
}

// A session of more than consensus_partners + 1 samples is screened with each sample's
// partners, not every pair: on 600 samples with every 10th a gross outlier (a flipped
// pattern pose or another sample's), the partners' screen rejects what the all-pairs
// screen rejects, every planted outlier and no other sample, at a tenth of the pairs.
TEST(Outliers, TheConsensusOfALargeSessionScreensEachSampleWithItsPartnersAsAllPairsWould) {
  Rng rng(61);
  const int n = 600;
  const Injected in = with_outliers(rng, Setup::EyeInHand, n, true);
  OutlierOptions all_pairs;
  all_pairs.consensus_partners = n;
  const OutlierOptions partners;  // the default
  const auto indices = [](const std::vector<Calibration::Rejected>& rejected) {
    std::vector<int> out;
    for (const auto& r : rejected) out.push_back(r.index);
    return out;
  };
  const std::vector<Calibration::Rejected> by_all = consensus(in.samples, all_pairs);
  const std::vector<Calibration::Rejected> by_partners = consensus(in.samples, partners);
  EXPECT_EQ(indices(by_partners), indices(by_all));
  EXPECT_EQ(indices(by_partners), in.outliers) << "every planted outlier, and no other sample";
  for (const auto& r : by_all) EXPECT_EQ(r.compared, n - 1) << "sample " << r.index;
  for (const auto& r : by_partners) EXPECT_EQ(r.compared, partners.consensus_partners - 1) << "sample " << r.index;  // n even
  std::printf("[consensus] %d samples, %zu planted: all pairs rejected %zu, %d partners each rejected %zu\n", n,
              in.outliers.size(), by_all.size(), partners.consensus_partners, by_partners.size());
  OutlierOptions odd;
  odd.consensus_partners = 7;
  EXPECT_THROW(consensus(in.samples, odd), std::invalid_argument);
}

// The pairs themselves: up to partners + 1 samples every pair, in the order of the nested loop;
// beyond, distinct pairs (i < j), each sample in exactly `partners` of them (partners - 1 when
// n is even), offsets reaching n / 2.
TEST(Outliers, TheConsensusPairsAreAllPairsUpToPartnersPlusOneAndThenEachSamplesPartners) {
  const int partners = OutlierOptions{}.consensus_partners;
  for (int n : {2, 6, partners + 1, partners + 2, partners + 3, 600, 601}) {
    const std::vector<std::pair<int, int>> pairs = consensus_pairs(n, partners);
    std::set<std::pair<int, int>> distinct(pairs.begin(), pairs.end());
    EXPECT_EQ(distinct.size(), pairs.size()) << n << " samples: a pair twice";
    std::vector<int> count(static_cast<std::size_t>(n), 0);
    int widest = 0;
    for (const auto& [i, j] : pairs) {
      ASSERT_TRUE(0 <= i && i < j && j < n) << n << " samples: pair " << i << ", " << j;
      ++count[static_cast<std::size_t>(i)], ++count[static_cast<std::size_t>(j)];
      widest = std::max(widest, std::min(j - i, n - (j - i)));
    }
    if (n - 1 <= partners) {
      std::vector<std::pair<int, int>> nested;
      for (int i = 0; i < n; ++i) {
        for (int j = i + 1; j < n; ++j) nested.emplace_back(i, j);
      }
      EXPECT_EQ(pairs, nested) << n << " samples";
      continue;
    }
    const int each = n % 2 == 0 ? partners - 1 : partners;
    for (int s = 0; s < n; ++s) EXPECT_EQ(count[static_cast<std::size_t>(s)], each) << n << " samples: sample " << s;
    EXPECT_EQ(widest, n / 2) << n << " samples";
  }
  EXPECT_THROW(consensus_pairs(100, 7), std::invalid_argument);
  EXPECT_THROW(consensus_pairs(100, 2), std::invalid_argument);
}

}  // namespace
}  // namespace handeye
