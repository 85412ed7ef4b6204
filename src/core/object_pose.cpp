#include "handeye_covariance/core/object_pose.h"

#include "handeye_covariance/core/validation.h"

namespace handeye {

namespace {

void check(const PoseWithCovariance& T, const std::string& where) {
  check_pose(T.pose, where);
  check_covariance(T.covariance, where + ".covariance");
}

Matrix6d sandwich(const Matrix6d& J, const Matrix6d& covariance) { return J * covariance * J.transpose(); }

}  // namespace

const char* to_string(CovarianceOrigin origin) {
  switch (origin) {
    case CovarianceOrigin::Input: return "its own";
    case CovarianceOrigin::Stated: return "stated";
    case CovarianceOrigin::CalibrationModel: return "the calibration's noise model";
    case CovarianceOrigin::None: return "none";
  }
  return "none";
}

ChosenCovariance choose_covariance(const std::optional<Matrix6d>& input, const std::optional<Matrix6d>& stated,
                                   const std::optional<PoseNoise>& calibration_model) {
  if (input) return {*input, CovarianceOrigin::Input};
  if (stated) return {*stated, CovarianceOrigin::Stated};
  if (calibration_model) return {calibration_model->as_pose_covariance(), CovarianceOrigin::CalibrationModel};
  return {};
}

Matrix6d isotropic_covariance(double sigma_translation, double sigma_rotation) {
  Matrix6d c = Matrix6d::Zero();
  c.diagonal() << Eigen::Vector3d::Constant(sigma_translation * sigma_translation),
      Eigen::Vector3d::Constant(sigma_rotation * sigma_rotation);
  return c;
}

ObjectPose object_in_base(const ObjectPoseInput& input) {
  // Eq. (68): T = T_base_parent X P, T_base_parent = E (eye_in_hand) or the identity (eye_to_hand).
  const bool in_hand = input.rig.eye_in_hand();
  if (in_hand) check(input.T_base_effector, "effector");
  check(input.X, "calibration");
  check(input.T_camera_object, "object");
  const Eigen::Isometry3d E = input.rig.camera_parent_in_base(input.T_base_effector.pose);
  const Eigen::Isometry3d& X = input.X.pose;
  const Eigen::Isometry3d& P = input.T_camera_object.pose;
  ObjectPose out;
  out.T_base_object.pose = E * X * P;
  if (in_hand) out.from_robot = sandwich(compose_jacobian_left(E, X * P), input.T_base_effector.covariance);
  out.from_calibration =
      sandwich(compose_jacobian_right(E) * compose_jacobian_left(X, P), input.X.covariance);
  out.from_detection = sandwich(compose_jacobian_right(E * X), input.T_camera_object.covariance);
  out.T_base_object.covariance = out.from_robot + out.from_calibration + out.from_detection;
  return out;
}

PointInBase point_in_base(const ObjectPose& object, const Eigen::Vector3d& p_object) {
  const Eigen::Isometry3d& T = object.T_base_object.pose;
  PointInBase point;
  point.position = T * p_object;
  point.covariance = point_covariance(object.T_base_object, p_object);
  point.from_robot = point_covariance({T, object.from_robot}, p_object);
  point.from_calibration = point_covariance({T, object.from_calibration}, p_object);
  point.from_detection = point_covariance({T, object.from_detection}, p_object);
  return point;
}

}  // namespace handeye
