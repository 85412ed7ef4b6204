// AprilTag corners in an image, with Debian's libapriltag (no ROS).
#pragma once

#include <Eigen/Core>
#include <array>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace handeye {

struct TagDetectorOptions {
  std::string family = "tag36h11";
  /// The quad search runs on the image shrunk by this factor (the edges are then
  /// refined on the full image, refine_edges). > 1 is faster but finds small tags
  /// less well. 0: by the image, width / 640 rounded down (at least 1), so the search
  /// sees about VGA: 1 at 640 x 480, 2 at 1280 x 720 (12 ms instead of 32 ms for
  /// the 2 x 2 board, BENCHMARKS.md; the covariance stays honest, test_vision).
  double quad_decimate = 0.0;
  double quad_sigma = 0.0;     // Gaussian blur before the quad search, px
  int threads = 2;
  bool refine_edges = true;    // fit the edges on the full-resolution image
  int max_hamming = 0;         // bit errors accepted in a code; 0 avoids false ids
  double min_decision_margin = 20.0;  // weaker codes are dropped
};

struct TagCorners {
  int id = 0;
  int hamming = 0;
  double decision_margin = 0.0;
  /// Image corners (px, x right, y down, pixel centres at integers as in OpenCV
  /// and CameraInfo) of the tag's black square, in the order
  /// of TagPlacement::corners(): bottom-left, bottom-right, top-right, top-left
  /// of the printed tag.
  std::array<Eigen::Vector2d, 4> corners;
};

/// The names accepted in TagDetectorOptions::family (and TagLayout::family).
std::vector<std::string> tag_families();

class TagDetector {
 public:
  /// Throws HandEyeError (InvalidLayout) for an unknown family, listing the known ones.
  explicit TagDetector(const TagDetectorOptions& options = {});
  ~TagDetector();
  TagDetector(const TagDetector&) = delete;
  TagDetector& operator=(const TagDetector&) = delete;

  /// Tags in an 8-bit single-channel image, sorted by id.
  std::vector<TagCorners> detect(const cv::Mat& gray) const;

  const TagDetectorOptions& options() const { return options_; }

 private:
  struct Impl;
  TagDetectorOptions options_;
  std::unique_ptr<Impl> impl_;
};

/// A marker's printable bitmap (black border plus the white quiet zone around it:
/// `total_width` cells, the black square `width_at_border`).
struct TagBitmap {
  cv::Mat pixels;  // CV_8UC1, one pixel per cell
  int width_at_border = 0;
};
/// A libapriltag family's tag (tag_bitmap in target.h takes OpenCV's dictionaries too).
TagBitmap apriltag_bitmap(const std::string& family, int id);

}  // namespace handeye
