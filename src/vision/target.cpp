#include "handeye_covariance/vision/target.h"

#include <cstdio>

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/core/lie.h"

namespace handeye {
namespace {

std::string mm(double metres) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f mm", metres * 1e3);
  return text;
}

}  // namespace

std::string Target::describe() const {
  switch (kind) {
    case TargetKind::Chessboard:
      return "chessboard " + std::to_string(chessboard.columns) + " x " + std::to_string(chessboard.rows) +
             " inner corners, " + mm(chessboard.square) + " squares";
    case TargetKind::Charuco:
      return "ChArUco " + std::to_string(charuco.columns) + " x " + std::to_string(charuco.rows) + " squares of " +
             mm(charuco.square) + ", " + mm(charuco.marker) + " markers, " + charuco.dictionary;
    case TargetKind::Markers:
      break;
  }
  const std::string what = is_aruco_dictionary(markers.family) ? "ArUco" : "AprilTag";
  if (markers.tags.size() == 1) {
    return what + " " + markers.family + " id " + std::to_string(markers.tags[0].id) + ", " + mm(markers.tags[0].size);
  }
  return what + " board of " + std::to_string(markers.tags.size()) + " " + markers.family + " markers";
}

Target make_target(const ChessboardTarget& chessboard) {
  Target target;
  target.kind = TargetKind::Chessboard;
  target.chessboard = chessboard;
  return target;
}

Target make_target(const CharucoTarget& charuco) {
  Target target;
  target.kind = TargetKind::Charuco;
  target.charuco = charuco;
  return target;
}

Target make_target(const TagLayout& markers) {
  Target target;
  target.kind = TargetKind::Markers;
  target.markers = markers;
  return target;
}

Eigen::Isometry3d target_face(const Target& target) {
  const Eigen::Matrix3d flip = Eigen::Vector3d(1.0, -1.0, -1.0).asDiagonal();
  switch (target.kind) {
    case TargetKind::Chessboard: {
      const ChessboardTarget& t = target.chessboard;
      return se3::make_pose(flip, Eigen::Vector3d(0.5 * (t.columns - 1) * t.square, 0.5 * (t.rows - 1) * t.square, 0.0));
    }
    case TargetKind::Charuco: {
      const CharucoTarget& t = target.charuco;
      return se3::make_pose(flip, Eigen::Vector3d(0.5 * t.columns * t.square, 0.5 * t.rows * t.square, 0.0));
    }
    case TargetKind::Markers:
      break;
  }
  if (target.markers.tags.empty()) return Eigen::Isometry3d::Identity();
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (const TagPlacement& tag : target.markers.tags) centre += tag.T_pattern_tag.translation();
  centre /= static_cast<double>(target.markers.tags.size());
  return se3::make_pose(target.markers.tags.front().T_pattern_tag.linear(), centre);
}

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
  if (is_aruco_dictionary(target.markers.family)) {
    aruco_ = std::make_unique<ArucoDetector>(target.markers.family);
  } else {
    TagDetectorOptions apriltag = options.apriltag;
    apriltag.family = target.markers.family;
    apriltag_ = std::make_unique<TagDetector>(apriltag);
  }
}

TargetDetector::~TargetDetector() = default;

TargetObservation TargetDetector::detect(const cv::Mat& gray) const {
  TargetObservation out;
  switch (target_.kind) {
    case TargetKind::Chessboard: {
      ChessboardDetection found = detect_chessboard(gray, target_.chessboard);
      out.points = std::move(found.points);
      out.refusal = std::move(found.refusal);
      return out;
    }
    case TargetKind::Charuco: {
      CharucoDetection found = detect_charuco(gray, target_.charuco, options_.min_charuco_corners);
      out.points = std::move(found.points);
      out.refusal = std::move(found.refusal);
      return out;
    }
    case TargetKind::Markers:
      break;
  }
  const std::vector<TagCorners> tags = aruco_ ? aruco_->detect(gray) : apriltag_->detect(gray);
  TagCorrespondences found = tag_correspondences(target_.markers, tags, options_.pose);
  if (!found.points && tags.empty()) {
    found.refusal = "no " + target_.markers.family + " marker found (is the target in view, and printed with this " +
                    (aruco_ ? "dictionary" : "family") + "?)";
  } else if (!found.points && found.refusal.rfind("saw 0", 0) == 0) {
    std::string seen;
    for (const TagCorners& t : tags) seen += (seen.empty() ? "" : ", ") + std::to_string(t.id);
    found.refusal = "saw markers " + seen + " but none of the target's ids; check the ids in the target file";
  }
  out.points = std::move(found.points);
  out.refusal = std::move(found.refusal);
  return out;
}

}  // namespace handeye
