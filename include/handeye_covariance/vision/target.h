// The one detector that finds a calibration target of any kind (core/target.h)
// in an image (no ROS).
// Every kind ends in the same correspondences (target points, image points, the
// detector's corner-noise model) and so in the same PnP (estimate_pose).
#pragma once

#include <memory>
#include <optional>
#include <string>

#include <opencv2/core.hpp>

#include "handeye_covariance/core/tag_layout.h"
#include "handeye_covariance/core/target.h"
#include "handeye_covariance/vision/aruco.h"
#include "handeye_covariance/vision/chessboard.h"
#include "handeye_covariance/vision/pattern_pose.h"
#include "handeye_covariance/vision/tag_detector.h"

namespace handeye {

/// Throws HandEyeError(InvalidLayout) naming what is wrong and how to fix it.
void check_target(const Target& target, const std::string& where);

struct TargetDetectorOptions {
  TagDetectorOptions apriltag;        // family is taken from the target
  PatternPoseOptions pose;            // min_tags and the corner model for marker targets
  int min_charuco_corners = 6;
};

class TargetDetector {
 public:
  /// Checks the target (throws as check_target).
  explicit TargetDetector(const Target& target, const TargetDetectorOptions& options = {});
  ~TargetDetector();
  TargetDetector(const TargetDetector&) = delete;
  TargetDetector& operator=(const TargetDetector&) = delete;

  /// The target's points in an 8-bit single-channel image, or why not.
  TargetObservation detect(const cv::Mat& gray) const;
  /// The same in a raw camera image: found in its rectification (straight
  /// edges), in rectified pixels, with a chessboard's or ChArUco board's corners
  /// refined in the raw image itself (refine_saddle_points_in_raw_image).
  TargetObservation detect(const cv::Mat& raw_gray, const ImageRectifier& rectifier) const;

  const Target& target() const { return target_; }

 private:
  Target target_;
  TargetDetectorOptions options_;
  std::unique_ptr<TagDetector> apriltag_;
  std::unique_ptr<ArucoDetector> aruco_;
};

}  // namespace handeye
