#include "handeye_covariance/ros/bag.h"

#include <algorithm>
#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <rosbag/bag.h>
#include <rosbag/exceptions.h>
#include <rosbag/view.h>
#include <tf2/buffer_core.h>
#include <tf2_msgs/TFMessage.h>

#include <set>

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/ros/msg_conversion.h"
#include "handeye_covariance/ros/observations.h"

namespace handeye {

namespace {

geometry_msgs::TransformStamped transform(const ros::Time& stamp, const std::string& parent, const std::string& child,
                                          const Eigen::Isometry3d& T) {
  geometry_msgs::TransformStamped tf;
  tf.header.stamp = stamp;
  tf.header.frame_id = parent;
  tf.child_frame_id = child;
  tf.transform = conversions::to_transform_msg(T);
  return tf;
}

}  // namespace

SimulatedBag write_simulated_bag(const std::string& path, const BagSimulationOptions& o) {
  Rng rng(o.seed);
  SimulatedBag result;
  result.X = typical_X(o.setup);
  result.frames = SessionConfig{}.rig.frames;
  const FrameNames& f = result.frames;
  const RigTrajectory trajectory = make_rig_trajectory(rng, o.setup, result.X, o.poses, o.pause, o.move);
  result.duration = trajectory.duration();

  PoseNoise noise;  // in the camera frame (the parent of T_camera_pattern)
  const double lateral = o.lateral_noise_mm * 1e-3, depth = o.depth_noise_mm * 1e-3;
  const double tilt = o.tilt_noise_deg * M_PI / 180, roll = o.roll_noise_deg * M_PI / 180;
  noise.translation = Eigen::Vector3d(lateral * lateral, lateral * lateral, depth * depth).asDiagonal();
  noise.rotation = Eigen::Vector3d(tilt * tilt, tilt * tilt, roll * roll).asDiagonal();

  rosbag::Bag bag;
  try {
    bag.open(path, rosbag::bagmode::Write);
  } catch (const rosbag::BagException& e) {
    throw HandEyeError(ErrorCode::IoError, std::string("cannot create the bag: ") + e.what(), path,
                       "check that the directory exists and is writable");
  }
  const ros::Time start(o.start_time);
  // A real chain: base_link -> shoulder (a yaw joint) -> flange, and a static flange -> tool0.
  const Eigen::Isometry3d flange_T_tool = se3::make_pose(so3::exp(Eigen::Vector3d(0, 0, 0.3)), Eigen::Vector3d(0, 0, 0.12));
  if (o.robot_tf) {
    tf2_msgs::TFMessage statics;
    statics.transforms.push_back(transform(start, "flange", f.effector, flange_T_tool));
    bag.write("/tf_static", start, statics);
  }
  const double span = result.duration + 1.0;
  for (double t = 0.0; o.robot_tf && t <= span; t += 1.0 / o.tf_rate) {
    const ros::Time stamp = start + ros::Duration(t);
    const Eigen::Isometry3d E = trajectory.effector_at(t);
    const Eigen::Isometry3d base_T_flange = E * flange_T_tool.inverse();
    const double yaw = std::atan2(base_T_flange.translation().y(), base_T_flange.translation().x());
    const Eigen::Isometry3d base_T_shoulder =
        se3::make_pose(so3::exp(Eigen::Vector3d(0, 0, yaw)), Eigen::Vector3d(0, 0, 0.35));
    tf2_msgs::TFMessage msg;
    msg.transforms.push_back(transform(stamp, f.base, "shoulder", base_T_shoulder));
    msg.transforms.push_back(transform(stamp, "shoulder", "flange", base_T_shoulder.inverse() * base_T_flange));
    bag.write("/tf", stamp, msg);
    ++result.tf_messages;
  }
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (double t = 0.0; o.detections && t <= span; t += 1.0 / o.detection_rate) {
    if (unit(rng) < o.dropout) continue;
    const ros::Time capture = start + ros::Duration(t);
    Eigen::Isometry3d P = perturb(rng, trajectory.pattern_at(t), noise);
    if (unit(rng) < o.wrong_detections) {
      P = P * se3::make_pose(so3::exp(Eigen::Vector3d(0.35, 0, 0)), Eigen::Vector3d::Zero());  // a flipped pose
      ++result.wrong_detections;
    }
    geometry_msgs::PoseWithCovarianceStamped pose;
    pose.header.stamp = capture;
    pose.header.frame_id = f.camera;
    pose.pose.pose = conversions::to_pose_msg(P);
    if (o.detection_covariance) {
      pose.pose.covariance = conversions::to_msg(PoseWithCovariance{P, noise.as_pose_covariance()}).covariance;
    }
    const double delay = o.latency + o.latency_jitter * (2.0 * unit(rng) - 1.0);
    const ros::Time received = capture + ros::Duration(std::max(0.0, delay));
    if (o.detection_type == "tags") {
      TagDetectionArray array;
      array.header = pose.header;
      TagDetection detection;
      detection.id = {0};
      detection.size = {0.1};
      detection.pose = pose;
      array.detections.push_back(detection);
      bag.write(o.detections_topic, received, array);
    } else if (o.detection_type == "pose_with_covariance") {
      bag.write(o.detections_topic, received, pose);
    } else if (o.detection_type == "pose") {
      geometry_msgs::PoseStamped plain;
      plain.header = pose.header;
      plain.pose = pose.pose.pose;
      bag.write(o.detections_topic, received, plain);
    } else {  // tf: camera -> pattern on /tf, as a TF-publishing detector does
      tf2_msgs::TFMessage msg;
      msg.transforms.push_back(transform(capture, f.camera, f.pattern, P));
      bag.write("/tf", received, msg);
    }
    ++result.detections;
  }
  bag.close();
  return result;
}

namespace {

HandEyeError no_data(const std::string& what, const std::string& path, const std::string& fix) {
  return HandEyeError(ErrorCode::NoData, what, path, fix);
}

}  // namespace

BagReplay replay_bag(const std::string& path, const SessionConfig& config, std::function<void(double)> progress) {
  SessionSettings settings = session_settings(config);
  settings.session_file.clear();  // a replay persists nothing
  CalibrationSession session(settings);
  return replay_bag(path, config, session, std::move(progress));
}

BagReplay replay_bag(const std::string& path, const SessionConfig& config, CalibrationSession& session,
                     std::function<void(double)> progress) {
  rosbag::Bag bag;
  try {
    bag.open(path, rosbag::bagmode::Read);
  } catch (const rosbag::BagException& e) {
    throw HandEyeError(ErrorCode::IoError, std::string("cannot read the bag: ") + e.what(), path,
                       "check the path; a truncated bag (a recording that was killed) can often be repaired "
                       "with `rosbag reindex`");
  }
  BagReplay replay;
  try {
    rosbag::View everything(bag);
    std::set<std::string> topics;
    for (const rosbag::ConnectionInfo* c : everything.getConnections()) topics.insert(c->topic);
    replay.duration = (everything.getEndTime() - everything.getBeginTime()).toSec();
    if (replay.duration < 5.0) progress = nullptr;  // short bags need no progress bar

    // Pass 1: every transform of the bag into an offline buffer covering the whole bag.
    tf2::BufferCore tf(ros::Duration(replay.duration + 60.0));
    rosbag::View tf_view(bag, rosbag::TopicQuery(std::vector<std::string>{"/tf", "/tf_static"}));
    std::vector<geometry_msgs::TransformStamped> pattern_transforms;  // detection_input: tf
    for (const rosbag::MessageInstance& m : tf_view) {
      ++replay.messages[m.getTopic()];
      const tf2_msgs::TFMessage::ConstPtr msg = m.instantiate<tf2_msgs::TFMessage>();
      if (!msg) continue;
      const bool is_static = m.getTopic() == "/tf_static";
      for (const geometry_msgs::TransformStamped& t : msg->transforms) {
        tf.setTransform(t, "bag", is_static);
        if (t.header.frame_id == config.rig.frames.camera && t.child_frame_id == config.rig.frames.pattern) {
          pattern_transforms.push_back(t);
        }
      }
    }

    // Pass 2: the detections, in stamp order, through the node's session.
    const auto feed = [&](const Detection& detection) {
      const ObservationResult r = make_observation(tf, config.rig, detection);
      if (r.refusal) {
        ++replay.refusals[r.refusal->kind];
        replay.refusal_examples.emplace(r.refusal->kind, r.refusal->message);
        return;
      }
      ++replay.observations;
      const std::optional<SessionEvent> outcome = session.observe(*r.observation);
      if (outcome && !outcome->success) {
        ++replay.refusals["too_close"];
        replay.refusal_examples.emplace("too_close", outcome->message);
      }
    };
    if (config.detection_input == "tf") {
      replay.detections = static_cast<int>(pattern_transforms.size());
      for (std::size_t i = 0; i < pattern_transforms.size(); ++i) {
        feed(detection_of(pattern_transforms[i]));
        if (progress) progress(static_cast<double>(i + 1) / pattern_transforms.size());
      }
    } else {
      if (!topics.count(config.detections_topic)) {
        std::string list;
        for (const std::string& t : topics) list += (list.empty() ? "" : ", ") + t;
        throw no_data("the bag has no topic `" + config.detections_topic + "`; its topics are: " + list, path,
                      "set detections_topic (in --config) to the topic the detector published");
      }
      rosbag::View view(bag, rosbag::TopicQuery(config.detections_topic));
      const double total = std::max<double>(1.0, view.size());
      std::vector<Detection> detections;
      for (const rosbag::MessageInstance& m : view) {
        ++replay.messages[m.getTopic()];
        std::optional<Detection> detection;
        if (const auto tags = m.instantiate<TagDetectionArray>()) {
          std::optional<Refusal> refusal;
          detection = select_detection(*tags, config.tag_ids, refusal);
          if (refusal) ++replay.refusals[refusal->kind], replay.refusal_examples.emplace(refusal->kind, refusal->message);
        } else if (const auto with_covariance = m.instantiate<geometry_msgs::PoseWithCovarianceStamped>()) {
          detection = detection_of(*with_covariance);
        } else if (const auto plain = m.instantiate<geometry_msgs::PoseStamped>()) {
          detection = detection_of(*plain);
        } else {
          throw no_data("`" + config.detections_topic + "` carries " + m.getDataType() +
                            ", not a TagDetectionArray, PoseWithCovarianceStamped or PoseStamped",
                        path, "point detections_topic at the detector's output");
        }
        if (detection) {
          if (!detections.empty() && detection->stamp < detections.back().stamp) ++replay.stamps_went_back;
          detections.push_back(*detection);
        }
        if (progress && replay.messages[m.getTopic()] % 50 == 0) progress(0.5 * replay.messages[m.getTopic()] / total);
      }
      // The bag is ordered by receive time; the sampler needs capture (stamp) order.
      // A stamp seen twice is the same image (a looping or duplicated recording): used once.
      std::stable_sort(detections.begin(), detections.end(),
                       [](const Detection& a, const Detection& b) { return a.stamp < b.stamp; });
      const auto repeated = std::unique(detections.begin(), detections.end(),
                                        [](const Detection& a, const Detection& b) { return a.stamp == b.stamp; });
      replay.repeated_stamps = static_cast<int>(detections.end() - repeated);
      detections.erase(repeated, detections.end());
      replay.detections = static_cast<int>(detections.size());
      for (std::size_t i = 0; i < detections.size(); ++i) {
        feed(detections[i]);
        if (progress && (i % 50 == 0 || i + 1 == detections.size())) progress(0.5 + 0.5 * (i + 1) / detections.size());
      }
    }
    replay.samples = session.sample_set();
  } catch (const rosbag::BagException& e) {
    throw HandEyeError(ErrorCode::IoError, std::string("the bag is corrupt or truncated: ") + e.what(), path,
                       "try `rosbag reindex` on a copy of it, or record again");
  }
  if (replay.detections == 0 && !replay.refusals.empty()) {  // messages came, but none held the pattern
    const auto most = std::max_element(replay.refusals.begin(), replay.refusals.end(),
                                       [](const auto& a, const auto& b) { return a.second < b.second; });
    throw no_data("none of the " + std::to_string(replay.messages[config.detections_topic]) + " messages on `" +
                      config.detections_topic + "` held the pattern; " + std::to_string(most->second) +
                      " were refused: " + replay.refusal_examples[most->first],
                  path, "set tag_ids (in --config) to the pattern's tag id(s), or [] to take a lone detection");
  }
  if (replay.detections == 0) {
    throw no_data("the bag has no detections on `" +
                      (config.detection_input == "tf" ? config.rig.frames.camera + " -> " + config.rig.frames.pattern + " (TF)"
                                                      : config.detections_topic) +
                      "`",
                  path, "check that the detector ran while recording, and the detection_input / topic settings");
  }
  if (replay.samples.samples.empty()) {
    std::string why;
    int most = 0;
    for (const auto& [kind, count] : replay.refusals) {
      if (count > most) most = count, why = replay.refusal_examples[kind];
    }
    throw no_data("no sample could be taken from " + std::to_string(replay.detections) + " detections" +
                      (why.empty() ? " (the robot never stood still for still_window)" : "; most were refused: " + why),
                  path, "fix the cause above; check the frame names and still_window in --config");
  }
  return replay;
}

}  // namespace handeye
