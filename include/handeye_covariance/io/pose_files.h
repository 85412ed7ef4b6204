// Robot pose files, one per image, in the formats users keep, and the CSV pose
// table for a folder of images (no ROS).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Geometry>

namespace handeye {
namespace io {

/// A robot pose file, one per image (T_base_effector in m), in any format users
/// keep next to their images:
///   YAML or JSON {matrix: [16 numbers, row-major]} or {translation: [x, y, z], rotation: [qx, qy, qz, qw]};
///   ViSP's vpPoseVector YAML {rows: 6, cols: 1, data: [[tx], [ty], [tz], [tux], [tuy], [tuz]]}
///     (theta-u: the rotation axis times its angle, rad);
///   a plain-text 4x4 matrix (16 numbers; whitespace, commas or semicolons between them).
/// Throws HandEyeError naming the file and what is wrong.
Eigen::Isometry3d parse_robot_pose(const std::string& text, const std::string& source);
Eigen::Isometry3d read_robot_pose(const std::string& path);

/// One CSV of robot poses for a folder of images: `image,tx,ty,tz,qx,qy,qz,qw`
/// per line (m, unit quaternion), a header line skipped, blank lines ignored.
/// `image` is the file name or its stem. Throws HandEyeError naming the line.
struct PoseTableRow {
  std::string image;
  Eigen::Isometry3d T_base_effector;
  std::string where;  // "poses.csv line 3"
};
std::vector<PoseTableRow> parse_pose_table(const std::string& text, const std::string& source);

}  // namespace io
}  // namespace handeye
