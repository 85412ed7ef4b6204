#include "handeye_covariance/ros/target_detector.h"

#include <cv_bridge/cv_bridge.h>
#include <sensor_msgs/image_encodings.h>

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/ros/messages.h"
#include "handeye_covariance/ros/msg_conversion.h"
#include "handeye_covariance/ros/params.h"
#include "handeye_covariance/ros/target_params.h"

namespace handeye {

TargetDetectorNode::TargetDetectorNode(ros::NodeHandle node, ros::NodeHandle pn)
    : pattern_frame_(param<std::string>(pn, "pattern_frame", "tag_0")),
      publish_tf_(param(pn, "publish_tf", false)),
      image_is_rectified_(param(pn, "image_is_rectified", false)),
      transport_(node),
      // The floor and window of `handeye images` and the library (PixelNoise's defaults).
      pixel_noise_(param(pn, "pixel_sigma_floor", PixelNoise{}.floor()),
                   static_cast<std::size_t>(param(pn, "noise_window", 200))) {
  options_.apriltag.quad_decimate = param(pn, "quad_decimate", 0.0);  // 0: by the image width (tag_detector.h)
  options_.apriltag.threads = param(pn, "threads", 2);
  options_.apriltag.max_hamming = param(pn, "max_hamming", 0);
  options_.apriltag.min_decision_margin = param(pn, "min_decision_margin", 20.0);
  options_.pose.min_tags = param(pn, "min_tags", 1);
  options_.pose.max_rms_px = param(pn, "max_rms_px", 2.0);
  options_.min_charuco_corners = param(pn, "min_charuco_corners", options_.min_charuco_corners);
  const std::string model = param<std::string>(pn, "corner_noise", "edge_fit");
  if (model != "edge_fit" && model != "independent") {
    throw HandEyeError(ErrorCode::MalformedFile, "~corner_noise is `" + model + "`", pn.getNamespace(),
                       "use edge_fit (default) or independent");
  }
  options_.pose.corner_noise = model == "edge_fit" ? CornerNoiseModel::EdgeFit : CornerNoiseModel::Independent;
  detector_ = std::make_unique<TargetDetector>(target_from_params(pn), options_);

  detections_pub_ = node.advertise<TagDetectionArray>(param<std::string>(pn, "detections_topic", "tag_detections"), 10);
  info_sub_ = node.subscribe("camera_info", 2, &TargetDetectorNode::on_camera_info, this);
  image_sub_ = transport_.subscribe("image", 2, &TargetDetectorNode::on_image, this);
  ROS_INFO("target_detector: %s on `%s` (info `%s`), publishing `%s`%s", detector_->target().describe().c_str(),
           image_sub_.getTopic().c_str(), info_sub_.getTopic().c_str(), detections_pub_.getTopic().c_str(),
           publish_tf_ ? (" and TF to `" + pattern_frame_ + "`").c_str() : "");
  if (is_half_turn_symmetric(detector_->target())) {
    ROS_WARN("target_detector: %s looks the same turned by 180 degrees: each pose published is one of two candidates "
             "(the calibration node decides which from the robot's motion; give it the same target_file). A board with "
             "one even and one odd number of inner corners avoids this.",
             detector_->target().describe().c_str());
  }
}

void TargetDetectorNode::on_camera_info(const sensor_msgs::CameraInfo::ConstPtr& info) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (info_ && info_->K == info->K && info_->D == info->D && info_->width == info->width && info_->height == info->height) {
    return;  // the usual case: the same calibration on every frame
  }
  try {
    CameraModel camera = conversions::to_camera_model(*info);
    if (image_is_rectified_) camera.distortion.clear();
    rectifier_ = std::make_unique<ImageRectifier>(camera);
    camera_ = camera;
    info_ = *info;
    camera_error_.clear();
  } catch (const HandEyeError& e) {
    rectifier_.reset();
    info_.reset();
    camera_error_ = e.what();
    ROS_ERROR_THROTTLE(5.0, "target_detector: refusing the camera info: %s", e.what());
  }
}

void TargetDetectorNode::on_image(const sensor_msgs::Image::ConstPtr& image) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!rectifier_) {
    ROS_WARN_THROTTLE(5.0, "target_detector: no usable CameraInfo on `%s` yet%s%s", info_sub_.getTopic().c_str(),
                      camera_error_.empty() ? "" : ": ", camera_error_.c_str());
    return;
  }
  if (static_cast<int>(image->width) != rectifier_->rectified().width ||
      static_cast<int>(image->height) != rectifier_->rectified().height) {
    ROS_ERROR_THROTTLE(5.0, "target_detector: image is %ux%u but the CameraInfo says %dx%d; is `camera_info` the info of `image`?",
                       image->width, image->height, rectifier_->rectified().width, rectifier_->rectified().height);
    return;
  }
  cv_bridge::CvImageConstPtr mono;
  try {
    mono = cv_bridge::toCvShare(image, sensor_msgs::image_encodings::MONO8);
  } catch (const cv_bridge::Exception& e) {
    ROS_ERROR_THROTTLE(5.0, "target_detector: cannot convert a `%s` image to mono8: %s", image->encoding.c_str(), e.what());
    return;
  }
  const TargetObservation seen = detector_->detect(mono->image, *rectifier_);
  TagDetectionArray array;
  array.header = image->header;
  if (seen.points) {
    const PatternPoseResult result = estimate_pose(rectifier_->rectified(), *seen.points, pixel_noise_, options_.pose);
    if (result.pose) {
      const Target& target = detector_->target();
      TagDetection detection;  // the pattern, as apriltag_ros names a bundle; a board has no tag ids
      if (const TagLayout* markers = target.get<TagLayout>()) {
        detection.id = markers->ids();
        for (const TagPlacement& tag : markers->tags) detection.size.push_back(tag.size);
      } else {
        detection.size.push_back(target.kind().ruler_length(target));  // a board's square
      }
      detection.pose.header = image->header;
      detection.pose.pose = conversions::to_msg(PoseWithCovariance{result.pose->T_camera_pattern, result.pose->covariance});
      // The corners behind the pose, in the raw image's pixels: what method corners refines X from.
      conversions::set_corners(TargetCorners{camera_, raw_pixels(*seen.points, camera_), ""}, detection);
      array.detections.push_back(detection);
      if (publish_tf_) {
        broadcaster_.sendTransform(conversions::to_transform_stamped(result.pose->T_camera_pattern, image->header.frame_id,
                                                                     pattern_frame_, image->header.stamp));
      }
    } else {
      ROS_WARN_THROTTLE(5.0, "target_detector: %s seen but no pose: %s", detector_->target().kind_name().c_str(),
                        result.refusal.c_str());
    }
  } else {
    ROS_WARN_THROTTLE(5.0, "target_detector: %s", seen.refusal.c_str());
  }
  detections_pub_.publish(array);  // empty when the target is not seen, so listeners know the frame was processed
}

}  // namespace handeye
