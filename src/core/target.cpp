#include "handeye_covariance/core/target.h"

#include <cctype>
#include <cstdio>

#include "handeye_covariance/core/lie.h"
#include "handeye_covariance/core/rig.h"

namespace handeye {
namespace {

std::string mm(double metres) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f mm", metres * 1e3);
  return text;
}

/// OpenCV's board frames (y down, z into the board) seen as a printed face or a
/// marker's frame (y up, z out of it): the same plane turned by 180 degrees about x.
Eigen::Matrix3d opencv_board_to_face() { return Eigen::Vector3d(1.0, -1.0, -1.0).asDiagonal(); }

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
  const std::string what = names_aruco_dictionary(markers.family) ? "ArUco" : "AprilTag";
  if (markers.tags.size() == 1) {
    return what + " " + markers.family + " id " + std::to_string(markers.tags[0].id) + ", " + mm(markers.tags[0].size);
  }
  return what + " board of " + std::to_string(markers.tags.size()) + " " + markers.family + " markers";
}

std::string Target::kind_name() const {
  switch (kind) {
    case TargetKind::Chessboard: return "chessboard";
    case TargetKind::Charuco: return "charuco";
    case TargetKind::Markers: break;
  }
  return names_aruco_dictionary(markers.family) ? "aruco" : "apriltag";
}

bool names_aruco_dictionary(const std::string& name) {
  if (name.size() < 4) return false;
  std::string head = name.substr(0, 4);
  for (char& c : head) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return head == "DICT";
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
  const Eigen::Matrix3d flip = opencv_board_to_face();
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

bool is_half_turn_symmetric(const Target& target) {
  return target.kind == TargetKind::Chessboard && (target.chessboard.columns + target.chessboard.rows) % 2 == 0;
}

Eigen::Isometry3d face_half_turn(const Target& target) {
  Rig rig;
  rig.T_pattern_face = target_face(target);
  return rig.face_half_turn();
}

void set_target(Rig& rig, const Target& target) {
  rig.T_pattern_face = target_face(target);
  rig.face_size = target_face_size(target);
  rig.symmetric_face = is_half_turn_symmetric(target);
}

Eigen::Isometry3d half_turn(const Target& target) {
  return is_half_turn_symmetric(target) ? face_half_turn(target) : Eigen::Isometry3d::Identity();
}

Eigen::Vector2d target_face_size(const Target& target) {
  switch (target.kind) {
    case TargetKind::Chessboard:
      return Eigen::Vector2d(target.chessboard.columns - 1, target.chessboard.rows - 1) * target.chessboard.square;
    case TargetKind::Charuco:
      return Eigen::Vector2d(target.charuco.columns - 2, target.charuco.rows - 2) * target.charuco.square;
    case TargetKind::Markers:
      break;
  }
  // The markers' corners in the face's frame: their extent along its x and y.
  const Eigen::Isometry3d face_inverse = target_face(target).inverse();
  Eigen::Vector2d low = Eigen::Vector2d::Constant(INFINITY), high = -low;
  for (const TagPlacement& tag : target.markers.tags) {
    for (const Eigen::Vector3d& corner : tag.corners()) {
      const Eigen::Vector2d p = (face_inverse * corner).head<2>();
      low = low.cwiseMin(p), high = high.cwiseMax(p);
    }
  }
  return target.markers.tags.empty() ? Eigen::Vector2d::Zero() : Eigen::Vector2d(high - low);
}

TagLayout aruco_grid_layout(const std::string& name, int columns, int rows, double marker, double separation,
                            int first_id) {
  TagLayout layout;
  layout.family = name;
  const Eigen::Matrix3d flip = opencv_board_to_face();  // each marker in the board's frame
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < columns; ++c) {
      TagPlacement tag;
      tag.id = first_id + r * columns + c;
      tag.size = marker;
      tag.T_pattern_tag = se3::make_pose(flip, Eigen::Vector3d(c * (marker + separation) + 0.5 * marker,
                                                               r * (marker + separation) + 0.5 * marker, 0.0));
      layout.tags.push_back(tag);
    }
  }
  return layout;
}

}  // namespace handeye
