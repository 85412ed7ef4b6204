// Images of a tag pattern seen by a camera at a known pose, for the tests and
// the simulated rig: libapriltag's own tag bitmaps warped by OpenCV onto a
// supersampled ideal (pinhole) image, blurred, area-averaged to the sensor
// resolution, distorted with the camera's distortion model, and given Gaussian
// pixel noise. No ROS.
#pragma once

#include <opencv2/core.hpp>
#include <vector>

#include "handeye_covariance/simulation/simulation.h"
#include "handeye_covariance/core/tag_layout.h"
#include "handeye_covariance/vision/pattern_pose.h"

namespace handeye {

struct RenderOptions {
  double blur_sigma_px = 0.7;   // optics (Gaussian PSF), sensor pixels
  double noise_sigma = 2.0;     // gray levels, per pixel
  double background = 90.0;     // gray level around the board
  double black = 25.0, white = 225.0;
  int supersample = 3;          // ideal image at supersample x resolution, for anti-aliasing
  int texels_per_cell = 8;      // tag bitmap upscaling before the warp
  double board_margin_cells = 1.0;  // white board beyond the tags' quiet zones (planar layouts)
};

class TagRenderer {
 public:
  /// Throws HandEyeError for an invalid camera or layout (unknown family or id).
  TagRenderer(const TagLayout& layout, const CameraModel& camera, const RenderOptions& options = {});

  /// An 8-bit mono image of the pattern at T_camera_pattern. Tags (and board
  /// parts) behind the camera are not drawn.
  cv::Mat render(const Eigen::Isometry3d& T_camera_pattern, Rng& rng) const;

  const CameraModel& camera() const { return camera_; }

 private:
  struct Tag {
    cv::Mat texture;                      // CV_32F, texels
    Eigen::Isometry3d T_pattern_tag;
    double texture_width = 0.0;           // m, the full bitmap including the quiet zone
  };
  TagLayout layout_;
  CameraModel camera_;
  RenderOptions options_;
  std::vector<Tag> tags_;
  std::vector<Eigen::Vector3d> board_corners_;  // pattern frame; empty for non-planar layouts
  cv::Mat map_x_, map_y_;                       // distorted pixel -> ideal pixel
};

/// A camera like a typical industrial 640 x 480 camera with mild barrel
/// distortion, for the simulated rig and the tests.
CameraModel simulated_camera();

}  // namespace handeye
