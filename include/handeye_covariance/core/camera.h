// The camera and the target's corners in its image, as plain data (no OpenCV):
// what a detection carries besides its pose, so that samples, session files and
// messages can hold the corners for `--method corners`. Projecting and detecting
// are the vision layer's (vision/pattern_pose.h: project, estimate_pose).
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <string>
#include <vector>

namespace handeye {

/// A pinhole camera with OpenCV's distortion model (sensor_msgs/CameraInfo's
/// plumb_bob / rational_polynomial: D = k1, k2, p1, p2[, k3[, k4, k5, k6]]).
struct CameraModel {
  Eigen::Matrix3d K = Eigen::Matrix3d::Identity();
  std::vector<double> distortion;
  int width = 0, height = 0;
  /// The 1 sigma of fx, fy, cx, cy (px) from the camera's own calibration, when the
  /// camera file states it (`intrinsics_sigma`); zero: taken as exact. Each view's
  /// pose covariance then carries it (vision/pattern_pose.h).
  Eigen::Vector4d intrinsics_sigma = Eigen::Vector4d::Zero();
};

/// Throws HandEyeError when K is not a usable pinhole matrix (fx, fy <= 0, NaN)
/// or the distortion has a length OpenCV does not know.
void check_camera_model(const CameraModel& camera, const std::string& where);

/// What a detector found of a target: the target's points (pattern frame, m) and
/// where they are in the image (px), with the detector's corner noise model.
struct PointCorrespondences {
  std::vector<Eigen::Vector3d> object;
  std::vector<Eigen::Vector2d> image;
  std::vector<int> ids;  // the tags, markers or corners used (for messages and PatternPose::ids)
  /// (2n x 2n) per unit sigma^2, block-diagonal in blocks of `blocks` rows (8: one
  /// AprilTag's four corners under the edge-fit model; 2: independent corners).
  /// Empty: independent corners, identity.
  Eigen::MatrixXd corner_covariance;
  int blocks = 2;
};

/// What a target's corners may be: the corner estimator whitens blocks of at most
/// kMaxCornerBlock coordinates, and a target of more than kMaxTargetPoints points
/// (its dense 2n x 2n covariance) is refused before it is allocated.
constexpr int kMaxCornerBlock = 16;
constexpr std::size_t kMaxTargetPoints = 1000;

/// Throws HandEyeError naming what is wrong with `points` at `where`: no points
/// or more than kMaxTargetPoints (NoData), object and image of different lengths
/// or a covariance that is not 2n x 2n in even blocks of at most kMaxCornerBlock
/// (WrongLength), NaN or Inf (NonFinite), a block that is not positive definite
/// (InvalidNoise).
void check_corners(const PointCorrespondences& points, const std::string& where);

/// How files and messages carry a corner covariance: its diagonal blocks of
/// `points.blocks` rows, each row-major, in order; empty when there is none.
std::vector<double> covariance_blocks(const PointCorrespondences& points);
/// The block-diagonal matrix of such blocks (`values.size()` a multiple of
/// block^2, checked by the caller): values.size() / block rows.
Eigen::MatrixXd from_covariance_blocks(const std::vector<double>& values, int block);

/// The corners behind one detected pattern pose, in the raw pixels (distortion
/// included) of the camera that saw them.
struct TargetCorners {
  CameraModel camera;
  PointCorrespondences points;
  std::string source;  // the image (file name, or the detection's stamp), for reports
};

}  // namespace handeye
