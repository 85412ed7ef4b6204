#include "handeye_covariance/vision/target.h"

#include "handeye_covariance/core/errors.h"

namespace handeye {

// Each kind's part (src/vision/targets/), listed once.
VisionKind chessboard_vision();
VisionKind charuco_vision();
VisionKind aruco_vision();
VisionKind apriltag_vision();

const std::vector<VisionKind>& vision_kinds() {
  static const std::vector<VisionKind> kinds = {chessboard_vision(), charuco_vision(), aruco_vision(), apriltag_vision()};
  return kinds;
}

const VisionKind& vision_kind(const std::string& name) {
  return layer_entry(vision_kinds(), name, "detector", "vision", "VisionKind", "src/vision/target.cpp");
}

void check_target(const Target& target, const std::string& where) { vision_kind(target.kind_name()).check(target, where); }

void check_markers(const TagLayout& layout, const std::string& where) {
  check_layout(layout, where);
  // Every id must exist in its family or dictionary (the bitmap lookup says which ids do).
  for (const TagPlacement& tag : layout.tags) tag_bitmap(layout.family, tag.id);
}

TagBitmap tag_bitmap(const std::string& family, int id) {
  return names_aruco_dictionary(family) ? aruco_bitmap(family, id) : apriltag_bitmap(family, id);
}

TargetObservation marker_observation(const TagLayout& layout, const std::vector<TagCorners>& tags,
                                     const PatternPoseOptions& options, const std::string& code) {
  TargetObservation found = tag_correspondences(layout, tags, options);
  if (!found.points && tags.empty()) {
    found.refusal = "no " + layout.family + " marker found (is the target in view, and printed with this " + code + "?)";
  } else if (!found.points && found.refusal.rfind("saw 0", 0) == 0) {
    std::string seen;
    for (const TagCorners& t : tags) seen += (seen.empty() ? "" : ", ") + std::to_string(t.id);
    found.refusal = "saw markers " + seen + " but none of the target's ids; check the ids in the target file";
  }
  return found;
}

TargetDetector::TargetDetector(const Target& target, const TargetDetectorOptions& options) : target_(target) {
  const VisionKind& kind = vision_kind(target.kind_name());
  kind.check(target, "target");
  detector_ = kind.detector(target, options);
}

TargetDetector::~TargetDetector() = default;

TargetObservation TargetDetector::detect(const cv::Mat& gray) const { return detector_->detect(gray); }

TargetObservation TargetDetector::detect(const cv::Mat& raw_gray, const ImageRectifier& rectifier) const {
  TargetObservation seen = detect(rectifier.rectify(raw_gray));
  if (seen.points) {
    refine_saddle_points_in_raw_image(raw_gray, rectifier, seen.saddle_half_window, seen.points->image);
  }
  return seen;
}

}  // namespace handeye
