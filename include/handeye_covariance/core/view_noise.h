// How a camera's pose error of a planar target changes from view to view (no
// ROS, no OpenCV): the shape of the noise of a pose detector that publishes no
// covariance of its own.
//
// A planar target's pose is fitted to its points' image coordinates. With the
// same noise on every image coordinate, its covariance is sigma^2 (J^T J)^-1,
// J = d(x/z, y/z) / d(pose perturbation) over the target's points: depth error
// grows as the square of the distance, lateral and rotation errors as the
// distance, and an oblique view loses depth and tilt. sigma (in units of the
// focal length) is not known without the images; the shape is, from the view
// itself and the target's size. The joint estimator scales the shape by a
// variance component fitted with the rest of the noise (joint_estimator.h).
#pragma once

#include <Eigen/Geometry>

#include "handeye_covariance/core/lie.h"
#include "handeye_covariance/core/rig.h"

namespace handeye {

/// The points the shape is computed from, in the pattern frame: a grid of 3 x 3
/// about the target's printed face (Rig::T_pattern_face) with the second moments
/// of the face's `extent` (m wide and high) covered evenly: the shape of a board's
/// many corners at a fraction of the cost (four corners alone misweigh near views:
/// X's RMS error 4x the Cramer-Rao bound over simulated sessions of 16 at 0.3-1.5 m).
std::vector<Eigen::Vector3d> face_points(const Eigen::Isometry3d& T_pattern_face, const Eigen::Vector2d& extent);

/// face_points of the rig's target (Rig::face_size), or of a nominal 0.2 m square
/// when its size is not known.
std::vector<Eigen::Vector3d> view_points(const Rig& rig);

/// J^T J of `points` (pattern frame) seen at T_camera_pattern, J = d(x/z, y/z) / d(pose
/// perturbation): the information of the view with unit noise on the normalized
/// image coordinates, ROS order, camera frame, left perturbation (pose_covariance.h).
/// The zero matrix when a point is behind the camera.
Matrix6d planar_view_information(const Eigen::Isometry3d& T_camera_pattern, const std::vector<Eigen::Vector3d>& points);

/// Its inverse, the view's covariance shape; the zero matrix when a point is
/// behind the camera or J^T J is singular (an edge-on view).
Matrix6d planar_view_covariance(const Eigen::Isometry3d& T_camera_pattern, const std::vector<Eigen::Vector3d>& points);

}  // namespace handeye
