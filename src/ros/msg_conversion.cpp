#include "handeye_covariance/ros/msg_conversion.h"

#include "handeye_covariance/core/errors.h"

#include <cmath>

namespace handeye {
namespace conversions {

namespace {
Eigen::Quaterniond quaternion(const geometry_msgs::Quaternion& q) { return {q.w, q.x, q.y, q.z}; }
geometry_msgs::Quaternion quaternion_msg(const Eigen::Matrix3d& R) {
  Eigen::Quaterniond q(R);
  if (q.w() < 0) q.coeffs() *= -1.0;
  geometry_msgs::Quaternion msg;
  msg.x = q.x();
  msg.y = q.y();
  msg.z = q.z();
  msg.w = q.w();
  return msg;
}
}  // namespace

Eigen::Isometry3d to_eigen(const geometry_msgs::Pose& pose) {
  return se3::make_pose(quaternion(pose.orientation).normalized().toRotationMatrix(),
                        Eigen::Vector3d(pose.position.x, pose.position.y, pose.position.z));
}

Eigen::Isometry3d to_eigen(const geometry_msgs::Transform& transform) {
  return se3::make_pose(quaternion(transform.rotation).normalized().toRotationMatrix(),
                        Eigen::Vector3d(transform.translation.x, transform.translation.y, transform.translation.z));
}

geometry_msgs::Pose to_pose_msg(const Eigen::Isometry3d& pose) {
  geometry_msgs::Pose msg;
  msg.position.x = pose.translation().x();
  msg.position.y = pose.translation().y();
  msg.position.z = pose.translation().z();
  msg.orientation = quaternion_msg(pose.linear());
  return msg;
}

geometry_msgs::Transform to_transform_msg(const Eigen::Isometry3d& pose) {
  geometry_msgs::Transform msg;
  msg.translation.x = pose.translation().x();
  msg.translation.y = pose.translation().y();
  msg.translation.z = pose.translation().z();
  msg.rotation = quaternion_msg(pose.linear());
  return msg;
}

PoseWithCovariance to_core(const geometry_msgs::PoseWithCovariance& msg) {
  std::array<double, 36> values;
  std::copy(msg.covariance.begin(), msg.covariance.end(), values.begin());
  return {to_eigen(msg.pose), from_row_major_6x6(values)};
}

geometry_msgs::PoseWithCovariance to_msg(const PoseWithCovariance& pose) {
  geometry_msgs::PoseWithCovariance msg;
  msg.pose = to_pose_msg(pose.pose);
  const std::array<double, 36> values = to_row_major_6x6(pose.covariance);
  std::copy(values.begin(), values.end(), msg.covariance.begin());
  return msg;
}

std::optional<Matrix6d> covariance_if_nonzero(const boost::array<double, 36>& covariance) {
  if (std::all_of(covariance.begin(), covariance.end(), [](double v) { return v == 0.0; })) return std::nullopt;
  std::array<double, 36> values;
  std::copy(covariance.begin(), covariance.end(), values.begin());
  return from_row_major_6x6(values);
}

boost::array<double, 9> to_msg_array(const Eigen::Matrix3d& covariance) {
  const std::array<double, 9> values = to_row_major_3x3(covariance);
  boost::array<double, 9> out;
  std::copy(values.begin(), values.end(), out.begin());
  return out;
}

double quaternion_norm(const geometry_msgs::Quaternion& q) {
  return std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
}

}  // namespace conversions
}  // namespace handeye
