// The object pose in the base frame (eq. 68): Jacobians checked numerically,
// each term's part, refusals, and a Monte-Carlo check of the compounded
// covariance over whole calibrations.
#include "handeye_covariance/core/object_pose.h"

#include "handeye_covariance/estimation/estimator.h"
#include "handeye_covariance/simulation/monte_carlo.h"
#include "test_helpers.h"

namespace handeye {
namespace {

using test::apply;
using test::pose_perturbation;

ObjectPoseInput example_input(Setup setup) {
  Rng rng(3);
  ObjectPoseInput in;
  in.rig.setup = setup;
  in.T_base_effector.pose = random_pose(rng, 0.6);
  in.X.pose = typical_X(setup);
  in.T_camera_object.pose = random_view(rng, {});
  // Full covariances, cross blocks included, different per input.
  for (auto* T : {&in.T_base_effector, &in.X, &in.T_camera_object}) {
    Matrix6d L = Matrix6d::Random() * 1e-3;
    T->covariance = L * L.transpose() + 1e-8 * Matrix6d::Identity();
  }
  return in;
}

TEST(ObjectPose, EachTermIsTheNumericJacobianOfEq68) {
  for (handeye::Setup setup : {Setup::EyeInHand, Setup::EyeToHand}) {
    const ObjectPoseInput in = example_input(setup);
    const ObjectPose out = object_in_base(in);
    const Eigen::Isometry3d E = setup == Setup::EyeInHand ? in.T_base_effector.pose : Eigen::Isometry3d::Identity();
    const auto object = [&](const Eigen::Isometry3d& e, const Eigen::Isometry3d& x, const Eigen::Isometry3d& p) {
      return e * x * p;
    };
    const auto jacobian = [&](int which) {
      return test::numeric_jacobian<6, 6>([&](const Vector6d& d) -> Vector6d {
        const Eigen::Isometry3d T = object(which == 0 ? apply(E, d) : E, which == 1 ? apply(in.X.pose, d) : in.X.pose,
                                           which == 2 ? apply(in.T_camera_object.pose, d) : in.T_camera_object.pose);
        return pose_perturbation(T, out.T_base_object.pose);
      });
    };
    const Matrix6d J_robot = jacobian(0), J_X = jacobian(1), J_object = jacobian(2);
    const double tol = 1e-9;
    if (setup == Setup::EyeInHand) {
      EXPECT_TRUE(out.from_robot.isApprox(J_robot * in.T_base_effector.covariance * J_robot.transpose(), 1e-6));
    } else {
      EXPECT_EQ(out.from_robot, Matrix6d::Zero()) << "eye_to_hand: no robot pose in eq. 68";
    }
    EXPECT_TRUE(out.from_calibration.isApprox(J_X * in.X.covariance * J_X.transpose(), 1e-6));
    EXPECT_TRUE(out.from_detection.isApprox(J_object * in.T_camera_object.covariance * J_object.transpose(), 1e-6));
    EXPECT_LT((out.T_base_object.covariance - out.from_robot - out.from_calibration - out.from_detection)
                  .cwiseAbs().maxCoeff(), tol);
    EXPECT_TRUE(out.T_base_object.pose.isApprox(E * in.X.pose * in.T_camera_object.pose));
  }
}

TEST(ObjectPose, PointTermsSumToThePointCovariance) {
  const ObjectPose out = object_in_base(example_input(Setup::EyeInHand));
  const Eigen::Vector3d hole(0.02, -0.03, 0.0);
  const PointInBase p = point_in_base(out, hole);
  EXPECT_TRUE(p.position.isApprox(out.T_base_object.pose * hole));
  EXPECT_TRUE(p.covariance.isApprox(p.from_robot + p.from_calibration + p.from_detection, 1e-9));
  // Numerically: the point moves as the object pose does.
  const Eigen::Matrix<double, 3, 6> J = test::numeric_jacobian<3, 6>([&](const Vector6d& d) -> Eigen::Vector3d {
    return apply(out.T_base_object.pose, d) * hole - p.position;
  });
  EXPECT_TRUE(p.covariance.isApprox(J * out.T_base_object.covariance * J.transpose(), 1e-6));
}

TEST(ObjectPose, RefusesBadInputsNamingThem) {
  ObjectPoseInput in = example_input(Setup::EyeInHand);
  in.X.covariance(0, 0) = std::nan("");
  try {
    object_in_base(in);
    FAIL() << "NaN accepted";
  } catch (const HandEyeError& e) {
    EXPECT_EQ(e.code(), ErrorCode::NonFinite);
    EXPECT_NE(std::string(e.what()).find("calibration.covariance"), std::string::npos) << e.what();
  }
  in = example_input(Setup::EyeInHand);
  in.T_camera_object.covariance(3, 3) = -1e-4;
  EXPECT_THROW(object_in_base(in), HandEyeError);
  in = example_input(Setup::EyeInHand);
  in.T_base_effector.pose.linear() *= 1.01;
  EXPECT_THROW(object_in_base(in), HandEyeError);
  // eye_to_hand ignores the robot pose entirely, even an invalid one.
  in.rig.setup = Setup::EyeToHand;
  EXPECT_NO_THROW(object_in_base(in));
}

struct ObjectStudy {
  MonteCarloSummary compounded, without_calibration;
  double calibration_share = 0.0;  // mean share of the position variance that comes from X
};

/// M independent worlds: calibrate X from a fresh 12-pose session, then locate
/// an object 0.7 m in front of the camera from a fresh robot pose and a fresh
/// detection, and compare with the truth.
ObjectStudy run_object_study(Setup setup, int M, unsigned seed) {
  Rng rng(seed);
  const double deg = M_PI / 180.0, mm = 1e-3;
  MeasurementNoise noise;
  noise.robot.rotation = std::pow(0.01 * deg, 2) * Eigen::Matrix3d::Identity();
  noise.robot.translation = std::pow(0.05 * mm, 2) * Eigen::Matrix3d::Identity();
  noise.camera.rotation = std::pow(0.05 * deg, 2) * Eigen::Matrix3d::Identity();
  noise.camera.translation = std::pow(0.3 * mm, 2) * Eigen::Matrix3d::Identity();
  ViewpointOptions object_view;
  object_view.min_distance = object_view.max_distance = 0.7;
  const Eigen::Isometry3d X = typical_X(setup);
  MonteCarloAccumulator compounded, without_calibration;
  ObjectStudy study;
  for (int m = 0; m < M; ++m) {
    const SimulatedSession session = simulate_session(rng, setup, X, 12, noise);
    const Calibration c = solve(session.samples);
    // The object: seen from a fresh viewpoint; eye_to_hand ignores the robot.
    const Eigen::Isometry3d P = random_view(rng, object_view);
    const Eigen::Isometry3d E = random_pose(rng, 0.5);
    const Eigen::Isometry3d truth = setup == Setup::EyeInHand ? E * X * P : X * P;
    ObjectPoseInput in;
    in.rig.setup = setup;
    in.T_base_effector = {perturb(rng, E, noise.robot), noise.robot.as_pose_covariance()};
    in.X = {c.T_parent_camera, c.pose_covariance};
    in.T_camera_object = {perturb(rng, P, noise.camera), noise.camera.as_pose_covariance()};
    const ObjectPose out = object_in_base(in);
    const Vector6d error = pose_error(out.T_base_object.pose, truth);
    compounded.add(error, out.T_base_object.covariance);
    without_calibration.add(error, out.from_robot + out.from_detection);
    study.calibration_share += out.from_calibration.topLeftCorner<3, 3>().trace() /
                               out.T_base_object.covariance.topLeftCorner<3, 3>().trace() / M;
  }
  study.compounded = compounded.summary();
  study.without_calibration = without_calibration.summary();
  return study;
}

TEST(ObjectPose, MonteCarloConfirmsTheCompoundedCovariance) {
  // M = 2000: an honest 3-dof NEES mean has sd sqrt(6 / M) = 0.055.
  for (handeye::Setup setup : {Setup::EyeInHand, Setup::EyeToHand}) {
    const ObjectStudy s = run_object_study(setup, 2000, 11);
    const MonteCarloSummary& c = s.compounded;
    std::printf("%s: NEES position %.3f rotation %.3f pose %.3f; eps t %.3f (floor %.3f) R %.3f (floor %.3f); "
                "X's share of the position variance %.2f; NEES without X's covariance %.2f / %.2f\n",
                to_string(setup), c.translation.nees_mean, c.rotation.nees_mean, c.pose.nees_mean,
                c.translation.epsilon, c.translation.floor, c.rotation.epsilon, c.rotation.floor, s.calibration_share,
                s.without_calibration.translation.nees_mean, s.without_calibration.rotation.nees_mean);
    EXPECT_GE(c.translation.nees_mean, 2.8);
    EXPECT_LE(c.translation.nees_mean, 3.2);
    EXPECT_GE(c.rotation.nees_mean, 2.8);
    EXPECT_LE(c.rotation.nees_mean, 3.2);
    EXPECT_LT(c.translation.epsilon, 3.0 * c.translation.floor);
    EXPECT_LT(c.rotation.epsilon, 3.0 * c.rotation.floor);
    // The regime matters: X is a real part of the error, and leaving its
    // covariance out (what other tools do) is visibly overconfident.
    EXPECT_GT(s.calibration_share, 0.2);
    EXPECT_GT(s.without_calibration.translation.nees_mean, 3.6);
  }
}

}  // namespace
}  // namespace handeye
