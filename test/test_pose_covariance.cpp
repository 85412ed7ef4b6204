#include <gtest/gtest.h>

#include "handeye_covariance/simulation/monte_carlo.h"
#include "handeye_covariance/core/pose_covariance.h"
#include "test_helpers.h"

namespace handeye {
namespace {

using Eigen::Isometry3d;
using Eigen::Matrix3d;
using Eigen::Vector3d;

Isometry3d pose(int seed) {
  Rng rng(seed);
  return random_pose(rng, 1.0);
}

TEST(PoseJacobians, InverseMatchesNumeric) {
  const Isometry3d T = pose(1);
  const std::function<Vector6d(const Vector6d&)> f = [&](const Vector6d& d) {
    return test::pose_perturbation(test::apply(T, d).inverse(), T.inverse());
  };
  EXPECT_LE((inverse_jacobian(T) - test::numeric_jacobian<6, 6>(f)).norm(), 1e-8);
}

TEST(PoseJacobians, ComposeMatchesNumeric) {
  const Isometry3d T1 = pose(2), T2 = pose(3);
  const std::function<Vector6d(const Vector6d&)> left = [&](const Vector6d& d) {
    return test::pose_perturbation(test::apply(T1, d) * T2, T1 * T2);
  };
  const std::function<Vector6d(const Vector6d&)> right = [&](const Vector6d& d) {
    return test::pose_perturbation(T1 * test::apply(T2, d), T1 * T2);
  };
  EXPECT_LE((compose_jacobian_left(T1, T2) - test::numeric_jacobian<6, 6>(left)).norm(), 1e-8);
  EXPECT_LE((compose_jacobian_right(T1) - test::numeric_jacobian<6, 6>(right)).norm(), 1e-8);
}

TEST(RowMajor, SixBySixIsReadRowByRow) {
  std::array<double, 36> values;
  for (int i = 0; i < 36; ++i) values[i] = i;
  const Matrix6d M = from_row_major_6x6(values);
  EXPECT_EQ(M(0, 1), 1.0);  // second entry of the array is row 0, column 1
  EXPECT_EQ(M(1, 0), 6.0);
  EXPECT_EQ(M(5, 4), 34.0);
  EXPECT_EQ(to_row_major_6x6(M), values);
}

TEST(RowMajor, ThreeByThreeIsReadRowByRow) {
  const std::array<double, 9> values = {0, 1, 2, 3, 4, 5, 6, 7, 8};
  const Matrix3d M = from_row_major_3x3(values);
  EXPECT_EQ(M(0, 2), 2.0);
  EXPECT_EQ(M(2, 0), 6.0);
  EXPECT_EQ(to_row_major_3x3(M), values);
}

DecoupledCovariance anisotropic(double scale) {
  DecoupledCovariance c;
  c.rotation << 4, 1, 0, 1, 2, 0.5, 0, 0.5, 1;
  c.translation << 3, 0, 1, 0, 1, 0, 1, 0, 5;
  c.rotation *= scale;
  c.translation *= scale;
  return c;
}

// Compounding is checked against Monte-Carlo: the predicted covariance of T1 T2
// against the scatter of products of independently perturbed T1 and T2.
TEST(Compounding, DecoupledFormulasAgreeWithMonteCarlo) {
  const DecoupledPose T1{pose(4), anisotropic(1e-3)}, T2{pose(5), anisotropic(2e-3)};
  const DecoupledPose predicted = compose_decoupled(T1, T2);
  const DecoupledPose predicted_inverse = inverse_decoupled(T1);
  Rng rng(6);
  const int M = 20000;
  Matrix6d scatter = Matrix6d::Zero(), scatter_inverse = Matrix6d::Zero();
  for (int m = 0; m < M; ++m) {
    const Isometry3d a = perturb(rng, T1.pose, T1.covariance), b = perturb(rng, T2.pose, T2.covariance);
    const Vector6d e = pose_error(a * b, predicted.pose);
    const Vector6d ei = pose_error(a.inverse(), predicted_inverse.pose);
    scatter += e * e.transpose();
    scatter_inverse += ei * ei.transpose();
  }
  scatter /= M;
  scatter_inverse /= M;
  const Matrix3d mc_t = scatter.topLeftCorner<3, 3>(), mc_R = scatter.bottomRightCorner<3, 3>();
  EXPECT_LE(relative_frobenius_error(predicted.covariance.rotation, mc_R), 1.5 * sampling_floor(mc_R, M));
  EXPECT_LE(relative_frobenius_error(predicted.covariance.translation, mc_t), 1.5 * sampling_floor(mc_t, M));
  const Matrix3d mci_t = scatter_inverse.topLeftCorner<3, 3>(), mci_R = scatter_inverse.bottomRightCorner<3, 3>();
  EXPECT_LE(relative_frobenius_error(predicted_inverse.covariance.rotation, mci_R), 1.5 * sampling_floor(mci_R, M));
  EXPECT_LE(relative_frobenius_error(predicted_inverse.covariance.translation, mci_t), 1.5 * sampling_floor(mci_t, M));
}

TEST(Compounding, FourthOrderTermMattersAtLargeNoise) {
  // Eq. (72)'s extra terms shrink the sum of the two rotation covariances; at
  // 0.3 rad they are visible and must be in the direction Monte-Carlo shows.
  const DecoupledPose T1{pose(7), anisotropic(0.02)}, T2{pose(8), anisotropic(0.02)};
  const Matrix3d first_order =
      T1.covariance.rotation + T1.pose.linear() * T2.covariance.rotation * T1.pose.linear().transpose();
  const Matrix3d fourth_order = compose_decoupled(T1, T2).covariance.rotation;
  Rng rng(9);
  const int M = 40000;
  Matrix3d mc = Matrix3d::Zero();
  for (int m = 0; m < M; ++m) {
    const Vector3d e = pose_error(perturb(rng, T1.pose, T1.covariance) * perturb(rng, T2.pose, T2.covariance),
                                  T1.pose * T2.pose)
                           .tail<3>();
    mc += e * e.transpose();
  }
  mc /= M;
  EXPECT_LT(relative_frobenius_error(fourth_order, mc), relative_frobenius_error(first_order, mc));
}

TEST(Compounding, FullCovarianceComposeIsConsistent) {
  PoseWithCovariance T1{pose(10), anisotropic(1e-4).as_pose_covariance()};
  PoseWithCovariance T2{pose(11), anisotropic(3e-4).as_pose_covariance()};
  T2.covariance(0, 5) = T2.covariance(5, 0) = 1e-4;  // a cross term must propagate too
  const PoseWithCovariance predicted = compose(T1, inverse(T2));
  Rng rng(12);
  MonteCarloAccumulator acc;
  const Eigen::LLT<Matrix6d> L1(T1.covariance), L2(T2.covariance);
  std::normal_distribution<double> normal;
  for (int m = 0; m < 4000; ++m) {
    Vector6d z1, z2;
    for (int j = 0; j < 6; ++j) z1(j) = normal(rng), z2(j) = normal(rng);
    const Isometry3d a = test::apply(T1.pose, L1.matrixL() * z1), b = test::apply(T2.pose, L2.matrixL() * z2);
    acc.add(pose_error(a * b.inverse(), predicted.pose), predicted.covariance);
  }
  const MonteCarloSummary s = acc.summary();
  EXPECT_NEAR(s.pose.nees_mean, 6.0, 0.3);
  EXPECT_LE(s.pose.epsilon, 1.5 * s.pose.floor);
}

}  // namespace
}  // namespace handeye
