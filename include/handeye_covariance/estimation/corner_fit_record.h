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
  /// The test of one pixel sigma for every image and what followed ("one pixel
  /// sigma: Bartlett chi2 12.3 on 11 dof, 99.9% bound 31.3", or each image its own).
  std::string pixel_noise;
  bool per_image_sigma = false;
  std::string robot;  // how the robot poses entered: "exact" or their prior
  bool robot_noise_estimated = false;  // the robot's noise estimated from the corners, off its floor
  /// The printed target's points' 1 sigma (m, per axis; estimated or given, 0:
  /// exact) and how it entered the covariance.
  double target_point_sigma = 0.0;
  std::string target_points;
  /// Refined intrinsics; none when kept.
  using Intrinsics = RefinedIntrinsics;
  std::optional<Intrinsics> intrinsics;
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
  }
};

}  // namespace handeye
