// Images of a calibration target seen by a camera at a known pose, for the tests
// and the simulated rig: the target's printed planes (libapriltag's tag bitmaps,
// OpenCV's ArUco markers and ChArUco board, a drawn chessboard) warped by OpenCV
// onto a supersampled ideal (pinhole) image, from the finest level of each plane's
// texture pyramid whose texels are no smaller than the ideal image's samples
// (mip-mapping: warpPerspective samples the texture at points, so finer texels
// alias), blurred, distorted with the camera's
// distortion model at the supersampled resolution, area-averaged to the sensor's
// pixels (as a sensor integrates light over each pixel), and given Gaussian
// pixel noise. No ROS.
#pragma once

#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "handeye_covariance/simulation/simulation.h"
#include "handeye_covariance/vision/target.h"

namespace handeye {

struct RenderOptions {
  double blur_sigma_px = 0.7;   // optics (Gaussian PSF), sensor pixels
  double noise_sigma = 2.0;     // gray levels, per pixel
  double background = 90.0;     // gray level around the board
  double black = 25.0, white = 225.0;
  int supersample = 3;          // ideal image at supersample x resolution, for anti-aliasing
  int texels_per_cell = 8;      // marker bitmap upscaling before the warp
  int texels_per_square = 96;   // chessboard and ChArUco textures
  // ChArUco boards are drawn at no less than this printer resolution: OpenCV's
  // CharucoBoard::draw puts each marker on whole pixels of its image (up to one
  // pixel off its place), as on a real print; at 96 px a square (0.36 mm a pixel)
  // that moved the saddle points near the markers by (-0.011, -0.007) px at 1 m,
  // more than a board printed at 300 dpi from an image at that resolution has.
  double print_dpi = 300.0;
  double board_margin_cells = 1.0;  // white board beyond the markers' quiet zones (planar marker layouts)
  double board_margin_squares = 0.75;  // white board beyond a chessboard's or ChArUco board's squares
};

/// A printed rectangle of a target: texel (u, v) (v down) at x right, y up in
/// the plane's frame, whose origin is the texture's centre.
struct PrintedPlane {
  cv::Mat texture;  // CV_8U, 0 black, 255 white
  Eigen::Isometry3d T_pattern_plane = Eigen::Isometry3d::Identity();
  double width = 0.0, height = 0.0;  // m
};

/// A target as the renderer draws it: its planes, and the corners of a white
/// board behind them (pattern frame; empty for none).
struct TargetPlanes {
  std::vector<PrintedPlane> planes;
  std::vector<Eigen::Vector3d> board_corners;
};

/// A kind's drawing: one file per kind in src/simulation/targets/, listed once
/// in src/simulation/pattern_renderer.cpp under the core kind's name.
struct RenderKind {
  std::string name;  // TargetKind::name
  TargetPlanes (*draw)(const Target& target, const RenderOptions& options) = nullptr;
};

const std::vector<RenderKind>& render_kinds();
/// Throws HandEyeError(InvalidLayout) when the kind has no drawing.
const RenderKind& render_kind(const std::string& name);

/// Markers (AprilTag or ArUco) at the layout's placements, on a white board
/// when they lie in the pattern's z = 0 plane.
TargetPlanes marker_planes(const TagLayout& layout, const RenderOptions& options);

class PatternRenderer {
 public:
  /// Throws HandEyeError for an invalid camera or target (unknown family or id).
  PatternRenderer(const Target& target, const CameraModel& camera, const RenderOptions& options = {});
  /// Markers (AprilTag or ArUco) at the layout's placements.
  PatternRenderer(const TagLayout& layout, const CameraModel& camera, const RenderOptions& options = {});

  /// An 8-bit mono image of the target at T_camera_pattern. Planes behind the
  /// camera are not drawn.
  cv::Mat render(const Eigen::Isometry3d& T_camera_pattern, Rng& rng) const;

  const CameraModel& camera() const { return camera_; }

 private:
  void build_distortion_map();

  CameraModel camera_;
  RenderOptions options_;
  std::vector<PrintedPlane> planes_;  // texture CV_32F, gray levels
  /// Per plane, its texture halved by area averaging, level by level (the first level is
  /// planes_[i].texture's half), down to a texel per side.
  std::vector<std::vector<cv::Mat>> pyramids_;
  std::vector<Eigen::Vector3d> board_corners_;  // pattern frame; empty without a white board behind
  cv::Mat map_x_, map_y_;  // supersampled distorted pixel -> supersampled ideal canvas pixel (margin included)
  struct MapTile {
    cv::Rect distorted;  // a tile of the distorted image ...
    cv::Rect reads;      // ... and the canvas pixels its bilinear remap reads
  };
  std::vector<MapTile> map_tiles_;
  int ideal_margin_ = 0;                        // px of ideal image beyond the camera's frame, every side
  cv::Size canvas_size_;                        // the supersampled ideal image: (camera + 2 margins) x supersample
};

/// A camera like a typical industrial 640 x 480 camera with mild barrel
/// distortion, for the simulated rig and the tests.
CameraModel simulated_camera();

}  // namespace handeye
