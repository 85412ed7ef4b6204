// The Rig: the loop Y = V^-1 X P closes for both setups, the derived maps are
// each other's inverses, and the Jacobians match numeric differences at poses
// whose rotation is 0, 1e-6 rad and near pi (where log/exp switch branches).
#include <gtest/gtest.h>

#include <random>

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/core/rig.h"
#include "test_helpers.h"

namespace handeye {
namespace {

using Eigen::Isometry3d;
using Eigen::Vector3d;

/// A pose with a rotation of `angle` about a fixed oblique axis.
Isometry3d pose_with_angle(double angle, const Vector3d& t) {
  return se3::make_pose(so3::exp(angle * Vector3d(1, 2, -2).normalized()), t);
}

const double kAngles[] = {0.0, 1e-6, M_PI - 1e-7};

Rig rig_of(Setup setup) {
  Rig rig;
  rig.setup = setup;
  rig.frames = {"base_link", "tool0", "camera_optical_frame", "tag_0"};
  return rig;
}

TEST(Rig, SetupSpellings) {
  EXPECT_EQ(setup_from_string("eye_in_hand", "here"), Setup::EyeInHand);
  EXPECT_EQ(setup_from_string(to_string(Setup::EyeToHand), "here"), Setup::EyeToHand);
  EXPECT_EQ(setup_from_eye_on_hand(true), Setup::EyeInHand);
  EXPECT_EQ(setup_from_eye_on_hand(false), Setup::EyeToHand);
  try {
    setup_from_string("eye_on_base", "config: setup");
    FAIL() << "an unknown setup was accepted";
  } catch (const HandEyeError& e) {
    EXPECT_EQ(e.code(), ErrorCode::MalformedFile);
    EXPECT_NE(std::string(e.what()).find("config: setup"), std::string::npos) << e.what();
  }
}

TEST(Rig, FramesFollowTheSetup) {
  EXPECT_EQ(rig_of(Setup::EyeInHand).camera_parent_frame(), "tool0");
  EXPECT_EQ(rig_of(Setup::EyeInHand).pattern_parent_frame(), "base_link");
  EXPECT_EQ(rig_of(Setup::EyeToHand).camera_parent_frame(), "base_link");
  EXPECT_EQ(rig_of(Setup::EyeToHand).pattern_parent_frame(), "tool0");
}

TEST(Rig, TheLoopClosesOnSimulatedSessions) {
  for (handeye::Setup setup : {Setup::EyeInHand, Setup::EyeToHand}) {
    Rng rng(3);
    const SimulatedSession s = simulate_session(rng, setup, typical_X(setup), 5, MeasurementNoise{});
    const Rig rig = rig_of(setup);
    for (const PoseSample& sample : s.samples.samples) {
      const Isometry3d& E = sample.T_base_effector;
      const Isometry3d& P = sample.T_camera_pattern;
      EXPECT_LE((rig.pattern_pose(E, s.X, P).matrix() - s.T_world_pattern.matrix()).norm(), 1e-12);
      EXPECT_LE((rig.predicted_view(E, s.X, s.T_world_pattern).matrix() - P.matrix()).norm(), 1e-12);
      EXPECT_LE((rig.effector_for_view(s.X, s.T_world_pattern, P).matrix() - E.matrix()).norm(), 1e-12);
      EXPECT_LE((rig.effector_for_link(rig.robot_link(E)).matrix() - E.matrix()).norm(), 1e-12);
    }
    // A X = X B for every motion (eq. 1), whichever setup.
    const auto& samples = s.samples.samples;
    for (std::size_t i = 0; i + 1 < samples.size(); ++i) {
      const Isometry3d A = rig.robot_motion(samples[i].T_base_effector, samples[i + 1].T_base_effector);
      const Isometry3d B = samples[i + 1].T_camera_pattern * samples[i].T_camera_pattern.inverse();
      EXPECT_LE(((A * s.X).matrix() - (s.X * B).matrix()).norm(), 1e-12) << to_string(setup);
    }
  }
}

TEST(Rig, CameraParentInBase) {
  const Isometry3d E = pose_with_angle(0.4, Vector3d(0.3, 0.1, 0.5));
  EXPECT_TRUE(rig_of(Setup::EyeInHand).camera_parent_in_base(E).isApprox(E));
  EXPECT_TRUE(rig_of(Setup::EyeToHand).camera_parent_in_base(E).isApprox(Isometry3d::Identity()));
}

TEST(Rig, RobotLinkJacobianMatchesNumeric) {
  for (handeye::Setup setup : {Setup::EyeInHand, Setup::EyeToHand}) {
    const Rig rig = rig_of(setup);
    for (double angle : kAngles) {
      const Isometry3d E = pose_with_angle(angle, Vector3d(0.4, -0.2, 0.7));
      const std::function<Vector6d(const Vector6d&)> f = [&](const Vector6d& d) {
        return test::pose_perturbation(rig.robot_link(test::apply(E, d)), rig.robot_link(E));
      };
      EXPECT_LE((rig.robot_link_jacobian(E) - test::numeric_jacobian<6, 6>(f)).norm(), 1e-7)
          << to_string(setup) << " at angle " << angle;
    }
  }
}

/// Every setup, and robot poses E_i, E_j whose rotation angles run through kAngles.
using MotionCheck = std::function<void(Setup, const Rig&, double angle_i, double angle_j, const Isometry3d& E_i,
                                       const Isometry3d& E_j)>;
void for_each_motion(const MotionCheck& check) {
  for (handeye::Setup setup : {Setup::EyeInHand, Setup::EyeToHand}) {
    const Rig rig = rig_of(setup);
    for (double angle_i : kAngles) {
      for (double angle_j : kAngles) {
        check(setup, rig, angle_i, angle_j, pose_with_angle(angle_i, Vector3d(0.4, -0.2, 0.7)),
              pose_with_angle(-angle_j, Vector3d(0.1, 0.3, 0.5)));
      }
    }
  }
}

TEST(Rig, RobotMotionJacobiansMatchNumeric) {
  for_each_motion([](handeye::Setup setup, const Rig& rig, double angle_i, double angle_j, const Isometry3d& E_i,
                         const Isometry3d& E_j) {
    const Isometry3d A = rig.robot_motion(E_i, E_j);
    const auto [dA_dEi, dA_dEj] = rig.robot_motion_jacobians(E_i, E_j);
    const std::function<Vector6d(const Vector6d&)> fi = [&](const Vector6d& d) {
      return test::pose_perturbation(rig.robot_motion(test::apply(E_i, d), E_j), A);
    };
    const std::function<Vector6d(const Vector6d&)> fj = [&](const Vector6d& d) {
      return test::pose_perturbation(rig.robot_motion(E_i, test::apply(E_j, d)), A);
    };
    EXPECT_LE((dA_dEi - test::numeric_jacobian<6, 6>(fi)).norm(), 1e-7)
        << to_string(setup) << " angles " << angle_i << ", " << angle_j;
    EXPECT_LE((dA_dEj - test::numeric_jacobian<6, 6>(fj)).norm(), 1e-7)
        << to_string(setup) << " angles " << angle_i << ", " << angle_j;
  });
}

// The written-out rotation block against the Jacobians' propagation of full 6x6
// covariances (with translation and cross blocks, which must not enter).
TEST(Rig, RobotMotionRotationCovarianceMatchesTheJacobians) {
  std::mt19937_64 rng(5);
  std::normal_distribution<double> normal;
  const auto random_covariance = [&] {
    Matrix6d F;
    for (int r = 0; r < 6; ++r) for (int c = 0; c < 6; ++c) F(r, c) = normal(rng);
    return Matrix6d(F * F.transpose());
  };
  for_each_motion([&](handeye::Setup setup, const Rig& rig, double angle_i, double angle_j, const Isometry3d& E_i,
                         const Isometry3d& E_j) {
    const Matrix6d S_i = random_covariance(), S_j = random_covariance();
    const auto [dA_dEi, dA_dEj] = rig.robot_motion_jacobians(E_i, E_j);
    const Matrix6d propagated = dA_dEi * S_i * dA_dEi.transpose() + dA_dEj * S_j * dA_dEj.transpose();
    const Eigen::Matrix3d written_out = rig.robot_motion_rotation_covariance(
        E_i, E_j, S_i.bottomRightCorner<3, 3>(), S_j.bottomRightCorner<3, 3>());
    EXPECT_LE((written_out - propagated.bottomRightCorner<3, 3>()).norm(), 1e-9 * propagated.norm())
        << to_string(setup) << " angles " << angle_i << ", " << angle_j;
  });
}

}  // namespace
}  // namespace handeye
