// The corner fit's section of a calibration (corners/corner_calibration.h produces it;
// declared here, below the corners library, because Calibration holds it). Fields
// described once (core/fields.h).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "handeye_covariance/core/fields.h"

namespace handeye {

/// A corner fit's refined intrinsics, each (value, 1 sigma): fx, fy, cx, cy (px), k1, k2.
struct RefinedIntrinsics {
  Eigen::Vector2d fx = Eigen::Vector2d::Zero(), fy = Eigen::Vector2d::Zero(), cx = Eigen::Vector2d::Zero(),
                  cy = Eigen::Vector2d::Zero(), k1 = Eigen::Vector2d::Zero(), k2 = Eigen::Vector2d::Zero();
  template <class Self, class Visit>
  static void fields(Self& s, Visit&& visit) {
    visit("fx", s.fx);
    visit("fy", s.fy);
    visit("cx", s.cx);
    visit("cy", s.cy);
    visit("k1", s.k1);
    visit("k2", s.k2);
  }
};

/// Corners: the fit of every image's corners (corners/corner_calibration.h).
struct CornerFitRecord {
  double pixel_sigma = 0.0;  // px, estimated from the residuals (or given)
  bool pixel_sigma_estimated = true;
  double rms_px = 0.0;       // over every corner coordinate
  int corners = 0;
  struct Image {
    std::string name;
    int corners = 0;
    double rms_px = 0.0;
    double sigma_px = 0.0;  // the pixel sigma it was weighed with
    template <class Self, class Visit>
    static void fields(Self& s, Visit&& visit) {
      visit("image", s.name);
      visit("corners", s.corners);
      visit("rms_px", s.rms_px);
      visit("sigma_px", s.sigma_px);
    }
  };
  std::vector<Image> images;
  /// The test of one pixel sigma for every image and what followed, in words ("one pixel
  /// sigma for every image (Bartlett's test of one sigma: chi2 12.3 on 11 dof, bound 31.3)").
  std::string pixel_noise;
  bool per_image_sigma = false;
  std::string robot;  // how the robot poses entered, in words: exact, under a prior, or their noise estimated
  bool robot_noise_estimated = false;  // the robot's noise estimated from the corners, off its floor
  /// The printed target's points' 1 sigma (m, per axis; estimated or given, 0:
  /// exact) and how it entered the covariance.
  double target_point_sigma = 0.0;
  std::string target_points;
  /// Refined intrinsics; none when kept.
  using Intrinsics = RefinedIntrinsics;
  std::optional<Intrinsics> intrinsics;
  /// The figures `robot`, `target_points` and `pixel_noise` are worded from
  /// (io::word_corner_fit; files carry the words). The robot poses: held exact, free
  /// under a prior (its largest axis' 1 sigma, m and rad), or with their noise
  /// estimated (its 1 sigma per axis, m and rad).
  enum class RobotPoses { Exact, Prior, Estimated };
  RobotPoses robot_poses = RobotPoses::Exact;  // (the file key robot_poses holds `robot`, the words)
  Eigen::Vector2d robot_prior_sigma = Eigen::Vector2d::Zero();
  Eigen::Vector2d robot_sigma = Eigen::Vector2d::Zero();
  bool target_point_sigma_estimated = false;
  Eigen::Vector2d target_inflation = Eigen::Vector2d::Ones();  // X's 1 sigma factors: translation, rotation
  /// Bartlett's test of one pixel sigma for every image, when it ran.
  bool homogeneity_tested = false, homogeneity_passed = false;
  double homogeneity_chi2 = 0.0, homogeneity_bound = 0.0;
  int homogeneity_dof = 0;
  template <class Self, class Visit>
  static void fields(Self& s, Visit&& visit) {
    visit("pixel_sigma", s.pixel_sigma);
    visit("pixel_sigma_estimated", s.pixel_sigma_estimated);
    visit("rms_px", s.rms_px);
    visit("corners", s.corners);
    visit("robot_poses", s.robot);
    visit("target_point_sigma", s.target_point_sigma);  // m, per axis
    visit("target_points", s.target_points, kWhenSet);
    visit("pixel_noise", s.pixel_noise, kWhenSet);
    visit("per_image_sigma", s.per_image_sigma);
    visit("intrinsics", s.intrinsics, kBlock);
    visit("images", s.images);
    visit("robot_noise_estimated", s.robot_noise_estimated, kInMemory);
    visit("robot_poses_kind", s.robot_poses, kInMemory);
    visit("robot_prior_sigma", s.robot_prior_sigma, kInMemory);
    visit("robot_sigma", s.robot_sigma, kInMemory);
    visit("target_point_sigma_estimated", s.target_point_sigma_estimated, kInMemory);
    visit("target_inflation", s.target_inflation, kInMemory);
    visit("homogeneity_tested", s.homogeneity_tested, kInMemory);
    visit("homogeneity_passed", s.homogeneity_passed, kInMemory);
    visit("homogeneity_chi2", s.homogeneity_chi2, kInMemory);
    visit("homogeneity_bound", s.homogeneity_bound, kInMemory);
    visit("homogeneity_dof", s.homogeneity_dof, kInMemory);
  }
};

}  // namespace handeye
