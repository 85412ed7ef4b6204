#include "handeye_covariance/vision/target.h"

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/core/lie.h"

namespace handeye {

void check_target(const Target& target, const std::string& where) {
  switch (target.kind) {
    case TargetKind::Chessboard:
      check_chessboard(target.chessboard, where);
      return;
    case TargetKind::Charuco:
      check_charuco(target.charuco, where);
      return;
    case TargetKind::Markers:
      check_layout(target.markers, where);
      // Every id must exist in its family or dictionary (the bitmap lookup says which ids do).
      for (const TagPlacement& tag : target.markers.tags) tag_bitmap(target.markers.family, tag.id);
      return;
  }
}

TargetDetector::TargetDetector(const Target& target, const TargetDetectorOptions& options)
    : target_(target), options_(options) {
  check_target(target, "target");
  if (target.kind != TargetKind::Markers) return;
  if (names_aruco_dictionary(target.markers.family)) {
    aruco_ = std::make_unique<ArucoDetector>(target.markers.family);
  } else {
    TagDetectorOptions apriltag = options.apriltag;
    apriltag.family = target.markers.family;
    apriltag_ = std::make_unique<TagDetector>(apriltag);
  }
}

TargetDetector::~TargetDetector() = default;

TargetObservation TargetDetector::detect(const cv::Mat& gray) const {
  switch (target_.kind) {
    case TargetKind::Chessboard:
      return detect_chessboard(gray, target_.chessboard);
    case TargetKind::Charuco:
      return detect_charuco(gray, target_.charuco, options_.min_charuco_corners);
    case TargetKind::Markers:
      break;
  }
  const std::vector<TagCorners> tags = aruco_ ? aruco_->detect(gray) : apriltag_->detect(gray);
  TargetObservation found = tag_correspondences(target_.markers, tags, options_.pose);
  if (!found.points && tags.empty()) {
    found.refusal = "no " + target_.markers.family + " marker found (is the target in view, and printed with this " +
                    (aruco_ ? "dictionary" : "family") + "?)";
  } else if (!found.points && found.refusal.rfind("saw 0", 0) == 0) {
    std::string seen;
    for (const TagCorners& t : tags) seen += (seen.empty() ? "" : ", ") + std::to_string(t.id);
    found.refusal = "saw markers " + seen + " but none of the target's ids; check the ids in the target file";
  }
  return found;
}

TargetObservation TargetDetector::detect(const cv::Mat& raw_gray, const ImageRectifier& rectifier) const {
  TargetObservation seen = detect(rectifier.rectify(raw_gray));
  if (seen.points) {
    refine_saddle_points_in_raw_image(raw_gray, rectifier, seen.saddle_half_window, seen.points->image);
  }
  return seen;
}

}  // namespace handeye
