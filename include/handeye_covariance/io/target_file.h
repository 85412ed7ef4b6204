// Calibration target files, tag layouts and ROS camera_info files (yaml-cpp; no
// ROS). See docs/targets.md.
#pragma once

#include <string>

#include "handeye_covariance/core/camera.h"
#include "handeye_covariance/core/tag_layout.h"
#include "handeye_covariance/core/target.h"

namespace handeye {
namespace io {

/// A tag pattern layout (config/tag_board_2x2.yaml shows the format):
///   family: tag36h11
///   tags:   # each tag's centre pose in the pattern frame; x/y/z and q default to the identity
///     - {id: 0, size: 0.06, x: -0.04, y: 0.04, z: 0.0, qw: 1, qx: 0, qy: 0, qz: 0}
/// Throws HandEyeError naming the file and the entry.
TagLayout parse_tag_layout(const std::string& text, const std::string& source);
TagLayout read_tag_layout(const std::string& path);

/// A calibration target file (its kind by `type`, the kinds' list in
/// core/target.h; a file with `tags:` is a layout). The kinds of today:
///   {type: chessboard, inner_corners: [columns, rows], square: 0.0236}
///   {type: charuco, squares: [columns, rows], square: 0.036, marker: 0.018, dictionary: DICT_6X6_250}
///   {type: aruco, dictionary: DICT_4X4_50, id: 7, marker: 0.05}
///   {type: aruco_board, dictionary: DICT_4X4_50, markers: [columns, rows], marker: 0.06, separation: 0.015[, first_id: 0]}
///   {type: apriltag, family: tag36h11, id: 10, size: 0.048}
///   a tag layout (parse_tag_layout; `family` may be an ArUco dictionary)
/// Lengths in m. Throws HandEyeError naming the file and key (an unknown type
/// with the known ones). Whether a
/// dictionary or family exists is checked by the detector (vision/target.h).
Target parse_target(const std::string& text, const std::string& source);
Target read_target(const std::string& path);

/// A ROS camera_info YAML (camera_calibration writes one): image_width,
/// image_height, camera_matrix: {data: [9 numbers]}, distortion_coefficients:
/// {data: [...]} (optional). Numbers checked (finite; sizes whole pixels); whether K
/// is a usable pinhole matrix is the vision layer's check (check_camera_model).
/// The sizes are 0 when not given.
CameraModel parse_camera_info(const std::string& text, const std::string& source);

}  // namespace io
}  // namespace handeye
