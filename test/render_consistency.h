// The honesty of a detector's pose covariance on rendered images: many random
// views of a target, each detected and compared with the truth under its own
// covariance, through the steps the detector node and `handeye images` take
// (rectify, detect, PnP with the pooled pixel sigma). test_vision, test_targets.
#pragma once

#include <gtest/gtest.h>

#include <cstdio>

#include "handeye_covariance/simulation/pattern_renderer.h"
#include "handeye_covariance/vision/target.h"
#include "test_helpers.h"

namespace handeye {

struct Consistency {
  double nees_rotation = 0.0, nees_translation = 0.0, nees_pose = 0.0;
  double max_correlation = 0.0;  // largest |corr| between a rotation and a translation axis
  double rms_translation = 0.0, rms_rotation = 0.0;  // m, rad
  double pixel_sigma = 0.0, points = 0.0;  // the last frame's sigma; the mean number of points used
  int frames = 0, missed = 0;
  std::string first_refusal;
};

struct Pipeline {
  CameraModel camera = simulated_camera();  // 640 x 480, f = 600 px
  bool rectify = true;
  CornerNoiseModel corner_noise = CornerNoiseModel::EdgeFit;
  ViewpointOptions views;
  RenderOptions render;
};

/// Renders `frames` random views of the target's face (after 20 that warm the
/// pooled pixel noise), detects, and accumulates the NEES of each pose.
inline Consistency consistency(const Target& target, int frames, std::uint64_t seed, const Pipeline& pipeline = {}) {
  const CameraModel& camera = pipeline.camera;
  const PatternRenderer renderer(target, camera, pipeline.render);
  const ImageRectifier rectifier(camera);
  TargetDetectorOptions options;
  options.pose.corner_noise = pipeline.corner_noise;
  const TargetDetector detector(target, options);
  const Eigen::Isometry3d T_face_pattern = target_face(target).inverse();
  PixelNoise noise;
  Rng rng(seed);
  Consistency c;
  const auto estimate = [&](const Eigen::Isometry3d& T) -> PatternPoseResult {
    const cv::Mat image = renderer.render(T, rng);
    const CameraModel& used = pipeline.rectify ? rectifier.rectified() : camera;
    const TargetObservation seen = pipeline.rectify ? detector.detect(image, rectifier) : detector.detect(image);
    if (!seen.points) return {std::nullopt, seen.refusal};
    return estimate_pose(used, *seen.points, noise, options.pose);
  };
  for (int i = 0; i < 20; ++i) estimate(random_view(rng, pipeline.views) * T_face_pattern);
  for (int i = 0; i < frames; ++i) {
    const Eigen::Isometry3d T = random_view(rng, pipeline.views) * T_face_pattern;
    const PatternPoseResult r = estimate(T);
    if (!r.pose) {
      if (c.first_refusal.empty()) c.first_refusal = r.refusal;
      ++c.missed;
      continue;
    }
    const Vector6d e = test::pose_perturbation(r.pose->T_camera_pattern, T);
    const Matrix6d& S = r.pose->covariance;
    c.nees_translation += e.head<3>().dot(S.topLeftCorner<3, 3>().inverse() * e.head<3>());
    c.nees_rotation += e.tail<3>().dot(S.bottomRightCorner<3, 3>().inverse() * e.tail<3>());
    c.nees_pose += e.dot(S.inverse() * e);
    c.rms_translation += e.head<3>().squaredNorm();
    c.rms_rotation += e.tail<3>().squaredNorm();
    for (int a = 0; a < 3; ++a)
      for (int b = 3; b < 6; ++b)
        c.max_correlation = std::max(c.max_correlation, std::abs(S(a, b)) / std::sqrt(S(a, a) * S(b, b)));
    c.pixel_sigma = r.pose->pixel_sigma;
    c.points += r.pose->points;
    ++c.frames;
  }
  c.nees_rotation /= c.frames;
  c.nees_translation /= c.frames;
  c.nees_pose /= c.frames;
  c.points /= c.frames;
  c.rms_translation = std::sqrt(c.rms_translation / c.frames);
  c.rms_rotation = std::sqrt(c.rms_rotation / c.frames);
  return c;
}

// The bar: over many rendered frames the detector's covariance matches
// its actual error, the NEES mean for rotation and translation within the band of
// an honest 3-dof covariance over that many frames at 99.95% ([2.53, 3.52] at 300
// frames, the bar as first set; [2.43, 3.64] at 200).
inline void expect_printed(const char* name, const Consistency& c) {
  std::printf("%s: %d frames (%d missed%s%s), %.1f points, pixel sigma %.3f px, RMS error %.3f mm %.4f deg, "
              "NEES R %.2f t %.2f pose %.2f, max |corr(R,t)| %.2f\n",
              name, c.frames, c.missed, c.first_refusal.empty() ? "" : ", first: ", c.first_refusal.c_str(), c.points,
              c.pixel_sigma, c.rms_translation * 1e3, c.rms_rotation * 180.0 / M_PI, c.nees_rotation, c.nees_translation,
              c.nees_pose, c.max_correlation);
}

inline void expect_honest(const char* name, const Consistency& c, int max_missed = 0) {
  expect_printed(name, c);
  EXPECT_LE(c.missed, max_missed) << c.first_refusal;
  const auto [low, high] = test::chi2_mean_band(c.frames, 3, 0.9995);
  std::printf("  honest 3-dof NEES over %d frames: %.2f-%.2f (99.95%%)\n", c.frames, low, high);
  EXPECT_GE(c.nees_rotation, low);
  EXPECT_LE(c.nees_rotation, high);
  EXPECT_GE(c.nees_translation, low);
  EXPECT_LE(c.nees_translation, high);
}

}  // namespace handeye
