#include "handeye_covariance/ros/static_edges.h"

#include <ros/console.h>
#include <ros/time.h>

#include <vector>

#include "handeye_covariance/ros/msg_conversion.h"
#include "handeye_covariance/ros/observations.h"

namespace handeye {

namespace {
bool same_edge(const geometry_msgs::TransformStamped& a, const geometry_msgs::TransformStamped& b) {
  const auto& s = a.transform;
  const auto& t = b.transform;
  return a.header.frame_id == b.header.frame_id && a.child_frame_id == b.child_frame_id &&
         s.translation.x == t.translation.x && s.translation.y == t.translation.y &&
         s.translation.z == t.translation.z && s.rotation.x == t.rotation.x && s.rotation.y == t.rotation.y &&
         s.rotation.z == t.rotation.z && s.rotation.w == t.rotation.w;
}
}  // namespace

std::string StaticEdges::publish_camera(const tf2::BufferCore& tf, const Rig& rig, const Eigen::Isometry3d& X) {
  const CameraTfEdge edge = camera_tf_edge(tf, rig, X, camera_root_);
  if (!edge.refusal.empty()) {  // an earlier X must not stay in TF while the topic and the file say another
    if (!camera_root_.empty() && edges_.erase(camera_root_) > 0) send();
    camera_root_.clear();
    if (edge.refusal != refusal_) ROS_WARN("%s", edge.refusal.c_str());  // once, not on every refresh
    refusal_ = edge.refusal;
    return edge.refusal;
  }
  const geometry_msgs::TransformStamped stamped =
      conversions::to_transform_stamped(edge.transform, edge.parent, edge.child, ros::Time::now());
  bool changed = false;
  if (!camera_root_.empty() && edge.child != camera_root_) changed = edges_.erase(camera_root_) > 0;  // the old edge goes
  changed = store(stamped) || changed;
  camera_root_ = edge.child;
  if (changed) send();
  const std::string published = edge.parent + " -> " + edge.child;
  if (!refusal_.empty()) ROS_INFO("published %s", published.c_str());
  refusal_.clear();
  return published;
}

void StaticEdges::publish(const geometry_msgs::TransformStamped& edge) {
  if (store(edge)) send();
}

bool StaticEdges::store(const geometry_msgs::TransformStamped& edge) {
  const auto old = edges_.find(edge.child_frame_id);
  if (old != edges_.end() && same_edge(old->second, edge)) return false;
  edges_[edge.child_frame_id] = edge;
  return true;
}

void StaticEdges::send() {
  broadcaster_ = std::make_unique<tf2_ros::StaticTransformBroadcaster>();
  std::vector<geometry_msgs::TransformStamped> edges;
  for (const auto& entry : edges_) edges.push_back(entry.second);
  broadcaster_->sendTransform(edges);
}

}  // namespace handeye
