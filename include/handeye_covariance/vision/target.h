// A calibration target of any kind, and the one detector that finds it in an
// image (no ROS): a chessboard, a ChArUco board, or markers (one or a board of
// AprilTags or ArUco markers, a TagLayout whose family names the detector).
// Every kind ends in the same correspondences (target points, image points, the
// detector's corner-noise model) and so in the same PnP (estimate_pose).
#pragma once

#include <memory>
#include <optional>
#include <string>

#include <opencv2/core.hpp>

#include "handeye_covariance/core/tag_layout.h"
#include "handeye_covariance/vision/aruco.h"
#include "handeye_covariance/vision/chessboard.h"
#include "handeye_covariance/vision/pattern_pose.h"
#include "handeye_covariance/vision/tag_detector.h"

namespace handeye {

enum class TargetKind { Chessboard, Charuco, Markers };

struct Target {
  TargetKind kind = TargetKind::Markers;
  ChessboardTarget chessboard;  // kind Chessboard
  CharucoTarget charuco;        // kind Charuco
  /// kind Markers: AprilTags (family: a libapriltag family, e.g. tag36h11) or
  /// ArUco markers (family: an OpenCV dictionary, e.g. DICT_4X4_50).
  TagLayout markers;

  /// e.g. "chessboard 9 x 6 inner corners, 23.6 mm squares".
  std::string describe() const;
};

Target make_target(const ChessboardTarget& chessboard);
Target make_target(const CharucoTarget& charuco);
Target make_target(const TagLayout& markers);

/// T_pattern_face: a frame at the middle of the target's printed face, x right,
/// y up, z out of the face towards a camera that sees it (the frame random_view
/// looks at; OpenCV's board frames have y down and z into the board). Markers:
/// the centroid of their centres, turned as the first marker.
Eigen::Isometry3d target_face(const Target& target);

/// Throws HandEyeError(InvalidLayout) naming what is wrong and how to fix it.
void check_target(const Target& target, const std::string& where);

struct TargetDetectorOptions {
  TagDetectorOptions apriltag;        // family is taken from the target
  PatternPoseOptions pose;            // min_tags and the corner model for marker targets
  int min_charuco_corners = 6;
};

struct TargetObservation {
  std::optional<PointCorrespondences> points;
  std::string refusal;  // why not (empty when found)
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

  const Target& target() const { return target_; }

 private:
  Target target_;
  TargetDetectorOptions options_;
  std::unique_ptr<TagDetector> apriltag_;
  std::unique_ptr<ArucoDetector> aruco_;
};

}  // namespace handeye
