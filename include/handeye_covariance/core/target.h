// A calibration target as printed (no ROS, no OpenCV): a chessboard, a ChArUco
// board, or markers (one or a board of AprilTags or ArUco markers, a TagLayout
// whose family names the detector). The vision layer detects each kind
// (vision/target.h); io reads target files (io/target_file.h).
//
// Frames: a chessboard's and a ChArUco board's are OpenCV's (vision/chessboard.h,
// vision/aruco.h): origin at a corner, x along a row, y down the rows, z into the
// board. Markers: tag_layout.h.
#pragma once

#include <Eigen/Geometry>
#include <string>

#include "handeye_covariance/core/tag_layout.h"

namespace handeye {

struct ChessboardTarget {
  int columns = 0, rows = 0;  // inner corners along a row, and along a column
  double square = 0.0;        // m, the edge of one square
};

struct CharucoTarget {
  int columns = 0, rows = 0;  // squares along a row, and along a column
  double square = 0.0;        // m, a square's edge
  double marker = 0.0;        // m, a marker's edge (black border included)
  std::string dictionary = "DICT_6X6_250";
};

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
  /// "chessboard", "charuco", "aruco" (one marker or a board) or "apriltag":
  /// the names of the node's `target` argument.
  std::string kind_name() const;
};

/// A grid board of markers (OpenCV's GridBoard: ids row by row from `first_id`)
/// as a layout in OpenCV's board frame (the top-left corner of the top-left
/// marker, x right, y down, z into the board); `family` is the dictionary.
TagLayout aruco_grid_layout(const std::string& dictionary, int columns, int rows, double marker, double separation,
                            int first_id = 0);

/// The name is meant as an OpenCV dictionary (it starts with DICT, any case),
/// known or not: the ArUco path then names a typo with the known dictionaries.
bool names_aruco_dictionary(const std::string& name);

Target make_target(const ChessboardTarget& chessboard);
Target make_target(const CharucoTarget& charuco);
Target make_target(const TagLayout& markers);

/// T_pattern_face: a frame at the middle of the target's printed face, x right,
/// y up, z out of the face towards a camera that sees it (the frame random_view
/// looks at; OpenCV's board frames have y down and z into the board). Markers:
/// the centroid of their centres, turned as the first marker.
Eigen::Isometry3d target_face(const Target& target);

/// The target looks the same turned by 180 degrees about its face's normal through
/// the face's centre: a chessboard whose inner-corner counts columns + rows are
/// even (both odd or both even, e.g. 9 x 7 or 8 x 6), whose squares' colours the
/// turn maps onto themselves. Its detected pose is then one of two candidates, P and
/// P * half_turn(target), told apart only by the robot's motion
/// (estimation/symmetric_views.h). ChArUco, ArUco and AprilTag boards are not: the
/// turn moves each marker to where another id (or none) is printed, so the
/// markers' ids tell the turn apart.
bool is_half_turn_symmetric(const Target& target);

/// F = T_pattern_pattern': the pose of the pattern frame turned by pi about the
/// face's normal through the face's centre (target_face) in the original frame, so
/// the other candidate of a detected T_camera_pattern P is P * F (F = F^-1). For
/// OpenCV's chessboard frame: the turn about z through ((columns - 1) s / 2,
/// (rows - 1) s / 2, 0). The identity when the target is not symmetric
/// (is_half_turn_symmetric): its pose has one candidate.
Eigen::Isometry3d half_turn(const Target& target);

/// The same turn about the face whatever the target (a tag, a ChArUco board): what
/// half_turn gives for a symmetric one. For tests that plant the ambiguity on
/// sessions of targets that do not have it.
Eigen::Isometry3d face_half_turn(const Target& target);

struct Rig;
/// What a session's geometry takes from its target: where its face is
/// (Rig::T_pattern_face, target_face), its size (Rig::face_size,
/// target_face_size) and whether it looks the same turned by 180 degrees
/// (Rig::symmetric_face, is_half_turn_symmetric).
void set_target(Rig& rig, const Target& target);

/// The width and height (m) of the target's detected points about target_face:
/// a chessboard's and a ChArUco board's inner corners, the markers' corners.
Eigen::Vector2d target_face_size(const Target& target);

}  // namespace handeye
