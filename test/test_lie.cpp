#include <gtest/gtest.h>

#include "test_helpers.h"

namespace handeye {
namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;

// The edge cases the estimator meets: identity, tiny, generic, just below pi, pi.
const double kAngles[] = {0.0, 1e-6, 0.3, 2.0, M_PI - 1e-6, M_PI};

Vector3d axis(int i) {
  Rng rng(100 + i);
  return sample_gaussian(rng, Matrix3d::Identity()).normalized();
}

TEST(So3, HatIsCrossProductAndVeeInvertsIt) {
  const Vector3d w(0.3, -1.2, 2.5), v(-0.7, 0.4, 1.1);
  EXPECT_TRUE(so3::hat(w).isApprox(-so3::hat(w).transpose()));
  EXPECT_NEAR((so3::hat(w) * v - w.cross(v)).norm(), 0.0, 1e-15);
  EXPECT_TRUE(so3::vee(so3::hat(w)).isApprox(w));
}

TEST(So3, ExpIsARotationAtEveryAngle) {
  for (double angle : kAngles) {
    for (int i = 0; i < 5; ++i) {
      const Matrix3d R = so3::exp(angle * axis(i));
      EXPECT_NEAR((R.transpose() * R - Matrix3d::Identity()).norm(), 0.0, 1e-14) << angle;
      EXPECT_NEAR(R.determinant(), 1.0, 1e-14) << angle;
      // Agrees with Eigen's independent implementation.
      EXPECT_LE((R - Eigen::AngleAxisd(angle, axis(i)).toRotationMatrix()).norm(), 1e-14) << angle;
    }
  }
}

TEST(So3, LogInvertsExpAtZeroTinyAndNearPi) {
  for (double angle : kAngles) {
    for (int i = 0; i < 5; ++i) {
      const Vector3d phi = angle * axis(i);
      const Vector3d back = so3::log(so3::exp(phi));
      if (angle < M_PI) {
        // Relative accuracy: 1e-6 rad must come back to 1e-6 * 1e-9.
        EXPECT_LE((back - phi).norm(), 1e-9 * std::max(angle, 1e-300) + 1e-15) << "angle " << angle;
      } else {
        // At exactly pi, phi and -phi are the same rotation; either is right.
        EXPECT_LE(std::min((back - phi).norm(), (back + phi).norm()), 1e-9) << "angle " << angle;
      }
      EXPECT_LE(back.norm(), M_PI + 1e-12);
      EXPECT_NEAR((so3::exp(back) - so3::exp(phi)).norm(), 0.0, 1e-13) << angle;
    }
  }
}

TEST(So3, LogAngleIsAccurateJustBelowPi) {
  // acos-based logs lose half the digits here; ours must not.
  const double angle = M_PI - 1e-6;
  EXPECT_NEAR(so3::log(so3::exp(angle * axis(0))).norm(), angle, 1e-12);
}

TEST(So3, LeftJacobianMatchesNumericDerivative) {
  // exp(phi + d) = exp(J d) exp(phi) to first order.
  for (double angle : kAngles) {
    if (angle == M_PI) continue;  // log's branch cut: tested through the inverse below
    const Vector3d phi = angle * axis(1);
    const std::function<Vector3d(const Vector3d&)> f = [&](const Vector3d& d) {
      return test::rotation_difference(so3::exp(phi + d), so3::exp(phi));
    };
    const Matrix3d numeric = test::numeric_jacobian<3, 3>(f);
    EXPECT_LE((so3::left_jacobian(phi) - numeric).norm(), 1e-8) << "angle " << angle;
  }
}

TEST(So3, LeftJacobianInverseMatchesNumericDerivative) {
  // log(exp(d) exp(phi)) = phi + J^-1 d to first order.
  for (double angle : kAngles) {
    if (angle >= M_PI - 1e-3) continue;  // a finite difference would cross the log's branch cut
    const Vector3d phi = angle * axis(2);
    const std::function<Vector3d(const Vector3d&)> f = [&](const Vector3d& d) {
      return Vector3d(so3::log(so3::exp(d) * so3::exp(phi)) - phi);
    };
    const Matrix3d numeric = test::numeric_jacobian<3, 3>(f);
    EXPECT_LE((so3::left_jacobian_inverse(phi) - numeric).norm(), 1e-8) << "angle " << angle;
  }
}

TEST(So3, JacobianTimesInverseIsIdentityIncludingPi) {
  for (double angle : kAngles) {
    const Vector3d phi = angle * axis(3);
    const Matrix3d product = so3::left_jacobian(phi) * so3::left_jacobian_inverse(phi);
    EXPECT_LE((product - Matrix3d::Identity()).norm(), 1e-12) << "angle " << angle;
    EXPECT_TRUE(so3::left_jacobian_inverse(phi).allFinite()) << angle;
  }
}

TEST(So3, OtherRepresentativeIsTheSameRotation) {
  for (double angle : {0.5, M_PI - 1e-6, M_PI}) {
    const Vector3d phi = angle * axis(4);
    const Vector3d other = so3::other_representative(phi);
    EXPECT_NEAR(other.norm(), 2 * M_PI - angle, 1e-12);
    EXPECT_NEAR((so3::exp(other) - so3::exp(phi)).norm(), 0.0, 1e-12);
  }
}

TEST(Se3, ExpLogRoundTrip) {
  for (double angle : kAngles) {
    Vector6d twist;
    twist << 0.3, -0.2, 0.5, angle * axis(5);
    const Eigen::Isometry3d T = se3::exp(twist);
    const Eigen::Isometry3d back = se3::exp(se3::log(T));
    EXPECT_NEAR((back.matrix() - T.matrix()).norm(), 0.0, 1e-12) << "angle " << angle;
    if (angle < M_PI) {
      EXPECT_LE((se3::log(T) - twist).norm(), 1e-9) << "angle " << angle;
    }
  }
}

}  // namespace
}  // namespace handeye
