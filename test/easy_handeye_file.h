// easy_handeye's calibration file, as its users keep it: what publish.launch and the
// calibration node must read (test_yaml_io, test_node_publish).
#pragma once

#include <Eigen/Geometry>
#include <sstream>
#include <string>

namespace handeye::test {

/// Its `transformation` block: X as {x, y, z, qx, qy, qz, qw}, m.
inline std::string easy_handeye_transformation(const Eigen::Isometry3d& X) {
  const Eigen::Quaterniond q(X.linear());
  std::ostringstream out;
  out.precision(17);
  out << "transformation:\n  x: " << X.translation().x() << "\n  y: " << X.translation().y()
      << "\n  z: " << X.translation().z() << "\n  qx: " << q.x() << "\n  qy: " << q.y() << "\n  qz: " << q.z()
      << "\n  qw: " << q.w() << "\n";
  return out.str();
}

/// The whole file of X = T_parent_camera: the frames under `parameters:` (nested, its
/// current format) or at the top level (its older one), then the transformation.
inline std::string easy_handeye_text(const Eigen::Isometry3d& X, bool eye_on_hand, const std::string& parent,
                                     const std::string& camera, bool nested) {
  const std::string indent = nested ? "  " : "";
  std::ostringstream out;
  if (nested) out << "parameters:\n";
  out << indent << "eye_on_hand: " << (eye_on_hand ? "true" : "false") << "\n"
      << indent << "robot_base_frame: " << (eye_on_hand ? "base_link" : parent) << "\n"
      << indent << "robot_effector_frame: " << (eye_on_hand ? parent : "tool0") << "\n"
      << indent << "tracking_base_frame: " << camera << "\n"
      << indent << "tracking_marker_frame: marker\n";
  return out.str() + easy_handeye_transformation(X);
}

}  // namespace handeye::test
