#include "handeye_covariance/ros/covariance_markers.h"

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/core/units.h"
#include "handeye_covariance/ros/msg_conversion.h"

namespace handeye {

namespace {

visualization_msgs::Marker ellipsoid_marker(const Ellipsoid& e, const Eigen::Vector3d& center, int id,
                                            std::array<float, 4> rgba) {
  visualization_msgs::Marker m;
  m.id = id;
  m.type = visualization_msgs::Marker::SPHERE;
  m.action = visualization_msgs::Marker::ADD;
  m.pose = conversions::to_pose_msg(se3::make_pose(e.axes, center));
  m.scale.x = std::max(2.0 * e.radii(0), 1e-4);  // a rank-deficient axis still shows as a thin disc
  m.scale.y = std::max(2.0 * e.radii(1), 1e-4);
  m.scale.z = std::max(2.0 * e.radii(2), 1e-4);
  m.color.r = rgba[0], m.color.g = rgba[1], m.color.b = rgba[2], m.color.a = rgba[3];
  return m;
}

}  // namespace

std::string sigma_label(const PoseWithCovariance& X) {
  return "1\u03c3 " + number_text(millimetres(max_sigma(X.covariance.topLeftCorner<3, 3>())), 3) + " mm, " +
         number_text(degrees(max_sigma(X.covariance.bottomRightCorner<3, 3>())), 3) + "\u00b0";
}

visualization_msgs::MarkerArray covariance_markers(const PoseWithCovariance& X, const std::string& frame,
                                                   const ros::Time& stamp, const CovarianceMarkerOptions& o) {
  visualization_msgs::MarkerArray array;
  const Eigen::Vector3d origin = X.pose.translation();
  array.markers.push_back(ellipsoid_marker(
      ellipsoid_from_covariance(X.covariance.topLeftCorner<3, 3>(), o.sigmas), origin, 0, {1.0f, 0.0f, 1.0f, 0.6f}));
  const std::array<std::array<float, 4>, 3> colours = {{{1, 0, 0, 0.6f}, {0, 1, 0, 0.6f}, {0, 0, 1, 0.6f}}};
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d axis = X.pose.linear().col(k);
    const Ellipsoid disc = ellipsoid_from_covariance(
        axis_tip_covariance(X.covariance.bottomRightCorner<3, 3>(), axis, o.axis_length), o.sigmas);
    array.markers.push_back(ellipsoid_marker(disc, origin + o.axis_length * axis, 1 + k, colours[k]));
  }
  visualization_msgs::Marker text;
  text.id = 4;
  text.type = visualization_msgs::Marker::TEXT_VIEW_FACING;
  text.action = visualization_msgs::Marker::ADD;
  text.pose.position.x = origin.x();
  text.pose.position.y = origin.y();
  text.pose.position.z = origin.z() + 1.5 * o.axis_length;
  text.pose.orientation.w = 1.0;
  text.scale.z = 0.02;
  text.color.r = text.color.g = text.color.b = text.color.a = 1.0f;
  text.text = sigma_label(X);
  array.markers.push_back(text);
  for (visualization_msgs::Marker& m : array.markers) {
    m.header.frame_id = frame;
    m.header.stamp = stamp;
    m.ns = o.ns;
  }
  return array;
}

visualization_msgs::MarkerArray next_pose_markers(const Rig& rig, const std::optional<Eigen::Isometry3d>& T_base_effector,
                                                  const Eigen::Isometry3d& X, double depth, const std::string& label,
                                                  const std::string& frame, const ros::Time& stamp,
                                                  const NextPoseMarkerOptions& o) {
  visualization_msgs::MarkerArray array;
  visualization_msgs::Marker clear;
  clear.action = visualization_msgs::Marker::DELETEALL;
  array.markers.push_back(clear);
  if (T_base_effector) {
    const auto point = [](const Eigen::Vector3d& p) {
      geometry_msgs::Point q;
      q.x = p.x(), q.y = p.y(), q.z = p.z();
      return q;
    };
    const auto colour = [](float r, float g, float b, float a) {
      std_msgs::ColorRGBA c;
      c.r = r, c.g = g, c.b = b, c.a = a;
      return c;
    };
    visualization_msgs::Marker axes;
    axes.id = 0;
    axes.type = visualization_msgs::Marker::LINE_LIST;
    axes.pose.orientation.w = 1.0;
    axes.scale.x = 0.006;
    axes.color = colour(1, 1, 1, 0.7f);
    const Eigen::Vector3d origin = T_base_effector->translation();
    for (int k = 0; k < 3; ++k) {
      axes.points.push_back(point(origin));
      axes.points.push_back(point(origin + o.axis_length * T_base_effector->linear().col(k)));
      const std_msgs::ColorRGBA c = colour(k == 0, k == 1, k == 2, 0.7f);
      axes.colors.insert(axes.colors.end(), {c, c});
    }
    array.markers.push_back(axes);

    // Apex at the camera, four edges to the corners of the image at `depth` (z forward,
    // x right, y down: the optical frame), and that rectangle.
    const Eigen::Isometry3d camera = rig.camera_parent_in_base(*T_base_effector) * X;
    const double half_width = depth * std::tan(0.5 * o.horizontal_fov), half_height = depth * std::tan(0.5 * o.vertical_fov);
    std::array<Eigen::Vector3d, 4> corners;
    const std::array<std::array<double, 2>, 4> signs = {{{-1, -1}, {1, -1}, {1, 1}, {-1, 1}}};
    for (int k = 0; k < 4; ++k) {
      corners[k] = camera * Eigen::Vector3d(signs[k][0] * half_width, signs[k][1] * half_height, depth);
    }
    visualization_msgs::Marker frustum = axes;
    frustum.id = 1;
    frustum.scale.x = 0.003;
    frustum.color = colour(0.3f, 0.8f, 1.0f, 0.8f);
    frustum.points.clear();
    frustum.colors.clear();
    for (int k = 0; k < 4; ++k) {
      frustum.points.insert(frustum.points.end(), {point(camera.translation()), point(corners[k])});
      frustum.points.insert(frustum.points.end(), {point(corners[k]), point(corners[(k + 1) % 4])});
    }
    array.markers.push_back(frustum);

    visualization_msgs::Marker text;
    text.id = 2;
    text.type = visualization_msgs::Marker::TEXT_VIEW_FACING;
    text.pose = conversions::to_pose_msg(Eigen::Isometry3d(Eigen::Translation3d(origin + Eigen::Vector3d(0, 0, 1.3 * o.axis_length))));
    text.scale.z = 0.03;
    text.color = colour(0.3f, 0.8f, 1.0f, 1.0f);
    text.text = label;
    array.markers.push_back(text);
  }
  for (visualization_msgs::Marker& m : array.markers) {
    m.header.frame_id = frame;
    m.header.stamp = stamp;
    m.ns = o.ns;
    if (m.action != visualization_msgs::Marker::DELETEALL) m.action = visualization_msgs::Marker::ADD;
  }
  return array;
}

}  // namespace handeye
