#include <gtest/gtest.h>

#include "handeye_covariance/core/ellipsoid.h"
#include "handeye_covariance/core/errors.h"
#include "test_helpers.h"

namespace handeye {
namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;

TEST(Ellipsoid, AxisAlignedRadiiAreScaledSigmasLargestFirst) {
  const Matrix3d covariance = Vector3d(0.01 * 0.01, 0.05 * 0.05, 0.02 * 0.02).asDiagonal();
  const Ellipsoid e = ellipsoid_from_covariance(covariance, 3.0);
  EXPECT_NEAR(e.radii(0), 0.15, 1e-12);
  EXPECT_NEAR(e.radii(1), 0.06, 1e-12);
  EXPECT_NEAR(e.radii(2), 0.03, 1e-12);
  EXPECT_NEAR(std::abs(e.axes.col(0).dot(Vector3d::UnitY())), 1.0, 1e-12);
  EXPECT_NEAR(e.axes.determinant(), 1.0, 1e-12);
}

TEST(Ellipsoid, ReconstructsARotatedCovarianceAndIsRightHanded) {
  Rng rng(1);
  for (int i = 0; i < 50; ++i) {
    const Matrix3d R = random_pose(rng, 0).linear();
    const Matrix3d covariance = R * Vector3d(4, 1, 0.25).asDiagonal() * R.transpose();
    const Ellipsoid e = ellipsoid_from_covariance(covariance, 1.0);
    EXPECT_NEAR(e.axes.determinant(), 1.0, 1e-12);
    EXPECT_LE((e.axes * e.radii.cwiseAbs2().asDiagonal() * e.axes.transpose() - covariance).norm(), 1e-12);
    // The quaternion is the same rotation.
    EXPECT_LE((e.orientation().toRotationMatrix() - e.axes).norm(), 1e-12);
  }
}

TEST(Ellipsoid, DegenerateAndInvalidCovariances) {
  const Ellipsoid flat = ellipsoid_from_covariance(Vector3d(1, 1, 0).asDiagonal(), 2.0);
  EXPECT_NEAR(flat.radii(2), 0.0, 1e-15);
  EXPECT_THROW(ellipsoid_from_covariance(Vector3d(1, -1, 1).asDiagonal(), 1.0), HandEyeError);
  Matrix3d nan = Matrix3d::Identity();
  nan(1, 1) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(ellipsoid_from_covariance(nan, 1.0), HandEyeError);
}

TEST(Ellipsoid, AxisTipCovarianceMatchesSampledWobble) {
  const Matrix3d rotation_covariance = Vector3d(1e-4, 4e-4, 9e-4).asDiagonal();
  const Vector3d axis = Vector3d(1, 2, 2).normalized();
  const Matrix3d predicted = axis_tip_covariance(rotation_covariance, axis, 0.3);
  EXPECT_NEAR((predicted * axis).norm(), 0.0, 1e-15);  // flat along the axis
  Rng rng(2);
  Matrix3d sampled = Matrix3d::Zero();
  const int M = 20000;
  for (int m = 0; m < M; ++m) {
    const Vector3d tip = so3::exp(sample_gaussian(rng, rotation_covariance)) * (0.3 * axis) - 0.3 * axis;
    sampled += tip * tip.transpose() / M;
  }
  EXPECT_LE((sampled - predicted).norm(), 0.05 * predicted.norm());
}

}  // namespace
}  // namespace handeye
