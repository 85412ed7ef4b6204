// Every degenerate or invalid input gets its named error and no result.
#include <gtest/gtest.h>

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/estimation/estimator.h"
#include "test_helpers.h"

namespace handeye {
namespace {

using Eigen::Isometry3d;
using Eigen::Matrix3d;
using Eigen::Vector3d;

template <typename Input>
void expect_error(const Input& input, ErrorCode code, const std::string& mentions = "") {
  try {
    solve(input);
    ADD_FAILURE() << "expected " << to_string(code) << ", got a result";
  } catch (const HandEyeError& e) {
    EXPECT_EQ(e.code(), code) << e.what();
    EXPECT_NE(std::string(e.what()).find("Fix:"), std::string::npos) << "no fix in: " << e.what();
    if (!mentions.empty()) {
      EXPECT_NE(std::string(e.what()).find(mentions), std::string::npos) << e.what();
    }
  }
}

const Isometry3d kX = se3::make_pose(so3::exp(Vector3d(0.2, -0.4, 1.1)), Vector3d(0.05, -0.02, 0.1));

MotionPair pair_for(const Isometry3d& A) { return {A, kX.inverse() * A * kX, std::nullopt}; }

MotionSet motions_about(const std::vector<Vector3d>& rotation_vectors, std::optional<MeasurementNoise> noise) {
  MotionSet set;
  set.noise = noise;
  Rng rng(1);
  for (const Vector3d& phi : rotation_vectors) {
    set.motions.push_back(pair_for(se3::make_pose(so3::exp(phi), sample_gaussian(rng, 0.01 * Matrix3d::Identity()))));
  }
  return set;
}

TEST(Degenerate, TooFewMotions) {
  expect_error(motions_about({Vector3d(0.5, 0, 0)}, paper_noise(1e-6)), ErrorCode::TooFewMotions);
  SampleSet samples;
  samples.samples.resize(2);
  expect_error(samples, ErrorCode::TooFewMotions);
}

TEST(Degenerate, PureTranslations) {
  expect_error(motions_about({Vector3d::Zero(), Vector3d::Zero(), Vector3d::Zero()}, paper_noise(1e-6)),
               ErrorCode::PureTranslation, "only translated");
  // Also when the noise is to be estimated.
  expect_error(motions_about({Vector3d::Zero(), Vector3d::Zero(), Vector3d::Zero(), Vector3d::Zero()}, std::nullopt),
               ErrorCode::PureTranslation);
}

TEST(Degenerate, ParallelRotationAxes) {
  expect_error(motions_about({Vector3d(0, 0, 0.3), Vector3d(0, 0, -0.8), Vector3d(0, 0, 1.2)}, paper_noise(1e-6)),
               ErrorCode::ParallelRotationAxes, "same axis");
  // One rotating motion is not enough either.
  expect_error(motions_about({Vector3d(0, 0, 0.6), Vector3d::Zero(), Vector3d::Zero()}, paper_noise(1e-8)),
               ErrorCode::ParallelRotationAxes);
}

TEST(Degenerate, AxesFarApartAreAccepted) {
  EXPECT_NO_THROW(solve(motions_about({Vector3d(0, 0, 0.3), Vector3d(0.3, 0, 0)}, paper_noise(1e-8))));
}

TEST(Degenerate, RotationsTooSmallForTheStatedNoise) {
  MeasurementNoise noise;  // 2 deg of camera rotation noise per axis
  noise.camera.rotation = std::pow(2.0 * M_PI / 180, 2) * Matrix3d::Identity();
  noise.camera.translation = 1e-6 * Matrix3d::Identity();
  const double one_degree = M_PI / 180;
  expect_error(motions_about({Vector3d(one_degree, 0, 0), Vector3d(0, one_degree, 0), Vector3d(0, 0, one_degree)}, noise),
               ErrorCode::RotationTooSmallForNoise, "sigma");
}

TEST(Degenerate, NonFiniteNumbers) {
  MotionSet set = motions_about({Vector3d(0.5, 0, 0), Vector3d(0, 0.5, 0)}, paper_noise(1e-6));
  set.motions[1].B.translation().y() = std::numeric_limits<double>::quiet_NaN();
  expect_error(set, ErrorCode::NonFinite, "motions[1].B");
  set = motions_about({Vector3d(0.5, 0, 0), Vector3d(0, 0.5, 0)}, paper_noise(1e-6));
  set.noise->camera.rotation(1, 1) = std::numeric_limits<double>::infinity();
  expect_error(set, ErrorCode::NonFinite, "noise.camera.rotation");
}

TEST(Degenerate, NonOrthonormalRotation) {
  MotionSet set = motions_about({Vector3d(0.5, 0, 0), Vector3d(0, 0.5, 0)}, paper_noise(1e-6));
  set.motions[0].A.linear() *= 1.01;  // e.g. a scaled matrix
  expect_error(set, ErrorCode::RotationNotOrthonormal, "motions[0].A");
  set = motions_about({Vector3d(0.5, 0, 0), Vector3d(0, 0.5, 0)}, paper_noise(1e-6));
  set.motions[1].B.linear().col(2) *= -1.0;  // a reflection: det = -1
  expect_error(set, ErrorCode::RotationNotOrthonormal, "det");
}

TEST(Degenerate, InvalidNoise) {
  MotionSet set = motions_about({Vector3d(0.5, 0, 0), Vector3d(0, 0.5, 0)}, paper_noise(1e-6));
  set.noise->robot.translation(2, 2) = -1e-6;
  expect_error(set, ErrorCode::InvalidNoise, "positive semi-definite");
  set = motions_about({Vector3d(0.5, 0, 0), Vector3d(0, 0.5, 0)}, paper_noise(1e-6));
  set.noise->camera.rotation(0, 1) = 1e-6;  // not symmetric
  expect_error(set, ErrorCode::InvalidNoise, "symmetric");
  set = motions_about({Vector3d(0.5, 0, 0), Vector3d(0, 0.5, 0)}, MeasurementNoise{});
  expect_error(set, ErrorCode::InvalidNoise, "singular");  // all-zero noise
}

TEST(Degenerate, AngleMismatchFarBeyondNoise) {
  MotionSet set = motions_about({Vector3d(0.5, 0, 0), Vector3d(0, 0.5, 0), Vector3d(0.3, 0.3, 0)}, paper_noise(1e-6));
  set.motions[2].B.linear() = so3::exp(Vector3d(0, 0, 0.2)) * set.motions[2].B.linear();  // unsynchronised
  expect_error(set, ErrorCode::AngleMismatch, "motions[2]");
}

TEST(Degenerate, AngleMismatchWithEstimatedNoise) {
  Rng rng(2);
  MotionSet set = simulate_motions(rng, kX, 20, paper_noise(1e-6));
  set.noise.reset();
  EXPECT_NO_THROW(solve(set));
  set.motions[7].B.linear() = so3::exp(Vector3d(0.3, 0, 0)) * set.motions[7].B.linear();
  expect_error(set, ErrorCode::AngleMismatch, "motions[7]");
}

TEST(Degenerate, NoiseUnidentifiableWithTwoMotionsAndNoNoise) {
  expect_error(motions_about({Vector3d(0.5, 0, 0), Vector3d(0, 0.5, 0)}, std::nullopt), ErrorCode::NoiseUnidentifiable);
}

TEST(Degenerate, PerItemNoiseWithoutGlobalBlock) {
  MotionSet set = motions_about({Vector3d(0.5, 0, 0), Vector3d(0, 0.5, 0), Vector3d(0, 0, 0.5)}, std::nullopt);
  set.motions[0].noise = paper_noise(1e-6);
  expect_error(set, ErrorCode::InvalidNoise, "global noise block");
}

TEST(Degenerate, PoorlyConstrainedWhenNoiseSwampsTheMotions) {
  MeasurementNoise noise;  // 10 deg per axis: the linearisation is meaningless
  noise.camera.rotation = std::pow(10.0 * M_PI / 180, 2) * Matrix3d::Identity();
  noise.camera.translation = 1e-4 * Matrix3d::Identity();
  SolverOptions options;
  options.min_rotation_sigmas = 0.0;  // let it past the per-motion check
  try {
    solve(motions_about({Vector3d(1.2, 0, 0), Vector3d(0, 1.2, 0)}, noise), options);
    ADD_FAILURE() << "expected PoorlyConstrained";
  } catch (const HandEyeError& e) {
    EXPECT_EQ(e.code(), ErrorCode::PoorlyConstrained) << e.what();
  }
}

}  // namespace
}  // namespace handeye
