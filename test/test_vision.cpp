// The vision layer: tag layouts, libapriltag corners on rendered images, the
// reprojection Jacobian (numerically), and the honesty of the detector's pose
// covariance against its actual error over many rendered frames.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <atomic>
#include <cstdio>
#include <thread>

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/estimation/estimator.h"
#include "handeye_covariance/estimation/outliers.h"
#include "handeye_covariance/estimation/solve.h"
#include "handeye_covariance/io/yaml_io.h"
#include "handeye_covariance/vision/chessboard.h"
#include "handeye_covariance/vision/pattern_pose.h"
#include "handeye_covariance/vision/tag_detector.h"
#include "handeye_covariance/vision/target.h"
#include "handeye_covariance/simulation/pattern_renderer.h"
#include "render_consistency.h"
#include "test_helpers.h"

namespace handeye {
namespace {

using Eigen::Isometry3d;
using Eigen::Vector3d;

std::string board_file() { return std::string(HANDEYE_SOURCE_DIR) + "/config/tag_board_2x2.yaml"; }

/// The camera 0.5 m in front of the pattern, looking at it, slightly rolled and tilted.
Isometry3d frontal_view(double roll = 0.3) {
  ViewpointOptions views;
  views.min_distance = views.max_distance = 0.5;
  Rng rng(3);
  Isometry3d view = random_view(rng, views);
  return se3::make_pose(so3::exp(Vector3d(0, 0, roll)) * view.linear(), view.translation());
}

TEST(TagLayout, ReadsTheBoardAndRefusesBadEntries) {
  const TagLayout layout = io::read_tag_layout(board_file());
  EXPECT_EQ(layout.family, "tag36h11");
  ASSERT_EQ(layout.tags.size(), 4u);
  EXPECT_NEAR(layout.find(3)->T_pattern_tag.translation().x(), 0.04, 1e-12);
  EXPECT_EQ(layout.find(7), nullptr);
  const auto code_of = [](const std::string& text) {
    try {
      io::parse_tag_layout(text, "layout.yaml");
    } catch (const HandEyeError& e) {
      return std::string(to_string(e.code())) + ": " + e.what();
    }
    return std::string("accepted");
  };
  EXPECT_NE(code_of("tags: []").find("InvalidLayout"), std::string::npos);
  EXPECT_NE(code_of("tags: [{id: 0}]").find("MissingKey"), std::string::npos);
  EXPECT_NE(code_of("tags: [{id: 0, size: -0.1}]").find("InvalidLayout"), std::string::npos);
  EXPECT_NE(code_of("tags: [{id: 0, size: 0.1}, {id: 0, size: 0.1, x: 1}]").find("appears twice"), std::string::npos);
  EXPECT_NE(code_of("tags: [{id: 0, size: 0.1, qw: 2}]").find("QuaternionNotUnit"), std::string::npos);
  EXPECT_NE(code_of("tags: [{id: 1.5, size: 0.1}]").find("integer"), std::string::npos);
  // Range-checked before it is converted (UBSan found `id: 1e90` in the fuzzer's inputs).
  EXPECT_NE(code_of("tags: [{id: 1e90, size: 0.1}]").find("whole number from 0 to 1000000"), std::string::npos);
  EXPECT_NE(code_of("tags: [{id: -1, size: 0.1}]").find("whole number"), std::string::npos);
  EXPECT_NE(code_of("tags: [{id: 0, size: .nan}]").find("layout.yaml: tags[0]"), std::string::npos);
  EXPECT_EQ(code_of("tags: [{id: 0, size: 0.1}]"), "accepted");
}

TEST(TagDetector, UnknownFamilyAndIdAreNamed) {
  TagDetectorOptions options;
  options.family = "tag99h1";
  try {
    TagDetector detector(options);
    FAIL() << "accepted an unknown family";
  } catch (const HandEyeError& e) {
    EXPECT_NE(std::string(e.what()).find("tag36h11"), std::string::npos) << e.what();
  }
  EXPECT_THROW(tag_bitmap("tag36h11", 587), HandEyeError);  // tag36h11 has ids 0-586
}

// The corner order of TagPlacement::corners() is libapriltag's: on a rendered
// tag, every detected corner lands on its own projected layout corner.
TEST(TagDetector, CornersMatchTheLayoutOrderOnRenderedTags) {
  const CameraModel camera = simulated_camera();
  for (double roll : {0.0, 0.3, 1.6, -2.5}) {
    const TagLayout layout = io::read_tag_layout(board_file());
    const PatternRenderer renderer(layout, camera);
    const ImageRectifier rectifier(camera);
    Rng rng(11);
    const Isometry3d T = frontal_view(roll);
    const std::vector<TagCorners> tags = TagDetector().detect(rectifier.rectify(renderer.render(T, rng)));
    ASSERT_EQ(tags.size(), 4u) << "roll " << roll;
    for (const TagCorners& tag : tags) {
      const auto corners = layout.find(tag.id)->corners();
      for (int c = 0; c < 4; ++c) {
        const double error = (project(rectifier.rectified(), T * corners[c]) - tag.corners[c]).norm();
        EXPECT_LT(error, 0.25) << "tag " << tag.id << " corner " << c << " roll " << roll;
      }
    }
  }
}

// libapriltag's worker threads start in a detector's first detection, racing
// the tasks it adds (tag_detector.cpp: start_worker_threads). Without that, this
// test died of a segfault in 3 of 8 runs (a call to a wild address from inside
// libapriltag); with it, none in 6. Two threads make 1 000 detectors each, so
// that workers start late; every detector finds the 4 tags.
TEST(TagDetector, WorkerThreadsStartSafely) {
  const CameraModel camera = simulated_camera();
  const TagLayout layout = io::read_tag_layout(board_file());
  Rng rng(12);
  const cv::Mat image = ImageRectifier(camera).rectify(PatternRenderer(layout, camera).render(frontal_view(), rng));
  cv::Mat small;  // a quarter of the pixels: the first detection still adds over 8 tasks per step
  cv::resize(image, small, cv::Size(image.cols / 2, image.rows / 2), 0, 0, cv::INTER_AREA);
  std::atomic<int> detectors{0}, tags{0};
  const auto make_detectors = [&] {
    for (int i = 0; i < 1000; ++i) {
      TagDetectorOptions options;
      options.threads = 2;
      tags += static_cast<int>(TagDetector(options).detect(small).size());
      ++detectors;
    }
  };
  std::thread first(make_detectors), second(make_detectors);
  first.join();
  second.join();
  EXPECT_EQ(detectors.load(), 2000);
  EXPECT_EQ(tags.load(), 4 * 2000);
}

// libapriltag fits each side once, from nearest-pixel samples about its
// thresholded quad; on these views its corners were off by (-0.0025, -0.0034) px
// on average, the same for every corner whatever the roll (a bias of X after 30
// images of 16 corners), with an RMS of 0.053 px. The detector refits until the
// lines stop moving, the last passes within +-1 px: within +-2 px the corners
// moved outwards by 0.002 px, which a mean over each tag's four corners cannot
// see, so the outward component is checked too. A reversed-border family
// (bright square, dark around) is refitted from dark to bright. Noise-free
// renders without distortion: what is left is the method's own error.
TEST(TagDetector, RefittedCornersAreUnbiasedOnRenderedTags) {
  CameraModel camera = simulated_camera();
  camera.distortion.clear();
  RenderOptions render;
  render.noise_sigma = 0.0;
  for (const std::string& family : {std::string("tag36h11"), std::string("tagStandard41h12")}) {
    const TagLayout layout = family == "tag36h11" ? io::read_tag_layout(board_file()) : single_tag_layout(3, 0.1, family);
    const PatternRenderer renderer(layout, camera, render);
    TagDetectorOptions options;
    options.family = family;
    const TagDetector detector(options);
    ViewpointOptions views;
    views.min_distance = 0.4;
    views.max_distance = 1.0;
    Rng rng(29);
    Eigen::Vector2d mean = Eigen::Vector2d::Zero();
    double squares = 0.0, outward = 0.0;
    int n = 0;
    for (int i = 0; i < 60; ++i) {
      const Isometry3d T = random_view(rng, views);
      for (const TagCorners& tag : detector.detect(renderer.render(T, rng))) {
        const auto corners = layout.find(tag.id)->corners();
        Eigen::Vector2d centre = Eigen::Vector2d::Zero();
        for (const Eigen::Vector2d& c : tag.corners) centre += 0.25 * c;
        for (int c = 0; c < 4; ++c) {
          const Eigen::Vector2d error = tag.corners[c] - project(camera, T * corners[c]);
          mean += error;
          squares += error.squaredNorm();
          outward += error.dot((tag.corners[c] - centre).normalized());
          ++n;
        }
      }
    }
    ASSERT_GE(n, 60 * 4 * static_cast<int>(layout.tags.size()) * 9 / 10) << family;
    mean /= n;
    outward /= n;
    const double rms = std::sqrt(squares / n);
    std::printf("%s, %d rendered corners: mean error (%.4f, %.4f) px, outwards %.4f px, RMS %.4f px\n", family.c_str(), n,
                mean.x(), mean.y(), outward, rms);
    EXPECT_LT(std::abs(mean.x()), 0.001) << family;
    EXPECT_LT(std::abs(mean.y()), 0.001) << family;
    EXPECT_LT(std::abs(outward), 0.001) << family;
    EXPECT_LT(rms, 0.02) << family;
  }
}

// A sensor averages light over each pixel; the rectified image is resampled at
// the distortion's ever-changing sub-pixel offsets. Through a bilinear
// rectification every corner moved towards the image centre; through the
// detector's (Lanczos, and saddle points refined in the raw image) it stays.
TEST(ImageRectifier, CornersKeepTheirPlaceThroughTheLensDistortion) {
  const CameraModel camera = simulated_camera();  // k1 = -0.12
  const ImageRectifier rectifier(camera);
  cv::Mat bilinear_x, bilinear_y;
  cv::initUndistortRectifyMap(cv::Mat(cv::Matx33d(camera.K.data()).t()), cv::Mat(camera.distortion), cv::noArray(),
                              cv::Mat(cv::Matx33d(camera.K.data()).t()), cv::Size(camera.width, camera.height), CV_32FC1,
                              bilinear_x, bilinear_y);
  RenderOptions render;
  render.noise_sigma = 0.0;
  ViewpointOptions views;
  views.min_distance = 0.4;
  views.max_distance = 1.0;
  const Eigen::Vector2d principal_point(camera.K(0, 2), camera.K(1, 2));
  for (const Target& target : {make_target(io::read_tag_layout(board_file())), make_target(ChessboardTarget{9, 6, 0.03})}) {
    const PatternRenderer renderer(target, camera, render);
    const TargetDetector detector(target);
    const Isometry3d T_face_pattern = target_face(target).inverse();
    Rng rng(31);
    double ours = 0.0, bilinear = 0.0;  // mean error away from the principal point, px
    int n_ours = 0, n_bilinear = 0;
    const auto radial = [&](const TargetObservation& seen, const Isometry3d& T, double& sum, int& n) {
      if (!seen.points) return;
      for (std::size_t i = 0; i < seen.points->image.size(); ++i) {
        const Eigen::Vector2d& u = seen.points->image[i];
        const Eigen::Vector2d error = u - project(rectifier.rectified(), T * seen.points->object[i]);
        if ((u - principal_point).norm() < 50.0) continue;  // no direction to speak of
        sum += error.dot((u - principal_point).normalized());
        ++n;
      }
    };
    for (int i = 0; i < 40; ++i) {
      const Isometry3d T = random_view(rng, views) * T_face_pattern;
      const cv::Mat raw = renderer.render(T, rng);
      radial(detector.detect(raw, rectifier), T, ours, n_ours);
      cv::Mat resampled;
      cv::remap(raw, resampled, bilinear_x, bilinear_y, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
      radial(detector.detect(resampled), T, bilinear, n_bilinear);
    }
    const std::string name = target.kind_name() == "chessboard" ? "chessboard" : "AprilTag board";
    ASSERT_GT(n_ours, 40 * 8) << name;
    ASSERT_GT(n_bilinear, 40 * 8) << name;
    ours /= n_ours;
    bilinear /= n_bilinear;
    std::printf("%s, 40 noise-free views: mean corner error away from the principal point %.4f px (bilinear "
                "rectification: %.4f px)\n", name.c_str(), ours, bilinear);
    EXPECT_LT(std::abs(ours), 0.003) << name;  // AprilTag board 0.0020, chessboard 0.0007
    EXPECT_LT(bilinear, -0.005) << name;  // what the test guards against is there to see
  }
}

TEST(PatternPose, ReprojectionJacobianMatchesNumericDifferences) {
  const CameraModel camera = simulated_camera();
  const TagLayout layout = io::read_tag_layout(board_file());
  std::vector<Vector3d> points;
  for (const TagPlacement& tag : layout.tags)
    for (const Vector3d& c : tag.corners()) points.push_back(c);
  for (double distance : {0.3, 0.8}) {
    Isometry3d T = frontal_view(0.7);
    T.translation() *= distance / T.translation().norm();
    const auto J = reprojection_jacobian(camera, T, points);
    for (int j = 0; j < 6; ++j) {
      Vector6d d = Vector6d::Zero();
      const double h = 1e-6;
      d(j) = h;
      for (std::size_t i = 0; i < points.size(); ++i) {
        const Eigen::Vector2d numeric =
            (project(camera, test::apply(T, d) * points[i]) - project(camera, test::apply(T, -d) * points[i])) / (2 * h);
        EXPECT_LT((J.block<2, 1>(2 * i, j) - numeric).norm(), 1e-4 * (1.0 + numeric.norm()))
            << "column " << j << " point " << i << " at " << distance << " m";
      }
    }
  }
}

// The intrinsics' uncertainty of a camera file (intrinsics_sigma) enters each
// view's pose covariance as the pose's own sensitivity to them carries it: the
// Jacobian of the projections against numeric differences, the pose's shift for a
// slightly wrong fx or cx against the re-estimated pose, and the added covariance
// A diag(sigma^2) A^T (a 1% focal length: depth 1% of the distance).
TEST(PatternPose, IntrinsicsUncertaintyEntersTheViewsCovariance) {
  CameraModel camera = simulated_camera();
  const TagLayout layout = io::read_tag_layout(board_file());
  std::vector<Vector3d> points;
  for (const TagPlacement& tag : layout.tags)
    for (const Vector3d& c : tag.corners()) points.push_back(c);
  Isometry3d T = frontal_view(0.7);
  T.translation() *= 0.8 / T.translation().norm();
  const auto JK = intrinsics_jacobian(camera, T, points);
  for (int k = 0; k < 4; ++k) {
    const double h = 1e-4;
    CameraModel plus = camera, minus = camera;
    const int row = k == 1 || k == 3 ? 1 : 0, col = k < 2 ? row : 2;  // fx (0,0), fy (1,1), cx (0,2), cy (1,2)
    plus.K(row, col) += h, minus.K(row, col) -= h;
    for (std::size_t i = 0; i < points.size(); ++i) {
      const Eigen::Vector2d numeric = (project(plus, T * points[i]) - project(minus, T * points[i])) / (2 * h);
      EXPECT_LT((JK.block<2, 1>(2 * i, k) - numeric).norm(), 1e-6 * (1.0 + numeric.norm())) << k << " " << i;
    }
  }
  // Exact corners of the view: the pose, then the pose with fx 0.5 px long, re-fitted.
  PointCorrespondences exact;
  exact.object = points;
  for (const Vector3d& p : points) exact.image.push_back(project(camera, T * p));
  exact.blocks = 2;
  PixelNoise noise(0.1);
  const PatternPoseResult as_given = estimate_pose(camera, exact, noise);
  ASSERT_TRUE(as_given.pose) << as_given.refusal;
  CameraModel longer = camera;
  longer.K(0, 0) += 0.5;
  PixelNoise noise2(0.1);
  const PatternPoseResult refit = estimate_pose(longer, exact, noise2);
  ASSERT_TRUE(refit.pose);
  const Vector6d shift = test::pose_perturbation(refit.pose->T_camera_pattern, as_given.pose->T_camera_pattern);
  const auto J = reprojection_jacobian(camera, as_given.pose->T_camera_pattern, points);
  const Vector6d predicted = -(J.transpose() * J).ldlt().solve(J.transpose() * JK.col(0) * 0.5);
  EXPECT_LT((shift - predicted).norm(), 0.02 * predicted.norm()) << shift.transpose() << " / " << predicted.transpose();
  // The covariance with sigma_fx = sigma_fy = 1% (6 px): depth about 1% of 0.8 m more.
  CameraModel uncertain = camera;
  uncertain.intrinsics_sigma << 6.0, 6.0, 0.0, 0.0;
  PixelNoise noise3(0.1);
  const PatternPoseResult with_sigma = estimate_pose(uncertain, exact, noise3);
  ASSERT_TRUE(with_sigma.pose);
  const Matrix6d added = with_sigma.pose->covariance - as_given.pose->covariance;
  const Eigen::Matrix<double, 6, 4> A = (J.transpose() * J).ldlt().solve(J.transpose() * JK);
  const Matrix6d expected = A * Eigen::Vector4d(36.0, 36.0, 0.0, 0.0).asDiagonal() * A.transpose();
  EXPECT_LT((added - expected).norm(), 1e-6 * expected.norm());
  const double depth_sigma = std::sqrt(added(2, 2));
  std::printf("[ figures  ] 1%% focal length at 0.8 m: the view's depth 1 sigma grows by %.2f mm (pixel part %.3f mm)\n",
              depth_sigma * 1e3, std::sqrt(as_given.pose->covariance(2, 2)) * 1e3);
  EXPECT_NEAR(depth_sigma, 0.01 * T.translation().z(), 0.3 * 0.01 * T.translation().z());
}

TEST(PixelNoise, PoolsOverTheWindowAndKeepsTheFloor) {
  PixelNoise noise(0.1, 3);
  EXPECT_EQ(noise.sigma(), 0.1);  // nothing seen yet: the floor
  noise.add(8.0, 2);              // 2 px^2 per dof
  EXPECT_NEAR(noise.sigma(), std::sqrt(4.0), 1e-12);
  noise.add(0.0, 2);
  EXPECT_NEAR(noise.sigma(), std::sqrt(2.0), 1e-12);
  noise.add(0.0, 2);
  noise.add(0.0, 2);  // the first frame leaves the window
  EXPECT_EQ(noise.sigma(), 0.1);
  noise.add(1.0, 0);  // no residual dof (e.g. an exactly determined fit): ignored
  EXPECT_EQ(noise.degrees_of_freedom(), 6);
  EXPECT_DOUBLE_EQ(noise.covariance_variance(), 0.01);  // the floor is not an estimate: no Student-t factor
}

// A sigma estimated from nu degrees of freedom: the covariance uses sigma^2 nu / (nu - 2),
// the variance of the Student-t, so that 6-dof errors over it average 6 (and not 6 nu / (nu - 2)).
TEST(PixelNoise, CovarianceVarianceCarriesTheUncertaintyOfAnEstimatedSigma) {
  PixelNoise noise(0.01, 200);
  noise.add(2.0, 2);  // one frame of one marker: 1 px^2 per dof, nu = 2, the factor stops at 3
  EXPECT_NEAR(noise.covariance_variance(), 3.0, 1e-12);
  for (int frame = 1; frame < 12; ++frame) noise.add(2.0, 2);  // 12 frames: nu = 24
  EXPECT_NEAR(noise.sigma(), 1.0, 1e-12);
  EXPECT_NEAR(noise.covariance_variance(), 24.0 / 22.0, 1e-12);
  // Monte-Carlo of what the factor is for: e ~ N(0, I6), s^2 ~ chi2(24)/24,
  // mean of e^T e / (s^2 nu / (nu - 2)) is 6 (and 6.55 without the factor).
  Rng rng(3);
  std::normal_distribution<double> gauss;
  double nees = 0.0, nees_without = 0.0;
  constexpr int kTrials = 200000;
  for (int trial = 0; trial < kTrials; ++trial) {
    PixelNoise pooled(1e-6, 200);
    for (int frame = 0; frame < 12; ++frame) pooled.add(std::pow(gauss(rng), 2) + std::pow(gauss(rng), 2), 2);
    double e2 = 0.0;
    for (int axis = 0; axis < 6; ++axis) e2 += std::pow(gauss(rng), 2);
    nees += e2 / pooled.covariance_variance() / kTrials;
    nees_without += e2 / std::pow(pooled.sigma(), 2) / kTrials;
  }
  EXPECT_NEAR(nees, 6.0, 0.05);
  EXPECT_NEAR(nees_without, 6.0 * 24.0 / 22.0, 0.06);
}

TEST(PatternPose, RefusesUnknownTagsAndBadFits) {
  const CameraModel camera = simulated_camera();
  const TagLayout layout = io::read_tag_layout(board_file());
  PixelNoise noise;
  TagCorners stranger;
  stranger.id = 42;
  PatternPoseResult r = estimate_pattern_pose(layout, camera, {stranger}, noise);
  EXPECT_FALSE(r.pose);
  EXPECT_NE(r.refusal.find("saw 0 of the pattern's tags"), std::string::npos) << r.refusal;

  // The right ids, but the printed board is 20% larger than the layout says
  // for one tag: the fit is refused, not believed.
  const PatternRenderer renderer(layout, camera);
  Rng rng(5);
  const Isometry3d T = frontal_view();
  std::vector<TagCorners> tags = TagDetector().detect(renderer.render(T, rng));
  ASSERT_EQ(tags.size(), 4u);
  TagLayout wrong = layout;
  wrong.tags[0].size *= 1.2;
  r = estimate_pattern_pose(wrong, camera, tags, noise);
  EXPECT_FALSE(r.pose);
  EXPECT_NE(r.refusal.find("reprojection RMS"), std::string::npos) << r.refusal;
  tags.push_back(tags[1]);
  r = estimate_pattern_pose(layout, camera, tags, noise);
  EXPECT_NE(r.refusal.find("seen twice"), std::string::npos) << r.refusal;
}

TEST(PatternPose, CovarianceIsHonestOnRenderedBoards) {
  expect_honest("board 2x2", consistency(make_target(io::read_tag_layout(board_file())), 200, 21));
}

// At 1280 x 720 the quad search runs on the image shrunk by 2 (quad_decimate 0:
// by the width, tag_detector.h), 2.7x faster; the corners still come from the
// edges fitted on the full image, and the covariance stays honest.
TEST(PatternPose, CovarianceIsHonestOnHighResolutionImages) {
  Pipeline hd;
  hd.camera.width = 1280;
  hd.camera.height = 720;
  hd.camera.K << 900.0, 0.0, 639.5, 0.0, 900.0, 359.5, 0.0, 0.0, 1.0;
  expect_honest("board 2x2 at 1280 x 720", consistency(make_target(io::read_tag_layout(board_file())), 200, 23, hd));
}

TEST(PatternPose, CovarianceIsHonestOnASingleTag) {
  expect_honest("single tag", consistency(make_target(single_tag_layout(0, 0.1)), 300, 22));
}

// The whole chain without ROS: sessions of 12 rendered views, the detector's
// covariances as the pattern noise of each sample, then the estimator. The X
// covariance must match X's error over the sessions (6-dof NEES mean near 6),
// although the estimator keeps only the rotation and translation blocks of
// each detection covariance (its R-t correlation is dropped, see docs/troubleshooting.md, "Limits that are not errors").
TEST(PatternPose, CalibrationFromRenderedImagesIsConsistent) {
  const TagLayout layout = io::read_tag_layout(board_file());
  const CameraModel camera = simulated_camera();
  const PatternRenderer renderer(layout, camera);
  const ImageRectifier rectifier(camera);
  const TagDetector detector;
  PixelNoise noise;
  const int sessions = 30;
  double nees = 0.0;
  int false_rejections = 0;
  for (int session = 0; session < sessions; ++session) {
    Rng rng(100 + session);
    SimulatedSession truth = simulate_session(rng, Setup::EyeInHand, typical_X(Setup::EyeInHand), 12, MeasurementNoise{});
    SampleSet set = truth.samples;
    MeasurementNoise mean;
    for (PoseSample& sample : set.samples) {
      const PatternPoseResult r = estimate_pattern_pose(
          layout, rectifier.rectified(), detector.detect(rectifier.rectify(renderer.render(sample.T_camera_pattern, rng))),
          noise);
      ASSERT_TRUE(r.pose) << r.refusal;
      sample.T_camera_pattern = r.pose->T_camera_pattern;
      MeasurementNoise n;
      n.camera.translation = r.pose->covariance.topLeftCorner<3, 3>();
      n.camera.rotation = r.pose->covariance.bottomRightCorner<3, 3>();
      mean.camera.translation += n.camera.translation / 12.0;
      mean.camera.rotation += n.camera.rotation / 12.0;
      sample.noise = n;
    }
    set.noise = mean;  // the robot is exact here
    const Calibration c = solve(set);
    const Vector6d e = test::pose_perturbation(c.T_parent_camera, truth.X);
    nees += e.dot(c.pose_covariance.ldlt().solve(e)) / sessions;
    // Outlier rejection keeps every real detection: the residual gate adapts
    // when the detector's decoupled covariance and X's own error widen them.
    false_rejections += static_cast<int>(solve_robust(set).rejected.size());
  }
  std::printf("outlier rejection dropped %d of %d real detections\n", false_rejections, 12 * sessions);
  EXPECT_LE(false_rejections, 12 * sessions / 100);  // at most 1%
  std::printf("calibration from rendered images: %d sessions of 12 views, 6-dof NEES mean %.2f\n", sessions, nees);
  // 30 x chi2(6) = chi2(180): its 0.05% and 99.95% quantiles (a 99.9% band) are 124 and 248.
  EXPECT_GT(nees, 124.0 / sessions);
  EXPECT_LT(nees, 248.0 / sessions);
}

// Why the detector rectifies first and models edge fits: without either, the
// covariance is far from its error (these are the measured failure modes that
// the choices in pattern_pose.h avoid).
TEST(PatternPose, WithoutRectificationOrEdgeModelTheCovarianceIsWrong) {
  const TagLayout layout = single_tag_layout(0, 0.1);
  Pipeline distorted;
  distorted.rectify = false;
  const Consistency biased = consistency(make_target(layout), 120, 23, distorted);
  Pipeline independent;
  independent.corner_noise = CornerNoiseModel::Independent;
  const Consistency conservative = consistency(make_target(layout), 120, 23, independent);
  std::printf("unrectified: NEES t %.2f; independent corners: NEES R %.2f t %.2f\n", biased.nees_translation,
              conservative.nees_rotation, conservative.nees_translation);
  EXPECT_GT(biased.nees_translation, 4.5);  // lines fitted to curved edges: a depth bias
  EXPECT_LT(conservative.nees_translation, 2.0);  // covariance too large
}

/// A chessboard of `t` seen at T_camera_pattern by `camera` (no distortion): the
/// board drawn at 4 px per mm, warped by the plane's homography, a little blur.
cv::Mat render_chessboard(const ChessboardTarget& t, const CameraModel& camera, const Eigen::Isometry3d& T_camera_pattern) {
  const double px_per_m = 4000.0;
  const int margin = 2;  // squares of white around the board
  const int w = static_cast<int>((t.columns + 1 + 2 * margin) * t.square * px_per_m);
  const int h = static_cast<int>((t.rows + 1 + 2 * margin) * t.square * px_per_m);
  cv::Mat board(h, w, CV_8UC1, cv::Scalar(255));
  for (int r = 0; r < t.rows + 1; ++r) {
    for (int c = 0; c < t.columns + 1; ++c) {
      if ((r + c) % 2 == 0) continue;  // the square outside the first inner corner is white (OpenCV's origin)
      const cv::Point a(static_cast<int>((margin + c) * t.square * px_per_m), static_cast<int>((margin + r) * t.square * px_per_m));
      const cv::Point b(static_cast<int>((margin + c + 1) * t.square * px_per_m) - 1,
                        static_cast<int>((margin + r + 1) * t.square * px_per_m) - 1);
      cv::rectangle(board, a, b, cv::Scalar(0), cv::FILLED);
    }
  }
  // Board pixel (u, v) -> pattern point: x = u / s - (margin + 1) square, likewise y
  // (the first inner corner is one square in from the board's corner).
  Eigen::Matrix3d board_to_pattern;
  board_to_pattern << 1.0 / px_per_m, 0, -(margin + 1) * t.square, 0, 1.0 / px_per_m, -(margin + 1) * t.square, 0, 0, 1;
  Eigen::Matrix3d plane;  // pattern (x, y, 1) -> camera: [r1 r2 t]
  plane << T_camera_pattern.linear().col(0), T_camera_pattern.linear().col(1), T_camera_pattern.translation();
  const Eigen::Matrix3d H = camera.K * plane * board_to_pattern;
  cv::Mat Hcv(3, 3, CV_64F);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) Hcv.at<double>(r, c) = H(r, c);
  }
  cv::Mat image;
  cv::warpPerspective(board, image, Hcv, cv::Size(camera.width, camera.height), cv::INTER_AREA, cv::BORDER_CONSTANT,
                      cv::Scalar(255));
  cv::GaussianBlur(image, image, cv::Size(3, 3), 0.6);
  return image;
}

TEST(Chessboard, FindsTheBoardInItsFrameAndRefusesBadTargets) {
  CameraModel camera;
  camera.K << 607.6, 0, 323.5, 0, 607.6, 243.3, 0, 0, 1;
  camera.width = 640, camera.height = 480;
  const ChessboardTarget board{9, 6, 0.0236};
  // The board turned in its plane by 0 and 90 degrees: the corner order follows the board, not the image.
  for (double roll : {0.0, M_PI / 2}) {
    // The board's centre 0.42 m in front of the camera, the board turned about it.
    const Eigen::Vector3d centre(0.5 * (board.columns - 1) * board.square, 0.5 * (board.rows - 1) * board.square, 0.0);
    const Eigen::Isometry3d about_centre = se3::make_pose(so3::exp(Eigen::Vector3d(0.0, 0.0, roll)), Eigen::Vector3d::Zero()) *
                                           se3::make_pose(Eigen::Matrix3d::Identity(), -centre);
    const Eigen::Isometry3d truth =
        se3::make_pose(so3::exp(Eigen::Vector3d(0.25, -0.2, 0.1)), Eigen::Vector3d(0.01, -0.01, 0.42)) * about_centre;
    const cv::Mat image = render_chessboard(board, camera, truth);
    const TargetObservation found = detect_chessboard(image, board);
    if (!found.points) cv::imwrite(::testing::TempDir() + "/chessboard_not_found.png", image);
    ASSERT_TRUE(found.points) << found.refusal << " (the image: " << ::testing::TempDir() << "/chessboard_not_found.png)";
    EXPECT_EQ(found.points->image.size(), 54u);
    PixelNoise noise;
    const PatternPoseResult pose = estimate_pose(camera, *found.points, noise);
    ASSERT_TRUE(pose.pose) << pose.refusal;
    const Vector6d error = test::pose_perturbation(pose.pose->T_camera_pattern, truth);
    std::printf("rendered chessboard (in-plane turn %.0f deg): %d corners, RMS %.3f px, error %.3f mm / %.4f deg\n",
                roll * 180 / M_PI, pose.pose->points, pose.pose->rms_px, error.head<3>().norm() * 1e3,
                error.tail<3>().norm() * 180 / M_PI);
    EXPECT_LT(error.head<3>().norm(), 1e-3);  // the frame convention (chessboard.h)
    EXPECT_LT(error.tail<3>().norm(), 0.3 * M_PI / 180.0);
    EXPECT_LT(pose.pose->rms_px, 0.5);
  }

  EXPECT_FALSE(detect_chessboard(cv::Mat(480, 640, CV_8UC1, cv::Scalar(255)), board).points);
  const auto refused = [](const ChessboardTarget& t, const std::string& what) {
    try {
      check_chessboard(t, "target.yaml");
      ADD_FAILURE() << "accepted " << t.columns << " x " << t.rows;
    } catch (const HandEyeError& e) {
      EXPECT_EQ(e.code(), ErrorCode::InvalidLayout);
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  refused({2, 5, 0.02}, "at least 3 x 3");
  refused({9, 6, -0.02}, "positive length");
  // A board that looks the same turned by 180 degrees is read (its pose is one of
  // two candidates, decided from the robot's motion: test_symmetric); a square one
  // (four candidates) is not.
  refused({7, 7, 0.02}, "turned by 90 degrees");
  EXPECT_NO_THROW(check_chessboard({8, 6, 0.02}, "target.yaml"));
  EXPECT_NO_THROW(check_chessboard({9, 7, 0.02}, "target.yaml"));
  EXPECT_NO_THROW(check_chessboard(board, "target.yaml"));
}

// A symmetric board (9 x 7 inner corners) turned in its plane by 0, 90, 180 and 270
// degrees: found every time, its pose one of the two candidates, the truth or the
// truth turned by half_turn about the board's centre (chessboard.h).
TEST(Chessboard, ASymmetricBoardsPoseIsOneOfItsTwoCandidates) {
  CameraModel camera;
  camera.K << 607.6, 0, 323.5, 0, 607.6, 243.3, 0, 0, 1;
  camera.width = 640, camera.height = 480;
  const ChessboardTarget board{9, 7, 0.0236};
  const Eigen::Isometry3d F = half_turn(make_target(board));
  ASSERT_FALSE(F.isApprox(Eigen::Isometry3d::Identity()));
  for (double roll : {0.0, M_PI / 2, M_PI, 3 * M_PI / 2}) {
    const Eigen::Vector3d centre(0.5 * (board.columns - 1) * board.square, 0.5 * (board.rows - 1) * board.square, 0.0);
    const Eigen::Isometry3d truth =
        se3::make_pose(so3::exp(Eigen::Vector3d(0.25, -0.2, 0.1)), Eigen::Vector3d(0.01, -0.01, 0.42)) *
        se3::make_pose(so3::exp(Eigen::Vector3d(0.0, 0.0, roll)), Eigen::Vector3d::Zero()) *
        se3::make_pose(Eigen::Matrix3d::Identity(), -centre);
    const TargetObservation found = detect_chessboard(render_chessboard(board, camera, truth), board);
    ASSERT_TRUE(found.points) << found.refusal;
    PixelNoise noise;
    const PatternPoseResult pose = estimate_pose(camera, *found.points, noise);
    ASSERT_TRUE(pose.pose) << pose.refusal;
    const Vector6d as_is = test::pose_perturbation(pose.pose->T_camera_pattern, truth),
                   turned = test::pose_perturbation(pose.pose->T_camera_pattern, truth * F);
    const Vector6d& error = as_is.norm() < turned.norm() ? as_is : turned;
    std::printf("symmetric chessboard 9 x 7 (in-plane turn %.0f deg): the %s candidate, error %.3f mm / %.4f deg\n",
                roll * 180 / M_PI, as_is.norm() < turned.norm() ? "true" : "turned", error.head<3>().norm() * 1e3,
                error.tail<3>().norm() * 180 / M_PI);
    EXPECT_LT(error.head<3>().norm(), 1e-3);
    EXPECT_LT(error.tail<3>().norm(), 0.3 * M_PI / 180.0);
  }
}

TEST(PatternPose, EdgeFitCovarianceOfASquare) {
  // A 100 px square: each corner coordinate is fixed by one edge line, whose two
  // ends move with variance 4/l and correlation -1/2.
  const std::array<Eigen::Vector2d, 4> square = {Eigen::Vector2d(0, 100), Eigen::Vector2d(100, 100),
                                                 Eigen::Vector2d(100, 0), Eigen::Vector2d(0, 0)};
  const Eigen::Matrix<double, 8, 8> C = edge_fit_corner_covariance(square);
  for (int i = 0; i < 8; ++i) EXPECT_NEAR(C(i, i), 0.04, 1e-12);
  // Corners 0 (0, 100) and 1 (100, 100) share the edge y = 100: their y errors.
  EXPECT_NEAR(C(1, 3) / 0.04, -0.5, 1e-12);
  // ... and corner 0's x shares nothing with corner 1's y.
  EXPECT_NEAR(C(0, 3), 0.0, 1e-12);
  EXPECT_GT(C.selfadjointView<Eigen::Lower>().ldlt().vectorD().minCoeff(), 0.0);
}

}  // namespace
}  // namespace handeye
