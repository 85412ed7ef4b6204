// The one detector that finds a calibration target of any kind (core/target.h)
// in an image (no ROS).
// Each kind's detector is its own (VisionKind, src/vision/targets/); every kind
// ends in the same correspondences (target points, image points, the
// detector's corner-noise model) and so in the same PnP (estimate_pose).
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "handeye_covariance/core/tag_layout.h"
#include "handeye_covariance/core/target.h"
#include "handeye_covariance/vision/aruco.h"
#include "handeye_covariance/vision/chessboard.h"
#include "handeye_covariance/vision/pattern_pose.h"
#include "handeye_covariance/vision/tag_detector.h"

namespace handeye {

/// Throws HandEyeError(InvalidLayout) naming what is wrong and how to fix it
/// (the kind's check, vision_kind).
void check_target(const Target& target, const std::string& where);

struct TargetDetectorOptions {
  TagDetectorOptions apriltag;        // family is taken from the target
  PatternPoseOptions pose;            // min_tags and the corner model for marker targets
  int min_charuco_corners = 6;
};

/// A kind's detector of one target.
class KindDetector {
 public:
  virtual ~KindDetector() = default;
  /// The target's points in an 8-bit single-channel image, or why not.
  virtual TargetObservation detect(const cv::Mat& gray) const = 0;
};

/// A kind's part of the vision layer: one file per kind in src/vision/targets/,
/// listed once in src/vision/target.cpp under the core kind's name.
struct VisionKind {
  std::string name;  // TargetKind::name
  /// Throws HandEyeError(InvalidLayout) for a target its detector would refuse.
  void (*check)(const Target& target, const std::string& where) = nullptr;
  /// For a checked target.
  std::unique_ptr<KindDetector> (*detector)(const Target& target, const TargetDetectorOptions& options) = nullptr;
};

const std::vector<VisionKind>& vision_kinds();
/// Throws HandEyeError(InvalidLayout) when the kind has no detector.
const VisionKind& vision_kind(const std::string& name);

/// A marker's printable bitmap: a libapriltag family's tag (apriltag_bitmap) or an
/// OpenCV dictionary's ArUco marker (aruco_bitmap), as `family` names it.
TagBitmap tag_bitmap(const std::string& family, int id);

/// For the marker kinds: check_layout, and every id in its family or dictionary.
void check_markers(const TagLayout& layout, const std::string& where);
/// For the marker kinds: the layout's correspondences from the markers found
/// (tag_correspondences), a refusal naming what was seen; `code` is what the
/// family is ("family", "dictionary").
TargetObservation marker_observation(const TagLayout& layout, const std::vector<TagCorners>& tags,
                                     const PatternPoseOptions& options, const std::string& code);

/// For the marker kinds: a layout's detector around a marker finder (TagDetector,
/// ArucoDetector: detect(gray) gives the markers' corners), built in place from `finder`'s
/// arguments; `code` as marker_observation's.
template <class Finder>
class MarkerLayoutDetector : public KindDetector {
 public:
  template <class... FinderArguments>
  MarkerLayoutDetector(const TagLayout& layout, const PatternPoseOptions& options, std::string code,
                       FinderArguments&&... finder)
      : layout_(layout), options_(options), code_(std::move(code)), finder_(std::forward<FinderArguments>(finder)...) {}
  TargetObservation detect(const cv::Mat& gray) const override {
    return marker_observation(layout_, finder_.detect(gray), options_, code_);
  }

 private:
  TagLayout layout_;
  PatternPoseOptions options_;
  std::string code_;
  Finder finder_;
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
  std::unique_ptr<KindDetector> detector_;
};

}  // namespace handeye
