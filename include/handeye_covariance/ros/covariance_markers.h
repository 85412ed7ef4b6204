// A MarkerArray with the same ellipsoids as the RViz display, for users without
// the plugin. Geometry from core/ellipsoid.h.
#pragma once

#include <visualization_msgs/MarkerArray.h>

#include <optional>
#include <string>

#include "handeye_covariance/core/ellipsoid.h"
#include "handeye_covariance/core/rig.h"
#include "handeye_covariance/core/units.h"

namespace handeye {

struct CovarianceMarkerOptions {
  double sigmas = 3.0;        // ellipsoid size in sigma
  double axis_length = 0.1;   // m: where the orientation discs sit on each axis
  std::string ns = "handeye_covariance";
};

/// Position ellipsoid (id 0), one disc per local axis for the orientation
/// uncertainty (ids 1-3, red/green/blue for x/y/z) and a 1-sigma label (id 4),
/// all in `frame`. Throws HandEyeError for an invalid covariance.
visualization_msgs::MarkerArray covariance_markers(const PoseWithCovariance& X, const std::string& frame,
                                                   const ros::Time& stamp, const CovarianceMarkerOptions& options = {});

struct NextPoseMarkerOptions {
  double axis_length = 0.1;  // m, the ghost effector frame's axes
  /// The frustum's full opening angles (rad): a common RGB-D camera's colour stream
  /// (the node does not know the camera's intrinsics).
  double horizontal_fov = radians(69.0), vertical_fov = radians(42.0);
  std::string ns = "handeye_next_pose";
};

/// The suggested next pose, for the operator to jog the robot to, all in the robot
/// base `frame`: a ghost effector frame at T_base_effector (id 0: x, y, z in red,
/// green, blue), the camera's view frustum at that pose out to `depth` along its
/// optical axis (id 1; the camera is rig.camera_parent_in_base(T_base_effector) X),
/// and `label` above the effector (id 2). The first marker is a DELETEALL of the
/// namespace, so that an earlier suggestion goes; without a pose, that is all.
visualization_msgs::MarkerArray next_pose_markers(const Rig& rig, const std::optional<Eigen::Isometry3d>& T_base_effector,
                                                  const Eigen::Isometry3d& X, double depth, const std::string& label,
                                                  const std::string& frame, const ros::Time& stamp,
                                                  const NextPoseMarkerOptions& options = {});

/// "1σ 0.42 mm, 0.031°": worst-axis translation and rotation sigma.
std::string sigma_label(const PoseWithCovariance& X);

}  // namespace handeye
