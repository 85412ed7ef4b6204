// The static TF edges of a node that publishes a calibration (the calibration
// node, calibration_publisher): X hung at the root of the camera's own tree
// (camera_tf_edge), and other edges (the pattern pose Y).
#pragma once

#include <geometry_msgs/TransformStamped.h>
#include <tf2/buffer_core.h>
#include <tf2_ros/static_transform_broadcaster.h>

#include <Eigen/Geometry>
#include <map>
#include <memory>
#include <string>

#include "handeye_covariance/core/rig.h"

namespace handeye {

/// One broadcaster sends every edge: two in one node would share the latched
/// /tf_static, and only the last one's edges would stay latched. It is remade
/// when an edge goes, so a late listener no longer gets the old edge. Not
/// thread-safe: the owner serialises the calls.
class StaticEdges {
 public:
  /// X's edge at the current root of the camera's tree (a camera driver that
  /// starts late moves it up to its own root). Sends only when the edge changed.
  /// Returns the edge ("tool0 -> camera_link"), or why nothing was published
  /// (camera_tf_edge's refusal, starting "no TF"; an earlier X's edge is then withdrawn).
  /// A refusal is logged when it is new, and the edge when it follows one.
  std::string publish_camera(const tf2::BufferCore& tf, const Rig& rig, const Eigen::Isometry3d& X);
  /// Any other edge, keyed by its child frame; sends when it changed.
  void publish(const geometry_msgs::TransformStamped& edge);

 private:
  /// Stores the edge; false when the same edge was already sent.
  bool store(const geometry_msgs::TransformStamped& edge);
  void send();
  std::map<std::string, geometry_msgs::TransformStamped> edges_;
  std::unique_ptr<tf2_ros::StaticTransformBroadcaster> broadcaster_;
  std::string camera_root_;  // the child of X's edge, once published
  std::string refusal_;      // the last refusal, while it lasts
};

}  // namespace handeye
