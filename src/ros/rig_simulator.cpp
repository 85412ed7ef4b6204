// A simulated calibration rig with a known X, for trying the node without a robot
// and for the rostests. The robot holds a pose for ~pause_time, then moves to the
// next in ~move_time. The base -> flange TF is published at ~tf_rate, with a static
// flange -> tool0 offset. Pattern detections come at ~detection_rate, stamped with
// the capture time and published ~latency later, with per-frame noise. With
// ~output:=images the rig instead renders what its camera sees (the target of
// ~target_file, ~layout_file or one tag ~tag_size of id 0: target_params.h) and
// publishes the image and its CameraInfo, stamped with the capture time, for the
// target_detector node.
// With ~robot_source:=tf the rig moves no robot: a real or simulated arm does
// (simulated_arm.launch), and the camera sees the target from the effector pose in
// TF at each capture, with X from ~truth and the target's pose Y from
// ~pattern_pose (x y z qx qy qz qw); it detects only when the target's face
// (~face_size, m) is whole in a 60 x 45 deg image (motion/view_planner.h);
// ~blind_after > 0 (s) stops every detection from then on, for a test.
// With ~camera_link set, the rig publishes a camera driver's own TF tree
// (camera_link -> the optical frame, the usual optical rotation) and can stamp
// its detections in another frame of that tree (~detection_frame); their pose
// and covariance are then expressed in that frame. The detection noise is
// drawn in the optical frame: lateral (~pattern_translation_noise_mm) and depth
// (~pattern_depth_noise_mm) differ, as a monocular detector's do.
#include <cv_bridge/cv_bridge.h>
#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <image_transport/image_transport.h>
#include <ros/ros.h>
#include <std_msgs/Float64.h>

#include <mutex>
#include <sensor_msgs/image_encodings.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_broadcaster.h>
#include <tf2_ros/transform_listener.h>

#include <optional>

#include "handeye_covariance/core/units.h"
#include "handeye_covariance/motion/view_planner.h"
#include "handeye_covariance/ros/messages.h"
#include "handeye_covariance/ros/msg_conversion.h"
#include "handeye_covariance/ros/params.h"
#include "handeye_covariance/ros/target_params.h"
#include "handeye_covariance/simulation/pattern_renderer.h"
#include "handeye_covariance/simulation/simulation.h"

namespace handeye {
namespace {

class RigSimulator {
 public:
  RigSimulator(ros::NodeHandle node, ros::NodeHandle pn) : rng_(param(pn, "seed", 1)) {
    setup_ = param(pn, "eye_on_hand", true) ? Setup::EyeInHand : Setup::EyeToHand;
    base_ = param<std::string>(pn, "robot_base_frame", "base_link");
    effector_ = param<std::string>(pn, "robot_effector_frame", "tool0");
    camera_ = param<std::string>(pn, "tracking_base_frame", "camera_optical_frame");
    pattern_frame_ = param<std::string>(pn, "tracking_marker_frame", "tag_0");
    output_ = param<std::string>(pn, "output", "tags");
    publish_robot_tf_ = param(pn, "publish_robot_tf", true);
    detection_covariance_ = param(pn, "detection_covariance", false);
    latency_ = param(pn, "latency", 0.05);
    tag_ids_ = param(pn, "tag_ids", std::vector<int>{0});
    const double rotation_sigma = radians(param(pn, "pattern_rotation_noise_deg", 0.05));
    const double translation_sigma = metres(param(pn, "pattern_translation_noise_mm", 0.3));
    const double depth_sigma = metres(param(pn, "pattern_depth_noise_mm", millimetres(translation_sigma)));
    noise_.rotation = rotation_sigma * rotation_sigma * Eigen::Matrix3d::Identity();
    noise_.translation = Eigen::Vector3d(translation_sigma, translation_sigma, depth_sigma).cwiseAbs2().asDiagonal();
    camera_link_ = param<std::string>(pn, "camera_link", "");
    detection_frame_ = param<std::string>(pn, "detection_frame", camera_);
    // camera_link: x forward, y left, z up; the optical frame: z forward, x right, y down.
    T_link_optical_ = se3::make_pose((Eigen::Matrix3d() << 0, 0, 1, -1, 0, 0, 0, -1, 0).finished(),
                                     Eigen::Vector3d(0.0, 0.015, 0.0));
    if (detection_frame_ != camera_ && detection_frame_ != camera_link_) {
      throw std::invalid_argument("~detection_frame must be ~tracking_base_frame or ~camera_link");
    }

    const std::vector<double> truth = param(pn, "truth", std::vector<double>{});
    const Eigen::Isometry3d X =
        truth.size() == 7 ? se3::make_pose(Eigen::Quaterniond(truth[6], truth[3], truth[4], truth[5]).normalized().toRotationMatrix(),
                                           Eigen::Vector3d(truth[0], truth[1], truth[2]))
                          : typical_X(setup_);
    trajectory_ = make_rig_trajectory(rng_, setup_, X, param(pn, "poses", 12), param(pn, "pause_time", 2.0),
                                      param(pn, "move_time", 1.0));
    robot_from_tf_ = param<std::string>(pn, "robot_source", "trajectory") == "tf";
    if (robot_from_tf_) {
      publish_robot_tf_ = false;
      const std::vector<double> y = param(pn, "pattern_pose", std::vector<double>{0.45, 0.15, 0.0, 0, 0, 0, 1});
      if (y.size() != 7) throw std::invalid_argument("~pattern_pose must be 7 numbers: x y z qx qy qz qw");
      trajectory_.T_world_pattern = se3::make_pose(
          Eigen::Quaterniond(y[6], y[3], y[4], y[5]).normalized().toRotationMatrix(), Eigen::Vector3d(y[0], y[1], y[2]));
      trajectory_.rig.setup = setup_;
      const std::vector<double> face = param(pn, "face_size", std::vector<double>{0.2, 0.15});
      trajectory_.rig.face_size = Eigen::Vector2d(face.at(0), face.at(1));
      tf_listener_ = std::make_unique<tf2_ros::TransformListener>(tf_buffer_);
      blind_after_ = param(pn, "blind_after", 0.0);  // s; > 0: no detection from then on (a test's fault)
    }
    std::optional<Target> target;
    if (output_ == "images") {
      target = target_from_params(pn);
      if (robot_from_tf_) {  // ~pattern_pose is the target's own frame; it is seen when its face is
        trajectory_.rig.T_pattern_face = target_face(*target);
        trajectory_.rig.face_size = target_face_size(*target);
      }
      else
        trajectory_.look_at_face(target_face(*target));
    }
    flange_T_tool_ = se3::make_pose(so3::exp(Eigen::Vector3d(0, 0, 0.3)), Eigen::Vector3d(0, 0, 0.12));

    truth_pub_ = pn.advertise<geometry_msgs::PoseStamped>("truth", 1, true);
    geometry_msgs::PoseStamped truth_msg;
    truth_msg.header.frame_id = setup_ == Setup::EyeInHand ? effector_ : base_;
    truth_msg.pose = conversions::to_pose_msg(trajectory_.X);
    truth_pub_.publish(truth_msg);
    pattern_truth_pub_ = pn.advertise<geometry_msgs::PoseStamped>("pattern_truth", 1, true);  // Y
    geometry_msgs::PoseStamped pattern_msg;
    pattern_msg.header.frame_id = setup_ == Setup::EyeInHand ? base_ : effector_;
    pattern_msg.pose = conversions::to_pose_msg(trajectory_.T_world_pattern);
    pattern_truth_pub_.publish(pattern_msg);

    bump_sub_ = pn.subscribe("bump_camera_mm", 1, &RigSimulator::on_bump, this);
    const std::string topic = param<std::string>(pn, "detections_topic", "tag_detections");
    if (output_ == "tags") detections_ = node.advertise<TagDetectionArray>(topic, 10);
    if (output_ == "pose_with_covariance") detections_ = node.advertise<geometry_msgs::PoseWithCovarianceStamped>(topic, 10);
    if (output_ == "pose") detections_ = node.advertise<geometry_msgs::PoseStamped>(topic, 10);
    if (output_ == "images") {
      RenderOptions render;
      render.noise_sigma = param(pn, "image_noise", render.noise_sigma);
      render.blur_sigma_px = param(pn, "image_blur", render.blur_sigma_px);
      renderer_ = std::make_unique<PatternRenderer>(*target, simulated_camera(), render);
      transport_ = std::make_unique<image_transport::ImageTransport>(node);
      image_pub_ = transport_->advertise(param<std::string>(pn, "image_topic", "camera/image_raw"), 2);
      info_pub_ = node.advertise<sensor_msgs::CameraInfo>(param<std::string>(pn, "camera_info_topic", "camera/camera_info"), 2);
    }

    const ros::Time started = ros::Time::now();
    std::vector<geometry_msgs::TransformStamped> statics;
    if (publish_robot_tf_) statics.push_back(conversions::to_transform_stamped(flange_T_tool_, "flange", effector_, started));
    if (!camera_link_.empty()) {  // the camera driver's tree
      statics.push_back(conversions::to_transform_stamped(T_link_optical_, camera_link_, camera_, started));
    }
    if (!statics.empty()) static_broadcaster_.sendTransform(statics);

    start_ = ros::Time::now();
    tf_timer_ = node.createTimer(ros::Duration(1.0 / param(pn, "tf_rate", 200.0)), &RigSimulator::publish_tf, this);
    detection_timer_ =
        node.createTimer(ros::Duration(1.0 / param(pn, "detection_rate", 20.0)), &RigSimulator::publish_detection, this);
    if (robot_from_tf_)
      ROS_INFO("rig simulator: %s, the robot from TF (%s -> %s), detections as `%s`", to_string(setup_), base_.c_str(),
               effector_.c_str(), output_.c_str());
    else
      ROS_INFO("rig simulator: %s, %zu poses, %.1f s pause, %.1f s move, detections as `%s`", to_string(setup_),
               trajectory_.poses.size(), trajectory_.pause, trajectory_.move, output_.c_str());
  }

 private:
  double elapsed(const ros::Time& t) const { return (t - start_).toSec(); }

  /// The true T_camera_pattern at `capture`: the rig's own trajectory, or the arm's
  /// effector in TF (none when TF has no pose then, or the face is not whole in view).
  std::optional<Eigen::Isometry3d> view_at(const ros::Time& capture) {
    if (!robot_from_tf_) {
      return trajectory_.rig.predicted_view(trajectory_.effector_at(elapsed(capture)), camera_mount(capture),
                                            trajectory_.T_world_pattern);
    }
    if (blind_after_ > 0.0 && elapsed(capture) > blind_after_) return std::nullopt;
    geometry_msgs::TransformStamped E;
    try {
      E = tf_buffer_.lookupTransform(base_, effector_, capture, ros::Duration(0.05));
    } catch (const tf2::TransformException&) {
      return std::nullopt;
    }
    const Eigen::Isometry3d P =
        trajectory_.rig.predicted_view(conversions::to_eigen(E.transform), camera_mount(capture), trajectory_.T_world_pattern);
    if (motion::view_problem(trajectory_.rig, std::nullopt, P, motion::PlannerOptions{})) return std::nullopt;
    return P;
  }

  /// X at `capture`: the truth, or after a bump (~bump_camera_mm, a test's fault) the camera
  /// moved on its mount along its own x axis; ~truth follows it.
  Eigen::Isometry3d camera_mount(const ros::Time& capture) const {
    std::lock_guard<std::mutex> lock(bump_mutex_);
    if (bumped_at_.isZero() || capture < bumped_at_) return trajectory_.X;
    Eigen::Isometry3d X = trajectory_.X;
    X.translation() += X.linear() * Eigen::Vector3d(metres(bump_mm_), 0.0, 0.0);
    return X;
  }

  void on_bump(const std_msgs::Float64::ConstPtr& msg) {
    {
      std::lock_guard<std::mutex> lock(bump_mutex_);
      bump_mm_ += msg->data;
      bumped_at_ = ros::Time::now();
    }
    ROS_WARN("rig simulator: the camera moved %.2f mm on its mount (along its x axis)", msg->data);
    geometry_msgs::PoseStamped truth;
    truth.header.frame_id = setup_ == Setup::EyeInHand ? effector_ : base_;
    truth.pose = conversions::to_pose_msg(camera_mount(ros::Time::now()));
    truth_pub_.publish(truth);
  }

  void publish_tf(const ros::TimerEvent&) {
    if (!publish_robot_tf_) return;
    const ros::Time now = ros::Time::now();
    broadcaster_.sendTransform(conversions::to_transform_stamped(
        trajectory_.effector_at(elapsed(now)) * flange_T_tool_.inverse(), base_, "flange", now));
  }

  /// The camera's view at the capture time, rendered, with its CameraInfo.
  void publish_image(const ros::Time& capture) {
    std_msgs::Header header;
    header.stamp = capture;
    header.frame_id = camera_;
    const std::optional<Eigen::Isometry3d> view = view_at(capture);
    if (!view) return;
    const cv::Mat image = renderer_->render(*view, rng_);
    const sensor_msgs::ImagePtr msg = cv_bridge::CvImage(header, sensor_msgs::image_encodings::MONO8, image).toImageMsg();
    sensor_msgs::CameraInfo info = conversions::to_camera_info(renderer_->camera());
    info.header = header;
    image_pub_.publish(msg);
    info_pub_.publish(info);
  }

  void publish_detection(const ros::TimerEvent&) {
    const ros::Time capture = ros::Time::now() - ros::Duration(latency_);
    if (output_ == "images") {
      publish_image(capture);
      return;
    }
    // Noise in the optical frame; the detection (pose and covariance) in detection_frame.
    const std::optional<Eigen::Isometry3d> view = view_at(capture);
    if (!view) return;
    PoseWithCovariance P{perturb(rng_, *view, noise_), noise_.as_pose_covariance()};
    if (detection_frame_ != camera_) P = compose({T_link_optical_, Matrix6d::Zero()}, P);
    geometry_msgs::PoseWithCovarianceStamped pose = conversions::to_stamped_msg(P, detection_frame_, capture);
    if (!detection_covariance_) pose.pose.covariance.fill(0.0);
    if (output_ == "tags") {
      TagDetectionArray array;
      array.header = pose.header;
      TagDetection detection;
      detection.id = tag_ids_;
      detection.size.assign(tag_ids_.size(), 0.1);
      detection.pose = pose;
      array.detections.push_back(detection);
      detections_.publish(array);
    } else if (output_ == "pose_with_covariance") {
      detections_.publish(pose);
    } else if (output_ == "pose") {
      geometry_msgs::PoseStamped plain;
      plain.header = pose.header;
      plain.pose = pose.pose.pose;
      detections_.publish(plain);
    } else {  // tf
      broadcaster_.sendTransform(conversions::to_transform_stamped(P.pose, detection_frame_, pattern_frame_, capture));
    }
  }

  mutable std::mutex bump_mutex_;
  double bump_mm_ = 0.0;
  ros::Time bumped_at_;
  ros::Subscriber bump_sub_;
  Rng rng_;
  Setup setup_;
  std::string base_, effector_, camera_, pattern_frame_, output_, camera_link_, detection_frame_;
  Eigen::Isometry3d T_link_optical_;
  bool publish_robot_tf_, detection_covariance_, robot_from_tf_ = false;
  double blind_after_ = 0.0;
  tf2_ros::Buffer tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  double latency_;
  std::vector<int> tag_ids_;
  PoseNoise noise_;  // in the optical frame
  RigTrajectory trajectory_;
  Eigen::Isometry3d flange_T_tool_;
  ros::Time start_;
  ros::Publisher truth_pub_, pattern_truth_pub_, detections_, info_pub_;
  std::unique_ptr<PatternRenderer> renderer_;
  std::unique_ptr<image_transport::ImageTransport> transport_;
  image_transport::Publisher image_pub_;
  ros::Timer tf_timer_, detection_timer_;
  tf2_ros::TransformBroadcaster broadcaster_;
  tf2_ros::StaticTransformBroadcaster static_broadcaster_;
};

}  // namespace
}  // namespace handeye

int main(int argc, char** argv) {
  ros::init(argc, argv, "rig_simulator");
  // Held past the catch: when the last handle goes, ROS shuts down its logging, and ROS_FATAL would print nothing.
  ros::NodeHandle node_handle, private_node_handle("~");
  try {
    handeye::RigSimulator rig(node_handle, private_node_handle);
    ros::spin();
  } catch (const std::exception& e) {
    ROS_FATAL("rig_simulator: %s", e.what());
    return 1;
  }
  return 0;
}
