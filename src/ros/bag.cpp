#include "handeye_covariance/ros/bag.h"

#include <algorithm>
#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <rosbag/bag.h>
#include <rosbag/exceptions.h>
#include <rosbag/view.h>
#include <tf2/buffer_core.h>
#include <tf2_msgs/TFMessage.h>

#include <cv_bridge/cv_bridge.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/image_encodings.h>

#include <opencv2/imgcodecs.hpp>
#include <set>

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/core/units.h"
#include "handeye_covariance/images/pooled_detector.h"
#include "handeye_covariance/io/yaml_io.h"
#include "handeye_covariance/corners/corner_calibration.h"
#include "handeye_covariance/ros/msg_conversion.h"
#include "handeye_covariance/ros/observations.h"
#include "handeye_covariance/simulation/pattern_renderer.h"

namespace handeye {

SimulatedBag write_simulated_bag(const std::string& path, const BagSimulationOptions& o) {
  Rng rng(o.seed);
  SimulatedBag result;
  result.X = typical_X(o.setup);
  result.frames = SessionConfig{}.rig.frames;
  const FrameNames& f = result.frames;
  RigTrajectory trajectory = make_rig_trajectory(rng, o.setup, result.X, o.poses, o.pause, o.move);
  result.duration = trajectory.duration();
  const bool images = o.detection_type == "images";
  if (images && !o.target) {
    throw HandEyeError(ErrorCode::MissingKey, "a bag of images needs the target to draw", "sim",
                       "give --target FILE (config/targets/)");
  }
  std::optional<PatternRenderer> renderer;
  if (images) {
    trajectory.look_at_face(target_face(*o.target));
    renderer.emplace(*o.target, simulated_camera());
  }

  PoseNoise noise;  // in the camera frame (the parent of T_camera_pattern)
  const double lateral = metres(o.lateral_noise_mm), depth = metres(o.depth_noise_mm);
  const double tilt = radians(o.tilt_noise_deg), roll = radians(o.roll_noise_deg);
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
    statics.transforms.push_back(conversions::to_transform_stamped(flange_T_tool, "flange", f.effector, start));
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
    msg.transforms.push_back(conversions::to_transform_stamped(base_T_shoulder, f.base, "shoulder", stamp));
    msg.transforms.push_back(conversions::to_transform_stamped(base_T_shoulder.inverse() * base_T_flange, "shoulder", "flange", stamp));
    bag.write("/tf", stamp, msg);
    ++result.tf_messages;
  }
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (double t = 0.0; o.detections && t <= span; t += 1.0 / o.detection_rate) {
    if (images) {  // what the camera sees, and its CameraInfo, stamped with the capture time
      const ros::Time capture = start + ros::Duration(t);
      const cv::Mat gray = renderer->render(trajectory.pattern_at(t), rng);
      std_msgs::Header header;
      header.stamp = capture;
      header.frame_id = f.camera;
      sensor_msgs::CameraInfo info = conversions::to_camera_info(renderer->camera());
      info.header = header;
      const ros::Time received = capture + ros::Duration(o.latency);
      if (o.compressed) {
        sensor_msgs::CompressedImage msg;
        msg.header = header;
        msg.format = "mono8; png compressed";
        cv::imencode(".png", gray, msg.data);
        bag.write(o.image_topic + "/compressed", received, msg);
      } else {
        bag.write(o.image_topic, received, cv_bridge::CvImage(header, sensor_msgs::image_encodings::MONO8, gray).toImageMsg());
      }
      bag.write(o.camera_info_topic, received, info);
      ++result.detections;
      continue;
    }
    if (unit(rng) < o.dropout) continue;
    const ros::Time capture = start + ros::Duration(t);
    Eigen::Isometry3d P = perturb(rng, trajectory.pattern_at(t), noise);
    if (unit(rng) < o.wrong_detections) {
      P = P * se3::make_pose(so3::exp(Eigen::Vector3d(0.35, 0, 0)), Eigen::Vector3d::Zero());  // a flipped pose
      ++result.wrong_detections;
    }
    // Without detection_covariance, zeros: what apriltag_ros and most detectors send.
    const geometry_msgs::PoseWithCovarianceStamped pose = conversions::to_stamped_msg(
        {P, o.detection_covariance ? noise.as_pose_covariance() : Matrix6d::Zero()}, f.camera, capture);
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
      msg.transforms.push_back(conversions::to_transform_stamped(P, f.camera, f.pattern, capture));
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

// Of the progress bar, the share of detecting in a bag's images (the rest feeds the session).
constexpr double kImageReadShare = 0.8;

struct ImageTopics {
  std::string image, info;
  bool compressed = false;
};

/// Where the images are when the detections are to come from them: the
/// configured image topic, or, when the bag has no detections topic, its one
/// image topic (raw or compressed); and their CameraInfo topic. Nothing when the
/// bag holds detections.
std::optional<ImageTopics> image_topics(rosbag::View& everything, const SessionConfig& config,
                                        const std::string& path) {
  std::map<std::string, std::string> type_of;
  for (const rosbag::ConnectionInfo* c : everything.getConnections()) type_of[c->topic] = c->datatype;
  const auto list = [&](const std::string& type) {
    std::vector<std::string> topics;
    for (const auto& [topic, t] : type_of)
      if (t == type) topics.push_back(topic);
    return topics;
  };
  const auto joined = [](const std::vector<std::string>& topics) {
    std::string text;
    for (const std::string& t : topics) text += (text.empty() ? "" : ", ") + t;
    return text.empty() ? std::string("none") : text;
  };
  ImageTopics topics;
  if (!config.image_topic.empty()) {
    topics.image = config.image_topic;
  } else {
    if (type_of.count(config.detections_topic)) return std::nullopt;
    std::vector<std::string> images = list("sensor_msgs/Image");
    for (const std::string& t : list("sensor_msgs/CompressedImage")) images.push_back(t);
    if (images.empty()) return std::nullopt;
    if (images.size() > 1) {
      throw no_data("the bag has no `" + config.detections_topic + "` but several image topics: " + joined(images), path,
                    "choose one with image_topic (in --config) or --image-topic");
    }
    topics.image = images.front();
  }
  const auto type = type_of.find(topics.image);
  if (type == type_of.end() || (type->second != "sensor_msgs/Image" && type->second != "sensor_msgs/CompressedImage")) {
    throw no_data("`" + topics.image + "` is " + (type == type_of.end() ? "not in the bag" : "a " + type->second) +
                      "; the bag's image topics are: " +
                      joined(list("sensor_msgs/Image")) + " (raw), " + joined(list("sensor_msgs/CompressedImage")) +
                      " (compressed)",
                  path, "set image_topic to one of them");
  }
  topics.compressed = type->second == "sensor_msgs/CompressedImage";
  if (!config.camera_info_topic.empty()) {
    topics.info = config.camera_info_topic;
  } else {
    std::string base = topics.image;  // /camera/image_raw/compressed -> /camera/camera_info
    if (topics.compressed && base.size() > 11 && base.compare(base.size() - 11, 11, "/compressed") == 0) {
      base.resize(base.size() - 11);
    }
    const std::string beside = base.substr(0, base.find_last_of('/')) + "/camera_info";
    const std::vector<std::string> infos = list("sensor_msgs/CameraInfo");
    if (type_of.count(beside)) topics.info = beside;
    else if (infos.size() == 1) topics.info = infos.front();
  }
  if (topics.info.empty() || !type_of.count(topics.info) || type_of[topics.info] != "sensor_msgs/CameraInfo") {
    throw no_data("no CameraInfo for `" + topics.image + "` (the bag's CameraInfo topics: " +
                      joined(list("sensor_msgs/CameraInfo")) + ")",
                  path, "record the camera's camera_info with its images, or set camera_info_topic");
  }
  return topics;
}

/// The target's pose in every image of the topic, through the target detector,
/// each with its covariance under the pixel sigma pooled over all the images.
std::vector<Detection> detect_bag_images(rosbag::Bag& bag, const ImageTopics& topics, const Target& target,
                                         const std::string& path, BagReplay& replay,
                                         const std::function<void(double)>& progress) {
  std::vector<sensor_msgs::CameraInfo> infos;
  for (const rosbag::MessageInstance& m : rosbag::View(bag, rosbag::TopicQuery(topics.info))) {
    ++replay.messages[m.getTopic()];
    if (const auto info = m.instantiate<sensor_msgs::CameraInfo>()) infos.push_back(*info);
  }
  if (infos.empty()) throw no_data("`" + topics.info + "` holds no CameraInfo", path, "record the camera_info topic");
  std::stable_sort(infos.begin(), infos.end(), [](const auto& a, const auto& b) { return a.header.stamp < b.header.stamp; });
  std::optional<std::size_t> camera_of;  // the info the current camera model is from
  CameraModel camera;

  images::PooledDetector detector(target);
  std::vector<std::pair<std::size_t, Detection>> found;  // detector frame -> detection (pose filled after pooling)
  rosbag::View view(bag, rosbag::TopicQuery(topics.image));
  const double total = std::max<double>(1.0, view.size());
  for (const rosbag::MessageInstance& m : view) {
    ++replay.messages[m.getTopic()];
    ++replay.images;
    cv::Mat gray;
    std_msgs::Header header;
    if (topics.compressed) {
      const auto msg = m.instantiate<sensor_msgs::CompressedImage>();
      if (!msg) continue;
      header = msg->header;
      gray = cv::imdecode(msg->data, cv::IMREAD_GRAYSCALE);
    } else {
      const auto msg = m.instantiate<sensor_msgs::Image>();
      if (!msg) continue;
      header = msg->header;
      try {
        gray = cv_bridge::toCvCopy(msg, sensor_msgs::image_encodings::MONO8)->image;
      } catch (const cv_bridge::Exception& e) {
        throw no_data("cannot convert a `" + msg->encoding + "` image on `" + topics.image + "` to mono8: " + e.what(),
                      path, "record the images as mono8, bgr8 or rgb8");
      }
    }
    if (gray.empty()) {
      ++replay.refusals["unreadable_image"];
      replay.refusal_examples.emplace("unreadable_image", "an image on `" + topics.image + "` could not be decoded");
      continue;
    }
    // The CameraInfo of this image: the last one stamped at or before it.
    std::size_t i = 0;
    while (i + 1 < infos.size() && infos[i + 1].header.stamp <= header.stamp) ++i;
    if (camera_of != i) {
      camera = conversions::to_camera_model(infos[i]);  // throws a named error for an uncalibrated camera
      camera_of = i;
    }
    if (gray.cols != camera.width || gray.rows != camera.height) {
      throw no_data("an image on `" + topics.image + "` is " + std::to_string(gray.cols) + " x " +
                        std::to_string(gray.rows) + " but `" + topics.info + "` says " + std::to_string(camera.width) +
                        " x " + std::to_string(camera.height),
                    path, "set camera_info_topic to the info of these images");
    }
    const images::PooledDetector::Frame& frame = detector.add(gray, camera);
    if (frame.pose) {
      Detection d;
      d.stamp = header.stamp;
      d.frame = header.frame_id;
      d.corners = std::make_shared<const TargetCorners>(
          TargetCorners{camera, *frame.corners, image_at(header.stamp)});
      found.emplace_back(detector.size() - 1, d);
    } else {
      ++replay.refusals["no_target_pose"];
      replay.refusal_examples.emplace("no_target_pose", frame.why);
    }
    if (progress && replay.images % 10 == 0) progress(kImageReadShare * replay.images / total);
  }
  replay.pixel_sigma = detector.pixel_sigma();
  std::vector<Detection> detections;
  for (auto& [index, d] : found) {
    const std::optional<PatternPose> pose = detector.pooled(index);
    d.pose = conversions::to_pose_msg(pose->T_camera_pattern);
    d.covariance = pose->covariance;
    detections.push_back(d);
  }
  return detections;
}

}  // namespace

BagReplay replay_bag(const std::string& path, const SessionConfig& config, std::function<void(double)> progress) {
  SessionSettings settings = session_settings(config);
  settings.session_file.clear();  // a replay persists nothing
  settings.refine_corners = corner_refiner();  // method corners
  CalibrationSession session(settings);
  return replay_bag(path, config, session, std::move(progress));
}

// Over 150 lines: the bag's two passes (the transforms into one buffer, then the detections through the session) share the buffer, the view and the counts it reports.
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
      // Detections recorded, or made here from the bag's images.
      std::vector<Detection> detections;
      double read_share = 0.5;  // of the progress: reading (and detecting), then feeding the session
      if (const std::optional<ImageTopics> images = image_topics(everything, config, path)) {
        if (config.target_file.empty()) {
          throw no_data("the bag has images on `" + images->image + "` and no detections on `" +
                            config.detections_topic + "`, but no target to look for",
                        path, "give the target: --target FILE (config/targets/), or target_file in --config");
        }
        replay.image_topic = images->image;
        replay.camera_info_topic = images->info;
        read_share = kImageReadShare;
        detections = detect_bag_images(bag, *images, io::read_target(config.target_file), path, replay, progress);
      } else {
        if (!topics.count(config.detections_topic)) {
          std::string list;
          for (const std::string& t : topics) list += (list.empty() ? "" : ", ") + t;
          throw no_data("the bag has no topic `" + config.detections_topic + "`; its topics are: " + list, path,
                        "set detections_topic (in --config) to the topic the detector published");
        }
        rosbag::View view(bag, rosbag::TopicQuery(config.detections_topic));
        const double total = std::max<double>(1.0, view.size());
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
          } else if (m.getDataType() == ros::message_traits::DataType<TagDetectionArray>::value()) {
            throw no_data("`" + config.detections_topic + "` carries another version of " + m.getDataType() + " (md5 " +
                              m.getMD5Sum() + ", this build reads " +
                              ros::message_traits::MD5Sum<TagDetectionArray>::value() +
                              "): TagDetection gained the detection's corners",
                          path, "replay it with the package version that recorded it, or record the camera images and "
                                "give --target so that this version detects them");
          } else {
            throw no_data("`" + config.detections_topic + "` carries " + m.getDataType() +
                              ", not a TagDetectionArray, PoseWithCovarianceStamped or PoseStamped",
                          path, "point detections_topic at the detector's output");
          }
          if (detection) {
            if (!detections.empty() && detection->stamp < detections.back().stamp) ++replay.stamps_went_back;
            detections.push_back(*detection);
          }
          if (progress && replay.messages[m.getTopic()] % 50 == 0) {
            progress(read_share * replay.messages[m.getTopic()] / total);
          }
        }
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
        if (progress && (i % 50 == 0 || i + 1 == detections.size())) {
          progress(read_share + (1.0 - read_share) * (i + 1) / detections.size());
        }
      }
    }
    replay.samples = session.sample_set();
  } catch (const rosbag::BagException& e) {
    throw HandEyeError(ErrorCode::IoError, std::string("the bag is corrupt or truncated: ") + e.what(), path,
                       "try `rosbag reindex` on a copy of it, or record again");
  }
  if (replay.images > 0 && replay.detections == 0) {
    const auto most = replay.refusals.find("no_target_pose");
    throw no_data("the target was found in none of the " + std::to_string(replay.images) + " images on `" +
                      replay.image_topic + "`" +
                      (most == replay.refusals.end() ? std::string() : ": " + replay.refusal_examples["no_target_pose"]),
                  path, "check the target file against the printed target (kind, sizes, dictionary, ids)");
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
