// From a detection message to a stamp-matched observation: shared by the node
// (tf2_ros::Buffer, filled live) and the bag replay (tf2::BufferCore, filled
// from the bag), so both take and refuse exactly the same samples.
#pragma once

#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <geometry_msgs/TransformStamped.h>
#include <tf2/buffer_core.h>

#include <memory>
#include <optional>
#include <string>

#include "handeye_covariance/core/measurements.h"
#include "handeye_covariance/ros/messages.h"

namespace handeye {

/// The pattern pose as a detector reported it, with its covariance: both in
/// `frame`, and they move together (make_observation).
struct Detection {
  ros::Time stamp;
  std::string frame;  // empty: the camera frame
  geometry_msgs::Pose pose;
  std::optional<Matrix6d> covariance;  // the full 6x6, ROS order, when the detector sent a non-zero one
  std::shared_ptr<const TargetCorners> corners;  // the corners behind the pose, when the detector sent them
  std::string corners_problem;  // why the corners it sent were dropped (conversions::to_corners); the pose is kept
};

/// How a sample's corners name their image: "image at 12.345 s" (its stamp).
std::string image_at(const ros::Time& stamp);

/// Why a detection gave no observation: `kind` is short and stable (for counts),
/// `message` is the full reason with the fix.
struct Refusal {
  std::string kind;
  std::string message;
};

/// The detection of the configured pattern (`tag_ids`, or the lone detection
/// when tag_ids is empty), or a refusal; nothing at all for an empty message.
/// Corners that do not fit together (conversions::to_corners) are dropped, the
/// pose kept, and Detection::corners_problem says why.
std::optional<Detection> select_detection(const TagDetectionArray& msg, const std::vector<int>& tag_ids,
                                          std::optional<Refusal>& refusal);
Detection detection_of(const geometry_msgs::PoseWithCovarianceStamped& msg);
Detection detection_of(const geometry_msgs::PoseStamped& msg);
Detection detection_of(const geometry_msgs::TransformStamped& camera_to_pattern);

/// Pairs the detection with T_base_effector looked up in `tf` AT THE DETECTION'S
/// STAMP (the caller waits for TF first if it is filled live). A detection in
/// another frame of the same camera (camera_link for camera_optical_frame) is
/// moved into the camera frame, its covariance with it (the adjoint of the
/// frame change, through compose()); its corners are then dropped, as they
/// belong to the detector's camera frame (`corners_dropped` says so, as it says
/// why unusable corners were).
struct ObservationResult {
  std::optional<Observation> observation;
  std::optional<Refusal> refusal;
  std::string corners_dropped;  // why the observation has no corners although the detection had them
};
ObservationResult make_observation(const tf2::BufferCore& tf, const Rig& rig, const Detection& detection);

/// Where X goes in TF. A TF frame has one parent, and a camera driver already
/// publishes its own tree (camera_link -> camera_optical_frame), so X is attached
/// at that tree's root: the edge <X's parent> -> root with X * T_camera_root.
/// `published_root` is the root of an earlier call (its edge is ours and is
/// replaced). When the camera is already connected to X's parent by another TF
/// (a URDF mount), nothing may be published: `refusal` says why.
struct CameraTfEdge {
  std::string parent, child;
  Eigen::Isometry3d transform = Eigen::Isometry3d::Identity();
  std::string refusal;  // non-empty: publish nothing
};
CameraTfEdge camera_tf_edge(const tf2::BufferCore& tf, const Rig& rig, const Eigen::Isometry3d& X,
                            const std::string& published_root);

}  // namespace handeye
