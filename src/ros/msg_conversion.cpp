#include "handeye_covariance/ros/msg_conversion.h"

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/core/units.h"
#include "handeye_covariance/io/check_text.h"

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

geometry_msgs::PoseWithCovarianceStamped to_stamped_msg(const PoseWithCovariance& pose, const std::string& frame,
                                                        const ros::Time& stamp) {
  geometry_msgs::PoseWithCovarianceStamped msg;
  msg.header.stamp = stamp;
  msg.header.frame_id = frame;
  msg.pose = to_msg(pose);
  return msg;
}

geometry_msgs::TransformStamped to_transform_stamped(const Eigen::Isometry3d& T_parent_child, const std::string& parent,
                                                     const std::string& child, const ros::Time& stamp) {
  geometry_msgs::TransformStamped tf;
  tf.header.stamp = stamp;
  tf.header.frame_id = parent;
  tf.child_frame_id = child;
  tf.transform = to_transform_msg(T_parent_child);
  return tf;
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

CameraModel to_camera_model(const sensor_msgs::CameraInfo& info) {
  const std::string where = "CameraInfo of frame `" + info.header.frame_id + "`";
  CameraModel camera;
  camera.K = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(info.K.data());
  camera.width = static_cast<int>(info.width);
  camera.height = static_cast<int>(info.height);
  if (info.distortion_model != "plumb_bob" && info.distortion_model != "rational_polynomial" &&
      !(info.distortion_model.empty() && info.D.empty())) {
    throw HandEyeError(ErrorCode::MalformedFile, "distortion model `" + info.distortion_model + "` is not supported", where,
                       "calibrate with plumb_bob or rational_polynomial (camera_calibration does), or feed the "
                       "rectified image (image_rect) with ~image_is_rectified:=true");
  }
  camera.distortion.assign(info.D.begin(), info.D.end());
  if (camera.K.isZero()) {
    throw HandEyeError(ErrorCode::MalformedFile, "K is all zeros: the camera is not calibrated", where,
                       "calibrate the intrinsics first (rosrun camera_calibration cameracalibrator.py) so that the "
                       "driver publishes K and D");
  }
  check_camera_model(camera, where);
  return camera;
}

sensor_msgs::CameraInfo to_camera_info(const CameraModel& camera) {
  sensor_msgs::CameraInfo info;
  info.width = static_cast<uint32_t>(camera.width);
  info.height = static_cast<uint32_t>(camera.height);
  info.distortion_model = camera.distortion.size() > 5 ? "rational_polynomial" : "plumb_bob";
  info.D = camera.distortion;
  Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(info.K.data()) = camera.K;
  info.R = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  Eigen::Map<Eigen::Matrix<double, 3, 4, Eigen::RowMajor>> P(info.P.data());
  P.setZero();
  P.leftCols<3>() = camera.K;
  return info;
}

std::shared_ptr<TargetCorners> to_corners(const TagDetection& detection) {
  if (detection.object_points.empty() && detection.image_points.empty()) return nullptr;
  const std::string where = "a detection's corners";
  const std::size_t n = detection.object_points.size();
  if (n > kMaxTargetPoints) {  // before its 2n x 2n covariance is allocated
    throw HandEyeError(ErrorCode::WrongLength, std::to_string(n) + " object_points", where,
                       "a target has at most " + std::to_string(kMaxTargetPoints) + " points");
  }
  if (detection.image_points.size() != 2 * n) {
    throw HandEyeError(ErrorCode::WrongLength,
                       std::to_string(detection.image_points.size()) + " image_points for " + std::to_string(n) +
                           " object_points",
                       where, "send u, v per object point, in the same order");
  }
  const int block = detection.corner_block == 0 ? 2 : detection.corner_block;
  if (block < 2 || block % 2 != 0 || block > kMaxCornerBlock || (2 * n) % static_cast<std::size_t>(block) != 0) {
    throw HandEyeError(ErrorCode::WrongLength, "corner_block " + std::to_string(block) + " does not divide " +
                                                   std::to_string(2 * n) + " coordinates into whole points",
                       where, "2 for independent corners, 8 for an AprilTag's four");
  }
  if (!detection.corner_covariance.empty() && detection.corner_covariance.size() != 2 * n * static_cast<std::size_t>(block)) {
    throw HandEyeError(ErrorCode::WrongLength,
                       "corner_covariance has " + std::to_string(detection.corner_covariance.size()) + " numbers, " +
                           std::to_string(2 * n * static_cast<std::size_t>(block)) + " expected",
                       where, "send the diagonal blocks (corner_block^2 numbers each, row-major), or none");
  }
  auto corners = std::make_shared<TargetCorners>();
  corners->camera = to_camera_model(detection.camera_info);  // checked there
  PointCorrespondences& p = corners->points;
  p.blocks = block;
  p.ids.assign(detection.point_ids.begin(), detection.point_ids.end());
  for (std::size_t i = 0; i < n; ++i) {
    const geometry_msgs::Point& o = detection.object_points[i];
    p.object.emplace_back(o.x, o.y, o.z);
    p.image.emplace_back(detection.image_points[2 * i], detection.image_points[2 * i + 1]);
  }
  if (!detection.corner_covariance.empty()) {
    p.corner_covariance = from_covariance_blocks(detection.corner_covariance, block);
  }
  check_corners(p, where);
  return corners;
}

void set_corners(const TargetCorners& corners, TagDetection& detection) {
  const PointCorrespondences& p = corners.points;
  detection.object_points.clear();
  detection.image_points.clear();
  for (std::size_t i = 0; i < p.object.size(); ++i) {
    geometry_msgs::Point o;
    o.x = p.object[i].x();
    o.y = p.object[i].y();
    o.z = p.object[i].z();
    detection.object_points.push_back(o);
    detection.image_points.push_back(p.image[i].x());
    detection.image_points.push_back(p.image[i].y());
  }
  detection.point_ids.assign(p.ids.begin(), p.ids.end());
  detection.corner_block = p.blocks;
  detection.corner_covariance = covariance_blocks(p);
  detection.camera_info = to_camera_info(corners.camera);
}

CalibrationCheckMsg to_msg(const CalibrationCheck& check, const ros::Time& stamp) {
  CalibrationCheckMsg msg;
  msg.header.stamp = stamp;
  msg.state = check.changed ? "changed" : "consistent";
  msg.text = io::check_verdict(check);
  msg.views_taken = msg.views_needed = static_cast<int>(check.views.size());
  msg.p_value = check.p_value;
  msg.alpha = check.alpha;
  msg.chi2 = check.chi2;
  msg.dof = check.dof;
  if (check.changed) {
    msg.changed = to_string(*check.change.what);
    const EstimatedChange::Delta& d = check.change.reported();
    for (int k = 0; k < 6; ++k) msg.change[static_cast<std::size_t>(k)] = d.value(k);
    const std::array<double, 36> c = to_row_major_6x6(d.covariance);
    std::copy(c.begin(), c.end(), msg.change_covariance.begin());
  }
  for (const CheckedView& v : check.views) {
    msg.view_error_mm.push_back(millimetres(v.translation_error));
    msg.view_sigma_mm.push_back(millimetres(v.predicted_translation_sigma));
    msg.view_error_deg.push_back(degrees(v.rotation_error));
    msg.view_sigma_deg.push_back(degrees(v.predicted_rotation_sigma));
    msg.view_mahalanobis.push_back(v.mahalanobis);
  }
  msg.left_out = check.left_out;
  msg.advice = io::check_advice(check);
  return msg;
}

trajectory_msgs::JointTrajectory to_msg(const motion::TrajectoryCommand& command) {
  trajectory_msgs::JointTrajectory msg;
  if (command.stamp != 0.0) msg.header.stamp = ros::Time(command.stamp);
  msg.joint_names = command.joint_names;
  for (const motion::TrajectoryPoint& p : command.points) {
    trajectory_msgs::JointTrajectoryPoint point;
    point.positions.assign(p.position.data(), p.position.data() + p.position.size());
    point.velocities.assign(p.velocity.data(), p.velocity.data() + p.velocity.size());
    point.accelerations.assign(p.acceleration.data(), p.acceleration.data() + p.acceleration.size());
    point.time_from_start = ros::Duration(p.time);
    msg.points.push_back(point);
  }
  return msg;
}

motion::TrajectoryCommand to_core(const trajectory_msgs::JointTrajectory& msg) {
  motion::TrajectoryCommand command;
  command.stamp = msg.header.stamp.isZero() ? 0.0 : msg.header.stamp.toSec();
  command.joint_names = msg.joint_names;
  auto vector = [](const std::vector<double>& v) { return Eigen::Map<const Eigen::VectorXd>(v.data(), v.size()); };
  for (const auto& point : msg.points)
    command.points.push_back({point.time_from_start.toSec(), vector(point.positions), vector(point.velocities),
                              vector(point.accelerations)});
  return command;
}

}  // namespace conversions
}  // namespace handeye
