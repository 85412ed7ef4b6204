// The corner-level calibration (corners/corner_calibration.h) on simulated
// corners: its residuals against OpenCV's projection, its Jacobian against
// numeric differences in the package's perturbation convention, and its
// covariance against the actual error over seeded sessions (robot exact, robot
// noisy, intrinsics off). Rendered images are test_images' and BENCHMARKS.md's.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <algorithm>
#include <functional>
#include <numeric>
#include <optional>

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/corners/corner_calibration.h"
#include "handeye_covariance/estimation/joint_estimator.h"
#include "handeye_covariance/estimation/solve.h"
#include "handeye_covariance/session/calibration_session.h"
#include "handeye_covariance/simulation/pattern_renderer.h"
#include "test_helpers.h"

namespace handeye {
namespace {

using Eigen::Isometry3d;
using Eigen::Vector2d;
using Eigen::Vector3d;

// An 8 x 5 grid of corners, 3 cm apart, centred on the pattern frame's origin
// (where the simulated views look).
std::vector<Vector3d> grid() {
  std::vector<Vector3d> points;
  for (int r = 0; r < 5; ++r)
    for (int c = 0; c < 8; ++c) points.emplace_back(0.03 * (c - 3.5), 0.03 * (r - 2.0), 0.0);
  return points;
}

struct Scene {
  Rig rig;
  Isometry3d X, Y;
  std::vector<Isometry3d> effector;  // true T_base_effector
  std::vector<Isometry3d> view;      // true T_camera_pattern
};

Scene scene(Rng& rng, Setup setup, int n) {
  const SimulatedSession s = simulate_session(rng, setup, typical_X(setup), n, MeasurementNoise{});
  Scene out;
  out.rig.setup = setup;
  out.X = s.X;
  out.Y = s.T_world_pattern;
  for (const PoseSample& sample : s.samples.samples) {
    out.effector.push_back(sample.T_base_effector);
    out.view.push_back(sample.T_camera_pattern);
  }
  return out;
}

// The corners of view i as `camera` sees them, with independent Gaussian noise;
// the target's points printed `printed[j]` off the nominal grid, when given.
CornerView corners(const Scene& s, std::size_t i, const CameraModel& camera, Rng& rng, double sigma_px,
                   const std::vector<Vector3d>& printed = {}) {
  std::normal_distribution<double> noise(0.0, sigma_px);
  CornerView v;
  v.T_base_effector = s.effector[i];
  v.points.object = grid();
  for (std::size_t j = 0; j < v.points.object.size(); ++j) {
    const Vector3d o = v.points.object[j] + (printed.empty() ? Vector3d::Zero() : printed[j]);
    v.points.image.push_back(project(camera, s.view[i] * o) + Vector2d(noise(rng), noise(rng)));
  }
  v.name = "view " + std::to_string(i);
  return v;
}

Vector6d small_error(Rng& rng, double translation, double rotation) {
  std::normal_distribution<double> n(0.0, 1.0);
  Vector6d xi;
  for (int k = 0; k < 6; ++k) xi[k] = n(rng) * (k < 3 ? translation : rotation);
  return xi;
}

double nees(const Vector6d& e, const Matrix6d& covariance) { return e.dot(covariance.ldlt().solve(e)); }

// At the truth the residuals vanish (the cost's projection is OpenCV's, distortion
// included), and the Jacobian by (xi_X, xi_Y) is the numeric one of the package's
// left perturbation, at X rotated by 0, 1e-6 and nearly pi, both setups, with a
// correlated corner covariance (blocks of 8, as the edge-fit model's).
TEST(CornerResiduals, VanishAtTheTruthAndTheirJacobianIsTheNumericOne) {
  const CameraModel camera = simulated_camera();
  for (const handeye::Setup setup : {handeye::Setup::EyeInHand, handeye::Setup::EyeToHand}) {
    for (const double angle : {0.0, 1e-6, M_PI - 1e-4}) {
      Rng rng(11);
      Scene s = scene(rng, setup, 4);
      s.X.linear() = so3::exp(angle * Vector3d(1.0, -2.0, 0.5).normalized());
      for (std::size_t i = 0; i < s.view.size(); ++i) s.effector[i] = s.rig.effector_for_view(s.X, s.Y, s.view[i]);
      std::vector<CornerView> views;
      for (std::size_t i = 0; i < s.view.size(); ++i) {
        CornerView v = corners(s, i, camera, rng, 0.0);
        const int m = static_cast<int>(2 * v.points.image.size());
        v.points.corner_covariance = Eigen::MatrixXd::Zero(m, m);
        v.points.blocks = 8;
        for (int b = 0; b < m; b += 8) {
          const Eigen::MatrixXd A = Eigen::MatrixXd::Random(8, 8);
          v.points.corner_covariance.block(b, b, 8, 8) = A * A.transpose() + 0.5 * Eigen::MatrixXd::Identity(8, 8);
        }
        views.push_back(v);
      }
      const CornerResiduals at_truth = corner_residuals(s.rig, camera, views, s.X, s.Y);
      EXPECT_LT(at_truth.whitened.cwiseAbs().maxCoeff(), 1e-8) << to_string(setup) << " angle " << angle;

      // Away from the truth, the whitened residuals are L^-1 (u_hat - u).
      const Vector6d offset = small_error(rng, 2e-3, 0.01);
      const Isometry3d X1 = test::apply(s.X, offset);
      const CornerResiduals r = corner_residuals(s.rig, camera, views, X1, s.Y);
      double expected = 0.0;
      for (std::size_t i = 0; i < views.size(); ++i) {
        const Isometry3d P = X1.inverse() * s.rig.robot_link(views[i].T_base_effector) * s.Y;
        Eigen::VectorXd d(2 * views[i].points.image.size());
        for (std::size_t j = 0; j < views[i].points.image.size(); ++j) {
          d.segment<2>(2 * j) = project(camera, P * views[i].points.object[j]) - views[i].points.image[j];
        }
        expected += d.dot(views[i].points.corner_covariance.ldlt().solve(d));
      }
      EXPECT_NEAR(r.whitened.squaredNorm(), expected, 1e-9 * expected);

      const double h = 1e-6;
      Eigen::MatrixXd numeric(r.whitened.size(), 12);
      for (int k = 0; k < 12; ++k) {
        Vector6d d = Vector6d::Zero();
        d[k % 6] = h;
        const auto at = [&](const Vector6d& step) {
          return k < 6 ? corner_residuals(s.rig, camera, views, test::apply(X1, step), s.Y).whitened
                       : corner_residuals(s.rig, camera, views, X1, test::apply(s.Y, step)).whitened;
        };
        numeric.col(k) = (at(d) - at(-d)) / (2.0 * h);
      }
      const double scale = numeric.cwiseAbs().maxCoeff();
      EXPECT_LT((r.jacobian - numeric).cwiseAbs().maxCoeff(), 1e-6 * scale) << to_string(setup) << " angle " << angle;
    }
  }
}

// raw_pixels takes a rectified image's corners to where the distorted camera has
// them, and carries their covariance by the distortion's Jacobian.
TEST(CornerResiduals, RawPixelsUndoTheRectification) {
  const CameraModel camera = simulated_camera();
  CameraModel rectified = camera;
  rectified.distortion.clear();
  Rng rng(3);
  const Scene s = scene(rng, Setup::EyeInHand, 3);
  const CornerView ideal = corners(s, 0, rectified, rng, 0.0);
  const PointCorrespondences raw = raw_pixels(ideal.points, camera);
  ASSERT_EQ(raw.corner_covariance.rows(), 80);
  for (std::size_t j = 0; j < raw.image.size(); ++j) {
    EXPECT_LT((raw.image[j] - project(camera, s.view[0] * ideal.points.object[j])).norm(), 1e-6);
    // The covariance of a rectified corner moved by h is the raw one moved by J h.
    const Vector2d step(0.3, -0.2);
    PointCorrespondences moved = ideal.points;
    moved.image[j] += 1e-4 * step;
    const Vector2d raw_step = (raw_pixels(moved, camera).image[j] - raw.image[j]) / 1e-4;
    const Eigen::Matrix2d C = raw.corner_covariance.block<2, 2>(2 * j, 2 * j);
    // C = J J^T for identity input: the raw step's squared length under C^-1 is |step|^2.
    EXPECT_NEAR(raw_step.dot(C.ldlt().solve(raw_step)), step.squaredNorm(), 1e-4);
  }
}

struct Honesty {
  double nees_X = 0.0, nees_Y = 0.0, sigma = 0.0;
  Vector6d bias = Vector6d::Zero();  // mean of the error over its sigma, per axis of X
  double focal_within_2_sigma = 0.0;  // share of sessions (intrinsics free)
  Eigen::Vector2d robot_sigma = Eigen::Vector2d::Zero();  // root of the mean variance estimate (m, rad)
  double rounds = 0.0, iterations = 0.0;                   // mean noise rounds and Ceres iterations
  Eigen::Vector2d rms_X = Eigen::Vector2d::Zero();         // RMS error of X: translation (m), rotation (rad)
  double per_image = 0.0;                                  // share of sessions that weighed each image by its own sigma
  double target_sigma = 0.0;                               // root of the mean target point variance estimate (m)
};

// M sessions of n views: noisy corners (`pixel_sigma`, 0.3 px), the robot's measured poses
// perturbed by `robot_noise`, the camera given with its focal length scaled by
// `focal_error`; the calibration started 1 mm / 0.1 deg off the truth. `noisy`
// images of each session, drawn at random, have 5x the pixel noise. The target's
// points are printed off the grid by `target_sigma` (m, per axis), anew each session.
Honesty honesty(Setup setup, int M, int n, const CornerOptions& options, const std::optional<Matrix6d>& robot_noise,
                double focal_error, int noisy = 0, double target_sigma = 0.0, double pixel_sigma = 0.3) {
  const CameraModel truth_camera = simulated_camera();
  CameraModel given = truth_camera;
  given.K(0, 0) *= 1.0 + focal_error;
  given.K(1, 1) *= 1.0 + focal_error;
  Honesty h;
  for (int session = 0; session < M; ++session) {
    Rng rng(1000 + session);
    const Scene s = scene(rng, setup, n);
    std::vector<CornerView> views;
    std::vector<std::size_t> order(s.view.size());
    std::iota(order.begin(), order.end(), 0);
    if (noisy > 0) std::shuffle(order.begin(), order.end(), rng);
    std::vector<Vector3d> printed;
    if (target_sigma > 0.0) {
      std::normal_distribution<double> error(0.0, target_sigma);
      for (std::size_t j = 0; j < grid().size(); ++j) printed.emplace_back(error(rng), error(rng), error(rng));
    }
    for (std::size_t i = 0; i < s.view.size(); ++i) {
      const bool is_noisy = std::find(order.begin(), order.begin() + noisy, i) != order.begin() + noisy;
      CornerView v = corners(s, i, truth_camera, rng, (is_noisy ? 5.0 : 1.0) * pixel_sigma, printed);
      if (robot_noise) v.T_base_effector = perturb(rng, v.T_base_effector, PoseNoise::from_pose_covariance(*robot_noise));
      views.push_back(v);
    }
    const CornerCalibration c = calibrate_corners(s.rig, given, views, test::apply(s.X, small_error(rng, 1e-3, 1.7e-3)),
                                                  test::apply(s.Y, small_error(rng, 1e-3, 1.7e-3)), options);
    const Vector6d eX = test::pose_perturbation(c.X, s.X), eY = test::pose_perturbation(c.Y, s.Y);
    const Matrix6d CX = c.covariance.topLeftCorner<6, 6>(), CY = c.covariance.bottomRightCorner<6, 6>();
    h.nees_X += nees(eX, CX) / M;
    h.nees_Y += nees(eY, CY) / M;
    h.sigma += c.pixel_sigma / M;
    h.robot_sigma += c.robot_sigma.cwiseAbs2() / M;  // the mean variance, rooted below
    h.rounds += static_cast<double>(c.noise_rounds) / M;
    h.iterations += static_cast<double>(c.iterations) / M;
    h.bias += eX.cwiseQuotient(CX.diagonal().cwiseSqrt()) / M;
    h.rms_X += Eigen::Vector2d(eX.head<3>().squaredNorm(), eX.tail<3>().squaredNorm()) / M;
    h.per_image += (c.per_image_sigma ? 1.0 : 0.0) / M;
    h.target_sigma += c.target_point_sigma * c.target_point_sigma / M;  // the mean variance, rooted below
    if (c.intrinsics) {
      const double f_sigma = std::sqrt(c.intrinsics_covariance(0, 0));
      h.focal_within_2_sigma += (std::abs((*c.intrinsics)[0] - truth_camera.K(0, 0)) < 2.0 * f_sigma ? 1.0 : 0.0) / M;
    }
  }
  h.robot_sigma = h.robot_sigma.cwiseSqrt();
  h.target_sigma = std::sqrt(h.target_sigma);
  h.rms_X = h.rms_X.cwiseSqrt();
  return h;
}

// The mean of M chi2(6) / 6 x 6: its 99.9% band (Wilson-Hilferty), for the NEES means.
std::pair<double, double> chi2_band(int M, int dim) {
  const double k = static_cast<double>(M * dim), z = 3.29;
  const auto q = [&](double zz) { return k * std::pow(1.0 - 2.0 / (9.0 * k) + zz * std::sqrt(2.0 / (9.0 * k)), 3) / M; };
  return {q(-z), q(z)};
}

TEST(CornerCalibration, CovarianceIsHonestWithTheRobotExact) {
  const int M = 200;
  const auto band = chi2_band(M, 6);
  for (const handeye::Setup setup : {handeye::Setup::EyeInHand, handeye::Setup::EyeToHand}) {
    const Honesty h = honesty(setup, M, 15, CornerOptions{}, std::nullopt, 0.0);
    std::printf("%s, robot exact: NEES X %.2f, Y %.2f (band %.2f..%.2f), sigma %.4f px (true 0.3)\n", to_string(setup),
                h.nees_X, h.nees_Y, band.first, band.second, h.sigma);
    EXPECT_GT(h.nees_X, band.first);
    EXPECT_LT(h.nees_X, band.second);
    EXPECT_GT(h.nees_Y, band.first);
    EXPECT_LT(h.nees_Y, band.second);
    EXPECT_NEAR(h.sigma, 0.3, 0.003);
  }
}

// Robot errors (0.3 mm, 0.03 deg per axis) that the corners cannot average out:
// with the robot poses as measurements the covariance stays honest; with them
// taken as exact it is overconfident.
// 100 sessions each (200 until the suite had to fit 20 minutes): chi2_band follows M.
TEST(CornerCalibration, RobotPosesAsMeasurementsKeepTheCovarianceHonest) {
  const int M = 100;
  const auto band = chi2_band(M, 6);
  Matrix6d robot = Matrix6d::Zero();
  robot.diagonal() << Vector3d::Constant(std::pow(0.3e-3, 2)), Vector3d::Constant(std::pow(0.03 * M_PI / 180.0, 2));
  CornerOptions free;
  free.robot_covariance = robot;
  CornerOptions estimated;
  estimated.estimate_robot_noise = true;
  for (const handeye::Setup setup : {handeye::Setup::EyeInHand, handeye::Setup::EyeToHand}) {
    const Honesty h = honesty(setup, M, 15, free, robot, 0.0);
    const Honesty e = honesty(setup, M, 15, estimated, robot, 0.0);
    const Honesty exact = honesty(setup, 50, 15, CornerOptions{}, robot, 0.0);  // far above the band: 50 show it
    std::printf("%s, robot noisy: NEES X %.2f, Y %.2f with the robot poses free (band %.2f..%.2f), sigma %.4f px; "
                "X %.2f, Y %.2f with the robot's noise estimated (%.3f mm, %.4f deg; true 0.3, 0.03); X %.2f taken as exact\n",
                to_string(setup), h.nees_X, h.nees_Y, band.first, band.second, h.sigma, e.nees_X, e.nees_Y,
                e.robot_sigma[0] * 1e3, e.robot_sigma[1] * 180.0 / M_PI, exact.nees_X);
    std::printf("  noise rounds %.1f / %.1f, Ceres iterations %.1f / %.1f (given / estimated)\n", h.rounds, e.rounds,
                h.iterations, e.iterations);
    EXPECT_GT(h.nees_X, band.first);
    EXPECT_LT(h.nees_X, band.second);
    EXPECT_GT(h.nees_Y, band.first);
    EXPECT_LT(h.nees_Y, band.second);
    EXPECT_NEAR(h.sigma, 0.3, 0.006);
    EXPECT_GT(exact.nees_X, band.second);
    // Estimated from 15 images (45 rows per component): the estimate's own error
    // widens the NEES a little (about 1 + 2 / 45 for one scale).
    EXPECT_GT(e.nees_X, band.first);
    EXPECT_LT(e.nees_X, band.second * 1.05);
    EXPECT_GT(e.nees_Y, band.first);
    EXPECT_LT(e.nees_Y, band.second * 1.05);
    // 15 images tell the robot's translation from its rotation poorly (some sessions
    // put one of them at 0): the mean variance is within 15% of the truth.
    EXPECT_NEAR(e.robot_sigma[0], 0.3e-3, 0.045e-3);
    EXPECT_NEAR(e.robot_sigma[1], 0.03 * M_PI / 180.0, 0.0045 * M_PI / 180.0);
  }
}

// An exact robot whose noise is estimated: the residuals support none, and what
// the fit then keeps of it must not show in X's covariance, however precise the
// corners. At 0.01 px one image's pose is known to about a micrometre: a robot
// held at 1 um / 1 urad (the bound until 2026-11) made the covariance cautious
// (NEES of X 4.77 on the rendered AprilTag board, BENCHMARKS.md).
TEST(CornerCalibration, AnExactRobotWithItsNoiseEstimatedKeepsTheCovarianceHonest) {
  const int M = 100;  // as above
  const auto band = chi2_band(M, 6);
  CornerOptions estimated;
  estimated.estimate_robot_noise = true;
  for (const handeye::Setup setup : {handeye::Setup::EyeInHand, handeye::Setup::EyeToHand}) {
    const Honesty e = honesty(setup, M, 15, estimated, std::nullopt, 0.0, 0, 0.0, 0.01);
    std::printf("%s, robot exact, its noise estimated, corners at 0.01 px: NEES X %.2f, Y %.2f (band %.2f..%.2f), "
                "robot %.5f mm / %.6f deg, X RMS %.5f mm / %.6f deg\n",
                to_string(setup), e.nees_X, e.nees_Y, band.first, band.second, e.robot_sigma[0] * 1e3,
                e.robot_sigma[1] * 180.0 / M_PI, e.rms_X[0] * 1e3, e.rms_X[1] * 180.0 / M_PI);
    EXPECT_GT(e.nees_X, band.first);
    EXPECT_LT(e.nees_X, band.second * 1.05);
    EXPECT_GT(e.nees_Y, band.first);
    EXPECT_LT(e.nees_Y, band.second * 1.05);
  }
}

// The focal length given 1% off: refined with the intrinsics, it lands within 2
// sigma of the truth as often as a Gaussian says, and X is unbiased; kept fixed, X
// is biased.
TEST(CornerCalibration, RefinedIntrinsicsRemoveTheFocalLengthBias) {
  const int M = 100;
  CornerOptions intrinsics;
  intrinsics.refine_intrinsics = true;
  const Honesty h = honesty(Setup::EyeInHand, M, 20, intrinsics, std::nullopt, 0.01);
  const Honesty fixed = honesty(Setup::EyeInHand, M, 20, CornerOptions{}, std::nullopt, 0.01);
  std::printf("focal 1%% off: refined within 2 sigma in %.0f%% of sessions; X bias over sigma %.2f (refined) and %.2f "
              "(fixed), NEES X %.2f / %.2f\n",
              100.0 * h.focal_within_2_sigma, h.bias.cwiseAbs().maxCoeff(), fixed.bias.cwiseAbs().maxCoeff(), h.nees_X,
              fixed.nees_X);
  EXPECT_GT(h.focal_within_2_sigma, 0.88);          // 95% expected; 100 sessions
  EXPECT_LT(h.bias.cwiseAbs().maxCoeff(), 0.33);    // the mean of 100 unit normals: 3.3 of its sigma
  EXPECT_GT(fixed.bias.cwiseAbs().maxCoeff(), 1.0);
}

// Images that are noisier than the others (3 of 15 at 5x the pixel noise, at
// random): Bartlett's test sees it and each image gets its own sigma, so the noisy
// ones count less. One pooled sigma weighs them all alike: less accurate. On
// images of one noise the test rarely fires (its level is 99.9%).
TEST(CornerCalibration, ImagesOfDifferentNoiseAreEachWeighedByTheirOwn) {
  const int M = 200;
  const auto band = chi2_band(M, 6);
  CornerOptions pooled;
  pooled.robust = JointOptions::Robust::Off;
  const Honesty robust = honesty(Setup::EyeInHand, M, 15, CornerOptions{}, std::nullopt, 0.0, 3);
  const Honesty plain = honesty(Setup::EyeInHand, M, 15, pooled, std::nullopt, 0.0, 3);
  const Honesty alike = honesty(Setup::EyeInHand, M, 15, CornerOptions{}, std::nullopt, 0.0, 0);
  std::printf("3 of 15 images at 5x noise: per-image sigma in %.0f%% of sessions, NEES X %.2f, Y %.2f, RMS X %.4f mm / "
              "%.5f deg; one pooled sigma: NEES X %.2f, Y %.2f, RMS X %.4f mm / %.5f deg (band %.2f..%.2f); images alike: "
              "per-image in %.1f%%\n",
              100.0 * robust.per_image, robust.nees_X, robust.nees_Y, robust.rms_X[0] * 1e3, robust.rms_X[1] * 180.0 / M_PI,
              plain.nees_X, plain.nees_Y, plain.rms_X[0] * 1e3, plain.rms_X[1] * 180.0 / M_PI, band.first, band.second,
              100.0 * alike.per_image);
  EXPECT_GT(robust.per_image, 0.99);
  EXPECT_LT(alike.per_image, 0.02);
  EXPECT_GT(robust.nees_X, band.first);
  EXPECT_LT(robust.nees_X, band.second * 1.05);
  EXPECT_GT(robust.nees_Y, band.first);
  EXPECT_LT(robust.nees_Y, band.second * 1.05);
  EXPECT_LT(robust.rms_X[0], 0.85 * plain.rms_X[0]);
  EXPECT_LT(robust.rms_X[1], 0.85 * plain.rms_X[1]);
}

// A target printed off its nominal geometry (each point 0.2 mm per axis, the same
// in every image): the per-image noise averages out over the images, the target's
// error does not. Taken as exact, the covariance is overconfident; with the
// target's error estimated from the corners and carried into the covariance, it is
// honest, and the pixel sigma gives the target's share back (0.3 px). Also with the
// robot poses free (their priors are rows of the fit the estimate accounts for). On
// an exact target the estimate is small and the covariance stays honest
// (CovarianceIsHonestWithTheRobotExact runs with it on).
TEST(CornerCalibration, TargetGeometryErrorIsEstimatedAndCarried) {
  const int M = 200;
  const auto band = chi2_band(M, 6);
  CornerOptions exact;
  exact.target_point_sigma = 0.0;
  CornerOptions given;
  given.target_point_sigma = 0.2e-3;
  Matrix6d robot = Matrix6d::Zero();
  robot.diagonal() << Vector3d::Constant(std::pow(0.3e-3, 2)), Vector3d::Constant(std::pow(0.03 * M_PI / 180.0, 2));
  CornerOptions robot_free;
  robot_free.robot_covariance = robot;
  const Honesty estimated = honesty(Setup::EyeInHand, M, 15, CornerOptions{}, std::nullopt, 0.0, 0, 0.2e-3);
  const Honesty known = honesty(Setup::EyeInHand, M, 15, given, std::nullopt, 0.0, 0, 0.2e-3);
  const Honesty free = honesty(Setup::EyeToHand, M, 15, robot_free, robot, 0.0, 0, 0.2e-3);
  const Honesty ignored = honesty(Setup::EyeInHand, M, 15, exact, std::nullopt, 0.0, 0, 0.2e-3);
  const Honesty none = honesty(Setup::EyeInHand, 50, 15, CornerOptions{}, std::nullopt, 0.0, 0, 0.0);
  std::printf("target points off by 0.2 mm per axis: estimated %.4f mm (pixel sigma %.4f px), NEES X %.2f, Y %.2f; "
              "given: NEES X %.2f, Y %.2f; robot poses free (eye-to-hand): estimated %.4f mm, NEES X %.2f, Y %.2f "
              "(band %.2f..%.2f); taken as exact: NEES X %.2f, Y %.2f; exact target: estimated %.4f mm\n",
              estimated.target_sigma * 1e3, estimated.sigma, estimated.nees_X, estimated.nees_Y, known.nees_X,
              known.nees_Y, free.target_sigma * 1e3, free.nees_X, free.nees_Y, band.first, band.second, ignored.nees_X,
              ignored.nees_Y, none.target_sigma * 1e3);
  EXPECT_NEAR(estimated.target_sigma, 0.2e-3, 0.02e-3);
  EXPECT_NEAR(free.target_sigma, 0.2e-3, 0.02e-3);
  EXPECT_NEAR(estimated.sigma, 0.3, 0.006);
  EXPECT_LT(none.target_sigma, 0.03e-3);
  for (const Honesty& h : {estimated, known, free}) {
    EXPECT_GT(h.nees_X, band.first);
    EXPECT_LT(h.nees_X, band.second);
    EXPECT_GT(h.nees_Y, band.first);
    EXPECT_LT(h.nees_Y, band.second);
  }
  EXPECT_GT(ignored.nees_X, band.second);
  EXPECT_GT(ignored.nees_Y, 1.5 * band.second);
}

TEST(CornerCalibration, RefusesWhatItCannotUse) {
  const CameraModel camera = simulated_camera();
  Rng rng(5);
  const Scene s = scene(rng, Setup::EyeInHand, 4);
  std::vector<CornerView> views;
  for (std::size_t i = 0; i < 4; ++i) views.push_back(corners(s, i, camera, rng, 0.3));
  const auto code_of = [&](const std::function<void()>& f) {
    try {
      f();
    } catch (const HandEyeError& e) {
      return std::string(to_string(e.code()));
    }
    return std::string("no error");
  };
  EXPECT_EQ(code_of([&] { calibrate_corners(s.rig, camera, {views[0], views[1]}, s.X, s.Y); }), "NoData");
  std::vector<CornerView> bad = views;
  bad[2].points.corner_covariance = -Eigen::MatrixXd::Identity(80, 80);
  EXPECT_EQ(code_of([&] { calibrate_corners(s.rig, camera, bad, s.X, s.Y); }), "InvalidNoise");
  bad = views;
  bad[1].points.image.pop_back();
  EXPECT_EQ(code_of([&] { calibrate_corners(s.rig, camera, bad, s.X, s.Y); }), "WrongLength");
  CornerOptions robot;
  robot.robot_covariance = Matrix6d::Zero();
  EXPECT_EQ(code_of([&] { calibrate_corners(s.rig, camera, views, s.X, s.Y, robot); }), "InvalidNoise");
  CameraModel tilted = camera;
  tilted.distortion.resize(14, 0.0);
  tilted.distortion[12] = 0.01;
  EXPECT_EQ(code_of([&] { calibrate_corners(s.rig, tilted, views, s.X, s.Y); }), "MalformedFile");
  // Ceres out of iterations far from the solution: named, not a half-way X.
  CornerOptions one_step;
  one_step.max_iterations = 1;
  Isometry3d far = s.X;
  far.translation() += Vector3d(0.05, -0.04, 0.03);
  far.linear() = so3::exp(Vector3d(0.2, -0.1, 0.15)) * far.linear();
  EXPECT_EQ(code_of([&] { calibrate_corners(s.rig, camera, views, far, s.Y, one_step); }), "NotConverged");
  // The pose estimators cannot do corners, nor can a session without the hook.
  SampleSet samples;
  samples.rig = s.rig;
  EXPECT_EQ(code_of([&] { estimate(samples, Method::Corners); }), "MalformedFile");
  SessionSettings settings;
  settings.rig = s.rig;
  settings.method = method_from_string("corners");
  EXPECT_EQ(code_of([&] { CalibrationSession session(settings); }), "MalformedFile");
}

// The session runs method corners as the node and `handeye images` do: the joint
// estimate from the samples' poses, then the refiner hook on their corners. A
// sample without corners, or with another camera's, is named.
TEST(CornerCalibration, SessionRefinesTheSamplesCorners) {
  const CameraModel camera = simulated_camera();
  Rng rng(8);
  const Scene s = scene(rng, Setup::EyeInHand, 12);
  PoseNoise detection;
  detection.translation = std::pow(0.3e-3, 2) * Eigen::Matrix3d::Identity();
  detection.rotation = std::pow(0.03 * M_PI / 180.0, 2) * Eigen::Matrix3d::Identity();
  SessionSettings settings;
  settings.rig = s.rig;
  settings.method = Method::Corners;
  settings.refine_corners = corner_refiner();
  settings.noise = MeasurementNoise{PoseNoise{}, detection};  // the robot exact
  std::vector<PoseSample> samples;
  for (std::size_t i = 0; i < s.view.size(); ++i) {
    PoseSample sample;
    sample.T_base_effector = s.effector[i];
    sample.T_camera_pattern = test::apply(s.view[i], small_error(rng, 0.3e-3, 0.03 * M_PI / 180.0));
    const CornerView v = corners(s, i, camera, rng, 0.3);
    sample.corners = std::make_shared<const TargetCorners>(TargetCorners{camera, v.points, v.name});
    samples.push_back(sample);
  }
  CalibrationSession session(settings);
  session.replace(samples, "simulated");
  const Calibration c = session.calibrate(session.snapshot());
  EXPECT_EQ(c.method, Method::Corners);
  ASSERT_TRUE(c.corner_fit);
  ASSERT_EQ(c.corner_fit->images.size(), 12u);
  EXPECT_EQ(c.corner_fit->images[3].name, "view 3");
  EXPECT_EQ(c.corner_fit->corners, 12 * 40);
  EXPECT_NEAR(c.corner_fit->pixel_sigma, 0.3, 0.03);
  // No robot noise stated (a zero block is none): from 12 images the hook estimates it.
  // The robot is exact here, so it comes out at its floor: not a noise the corners
  // supported, and not one target_progress holds to its rule.
  EXPECT_NE(c.corner_fit->robot.find("noise estimated from the corners"), std::string::npos) << c.corner_fit->robot;
  EXPECT_FALSE(c.corner_fit->robot_noise_estimated);
  const double e = nees(test::pose_perturbation(c.T_parent_camera, s.X), c.pose_covariance);
  std::printf("session method corners: X within NEES %.2f, sigma %.3f px\n", e, c.corner_fit->pixel_sigma);
  EXPECT_LT(e, 22.5);  // chi^2(6) at 0.999

  const auto message_of = [&](std::vector<PoseSample> changed) {
    CalibrationSession other(settings);
    other.replace(std::move(changed), "changed");
    try {
      other.calibrate(other.snapshot());
    } catch (const HandEyeError& error) {
      return std::string(to_string(error.code())) + ": " + error.what();
    }
    return std::string("no error");
  };
  std::vector<PoseSample> without = samples;
  without[5].corners.reset();
  EXPECT_NE(message_of(without).find("MalformedFile: sample 5 has no corners"), std::string::npos) << message_of(without);
  std::vector<PoseSample> other_camera = samples;
  TargetCorners moved = *other_camera[7].corners;
  moved.camera.K(0, 0) *= 1.01;
  other_camera[7].corners = std::make_shared<const TargetCorners>(moved);
  EXPECT_NE(message_of(other_camera).find("sample 7's corners come from another camera"), std::string::npos)
      << message_of(other_camera);
}

}  // namespace
}  // namespace handeye
