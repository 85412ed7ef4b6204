#include "handeye_covariance/ros/observations.h"

#include <tf2/exceptions.h>

#include <cmath>
#include <set>

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/core/validation.h"
#include "handeye_covariance/ros/msg_conversion.h"

namespace handeye {

std::string image_at(const ros::Time& stamp) { return "image at " + number_text(stamp.toSec(), 12) + " s"; }

std::optional<Detection> select_detection(const TagDetectionArray& msg, const std::vector<int>& tag_ids,
                                          std::optional<Refusal>& refusal) {
  refusal.reset();
  if (msg.detections.empty()) return std::nullopt;
  const std::set<int> wanted(tag_ids.begin(), tag_ids.end());
  for (const TagDetection& d : msg.detections) {
    if (wanted.empty() ? msg.detections.size() == 1 : std::set<int>(d.id.begin(), d.id.end()) == wanted) {
      Detection detection;
      detection.stamp = d.pose.header.stamp.isZero() ? msg.header.stamp : d.pose.header.stamp;
      detection.frame = d.pose.header.frame_id.empty() ? msg.header.frame_id : d.pose.header.frame_id;
      detection.pose = d.pose.pose.pose;
      detection.covariance = conversions::covariance_if_nonzero(d.pose.pose.covariance);
      try {
        if (std::shared_ptr<TargetCorners> corners = conversions::to_corners(d)) {
          corners->source = image_at(detection.stamp);
          detection.corners = std::move(corners);
        }
      } catch (const HandEyeError& e) {
        detection.corners_problem = std::string("a detection's corners are unusable, the pose is used without them: ") +
                                    e.what();
      }
      return detection;
    }
  }
  refusal = wanted.empty()
                ? Refusal{"several_tags", "several detections in one message and tag_ids is empty; set tag_ids to the pattern's id(s)"}
                : Refusal{"other_tags", "no detection with the configured tag_ids in this message (a different tag is in view)"};
  return std::nullopt;
}

Detection detection_of(const geometry_msgs::PoseWithCovarianceStamped& msg) {
  return {msg.header.stamp, msg.header.frame_id, msg.pose.pose, conversions::covariance_if_nonzero(msg.pose.covariance), {}, {}};
}

Detection detection_of(const geometry_msgs::PoseStamped& msg) {
  return {msg.header.stamp, msg.header.frame_id, msg.pose, std::nullopt, {}, {}};
}

Detection detection_of(const geometry_msgs::TransformStamped& camera_to_pattern) {
  Detection d;
  d.stamp = camera_to_pattern.header.stamp;
  d.frame = camera_to_pattern.header.frame_id;
  d.pose.position.x = camera_to_pattern.transform.translation.x;
  d.pose.position.y = camera_to_pattern.transform.translation.y;
  d.pose.position.z = camera_to_pattern.transform.translation.z;
  d.pose.orientation = camera_to_pattern.transform.rotation;
  return d;
}

ObservationResult make_observation(const tf2::BufferCore& tf, const Rig& rig, const Detection& detection) {
  ObservationResult result;
  if (detection.stamp.isZero()) {
    result.refusal = Refusal{"zero_stamp", "a detection has a zero stamp; the detector must stamp with the image time"};
    return result;
  }
  const double norm = conversions::quaternion_norm(detection.pose.orientation);
  if (!std::isfinite(norm) || std::abs(norm - 1.0) > 1e-3) {
    result.refusal = Refusal{"bad_quaternion", "a detection's quaternion has norm " + number_text(norm) +
                                                   "; expected a unit quaternion"};
    return result;
  }
  if (detection.covariance) {
    try {  // a sample with a NaN or negative variance would poison every later solve
      check_covariance(PoseNoise::from_pose_covariance(*detection.covariance), "detection covariance");  // names the block
      check_covariance(*detection.covariance, "detection covariance");  // and the 6x6's symmetry
    } catch (const HandEyeError& e) {
      result.refusal = Refusal{"bad_covariance", std::string("a detection's covariance is unusable: ") + e.what() +
                                                     ". Fix the detector, or send an all-zero covariance to use the "
                                                     "configured noise"};
      return result;
    }
  }
  if (!std::isfinite(detection.pose.position.x) || !std::isfinite(detection.pose.position.y) ||
      !std::isfinite(detection.pose.position.z)) {
    result.refusal = Refusal{"bad_position", "a detection's position is NaN or Inf"};
    return result;
  }
  Observation o;
  o.stamp = detection.stamp.toSec();
  try {
    // The robot pose at the detection's stamp; never the latest (Time(0)).
    o.T_base_effector = conversions::to_eigen(
        tf.lookupTransform(rig.frames.base, rig.frames.effector, detection.stamp).transform);
  } catch (const tf2::TransformException& e) {
    result.refusal = Refusal{"no_robot_tf", "no TF " + rig.frames.base + " -> " + rig.frames.effector +
                                                " at the detection stamp " + std::to_string(detection.stamp.toSec()) +
                                                ": " + e.what() +
                                                ". Is the robot state publisher running, and are the clocks in sync?"};
    return result;
  }
  PoseWithCovariance pattern{conversions::to_eigen(detection.pose), detection.covariance.value_or(Matrix6d::Zero())};
  if (!detection.frame.empty() && detection.frame != rig.frames.camera) {
    try {  // a detection in another frame of the same camera: pose and covariance move together
      const Eigen::Isometry3d T_camera_frame = conversions::to_eigen(
          tf.lookupTransform(rig.frames.camera, detection.frame, detection.stamp).transform);
      pattern = compose(PoseWithCovariance{T_camera_frame, Matrix6d::Zero()}, pattern);  // the frame change is exact
    } catch (const tf2::TransformException& e) {
      result.refusal = Refusal{"detection_frame", "the detection is in frame `" + detection.frame + "`, not `" +
                                                      rig.frames.camera + "`, and TF cannot relate them: " +
                                                      e.what() + ". Set tracking_base_frame to the detector's frame"};
      return result;
    }
  }
  o.T_camera_pattern = pattern.pose;
  if (detection.covariance) o.pattern_noise = PoseNoise::from_pose_covariance(pattern.covariance);
  if (!detection.corners_problem.empty()) {
    result.corners_dropped = detection.corners_problem;
  } else if (detection.corners && !detection.frame.empty() && detection.frame != rig.frames.camera) {
    result.corners_dropped = "the detection's corners are in frame `" + detection.frame + "`'s image, not `" +
                             rig.frames.camera + "`'s; set tracking_base_frame to `" + detection.frame +
                             "` for method corners";
  } else {
    o.corners = detection.corners;
  }
  result.observation = o;
  return result;
}

CameraTfEdge camera_tf_edge(const tf2::BufferCore& tf, const Rig& rig, const Eigen::Isometry3d& X,
                            const std::string& published_root) {
  CameraTfEdge edge;
  edge.parent = rig.camera_parent_frame();
  const std::string& camera = rig.frames.camera;
  // Our edge from an earlier call counts only while it still hangs from X's parent
  // (a driver tree that arrived since re-parents that frame, and X moves above it).
  std::string up;
  const bool still_ours = !published_root.empty() && tf._getParent(published_root, ros::Time(0), up) && up == edge.parent;
  std::string root = camera;
  for (int depth = 0;; ++depth) {
    if (depth > 1000) {  // tf2's own limit on a chain; a loop in the tree would never end
      edge.refusal = "no TF published: the TF tree above " + camera + " has a loop (two publishers disagree)";
      return edge;
    }
    if (still_ours && root == published_root) break;
    if (!tf._getParent(root, ros::Time(0), up) || up == edge.parent) break;
    root = up;
  }
  const bool ours = still_ours && root == published_root;  // below our own edge from before
  if (!ours && tf.canTransform(edge.parent, camera, ros::Time(0))) {
    edge.refusal = "no TF published: " + camera + " is already connected to " + edge.parent +
                   " by another TF (a URDF mount?); remove that link, or set publish_tf false and use the result file";
    return edge;
  }
  Eigen::Isometry3d T_camera_root = Eigen::Isometry3d::Identity();
  if (root != camera) {
    try {
      T_camera_root = conversions::to_eigen(tf.lookupTransform(camera, root, ros::Time(0)).transform);
    } catch (const tf2::TransformException& e) {
      edge.refusal = std::string("no TF published: ") + e.what();
      return edge;
    }
  }
  edge.child = root;
  edge.transform = X * T_camera_root;
  return edge;
}

}  // namespace handeye
