// The pose of an object in the robot base, with its covariance: what the
// calibration is for (paper section IV-C, eq. 68, and Appendix A).
//
//   eye_in_hand: T_base_object = T_base_effector * X * T_camera_object,  X = T_effector_camera
//   eye_to_hand: T_base_object = X * T_camera_object,                    X = T_base_camera
//
// Three independent uncertainties compound to first order: the robot's pose
// when the image was taken (eye_in_hand only), X (its full 6x6, with the R-t
// cross block the estimator gives), and the detection's own covariance. All
// covariances are in ROS order (x, y, z, rx, ry, rz), rotation as a left
// perturbation in the parent frame (pose_covariance.h). The paper's Appendix A
// compounds decoupled blocks (compose_decoupled); here the full 6x6 is kept,
// because X's translation error is strongly correlated with its rotation error.
#pragma once

#include <optional>

#include "handeye_covariance/core/measurements.h"

namespace handeye {

/// Where a pose's covariance comes from: one rule for `handeye compose` and the
/// object_localizer node. In order: the input's own (a message's or a pose
/// file's covariance), what the user stated (1 sigma options or parameters),
/// the calibration's noise model (the pattern's for a detection, the robot's
/// for a robot pose); else none, and the caller refuses the pose or takes it as
/// exact, saying so.
enum class CovarianceOrigin { Input, Stated, CalibrationModel, None };
const char* to_string(CovarianceOrigin origin);  // "its own", "stated", "the calibration's noise model", "none"

struct ChosenCovariance {
  Matrix6d covariance = Matrix6d::Zero();  // zero when origin is None
  CovarianceOrigin origin = CovarianceOrigin::None;
};
ChosenCovariance choose_covariance(const std::optional<Matrix6d>& input, const std::optional<Matrix6d>& stated,
                                   const std::optional<PoseNoise>& calibration_model);

/// Isotropic 6x6 from a 1 sigma per axis (m, rad).
Matrix6d isotropic_covariance(double sigma_translation, double sigma_rotation);

struct ObjectPoseInput {
  Rig rig;  // only its setup matters here
  PoseWithCovariance T_base_effector;  // at the detection's stamp; ignored for eye_to_hand
  PoseWithCovariance X;                // T_effector_camera or T_base_camera, with its covariance
  PoseWithCovariance T_camera_object;  // the detection
};

struct ObjectPose {
  PoseWithCovariance T_base_object;
  /// Each term's part of T_base_object.covariance (they sum to it): which one
  /// to improve first.
  Matrix6d from_robot = Matrix6d::Zero();
  Matrix6d from_calibration = Matrix6d::Zero();
  Matrix6d from_detection = Matrix6d::Zero();
};

/// Eq. (68) with first-order propagation. Throws HandEyeError (NonFinite,
/// RotationNotOrthonormal, InvalidNoise) naming the bad input.
ObjectPose object_in_base(const ObjectPoseInput& input);

/// A point fixed on the object (p_object, e.g. a hole to drill) in the base
/// frame, with each term's part of its 3x3 covariance (m^2).
struct PointInBase {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d from_robot = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d from_calibration = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d from_detection = Eigen::Matrix3d::Zero();
};
PointInBase point_in_base(const ObjectPose& object, const Eigen::Vector3d& p_object);

}  // namespace handeye
