// A target detected image after image, every pose's covariance under the pixel
// sigma pooled over all the images: one frame of one marker leaves 8 - 6 = 2
// degrees of freedom, a session hundreds. A folder of images (image_folder.h) and
// the images of a bag (ros/bag.h) both go through it; the node pools over a
// sliding window instead (PixelNoise), as its images come one by one.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "handeye_covariance/core/target.h"
#include "handeye_covariance/vision/pattern_pose.h"
#include "handeye_covariance/vision/target.h"

namespace handeye {
namespace images {

class PooledDetector {
 public:
  /// Checks the target (throws as check_target).
  explicit PooledDetector(const Target& target, const TargetDetectorOptions& options = {});
  ~PooledDetector();

  struct Frame {
    std::optional<PatternPose> pose;  // under the sigma pooled so far; pooled() rescales it
    /// The corners the pose came from, in the raw image's pixels (raw_pixels):
    /// what --method corners refines from.
    std::optional<PointCorrespondences> corners;
    std::string why;                  // why not (not found, refused by the PnP)
  };
  /// Detects the target in an 8-bit gray image as `camera` took it (rectified
  /// first when the camera has distortion). The camera may change between images.
  const Frame& add(const cv::Mat& gray, const CameraModel& camera);

  std::size_t size() const { return frames_.size(); }
  const Frame& frame(std::size_t i) const { return frames_.at(i); }
  double pixel_sigma() const { return noise_.sigma(); }
  int degrees_of_freedom() const { return noise_.degrees_of_freedom(); }  // pooled so far
  /// The i-th frame's pose with its covariance under the pooled sigma:
  /// sigma^2 nu / (nu - 2) (J^T C^-1 J)^-1 (PixelNoise::covariance_variance),
  /// so rescaling from the variance it had is exact.
  std::optional<PatternPose> pooled(std::size_t i) const;

 private:
  TargetDetector detector_;
  PatternPoseOptions pose_options_;
  PixelNoise noise_;
  std::vector<Frame> frames_;
  std::optional<CameraModel> camera_;  // the camera rectifier_ was made for
  std::unique_ptr<ImageRectifier> rectifier_;
};

}  // namespace images
}  // namespace handeye
