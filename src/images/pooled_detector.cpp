#include "handeye_covariance/images/pooled_detector.h"

#include <cmath>

namespace handeye {
namespace images {

PooledDetector::PooledDetector(const Target& target, const TargetDetectorOptions& options)
    : detector_(target, options), pose_options_(options.pose) {}

PooledDetector::~PooledDetector() = default;

const PooledDetector::Frame& PooledDetector::add(const cv::Mat& gray, const CameraModel& camera) {
  if (!camera_ || camera_->K != camera.K || camera_->distortion != camera.distortion || camera_->width != camera.width ||
      camera_->height != camera.height) {
    rectifier_ = std::make_unique<ImageRectifier>(camera);  // checks the camera
    camera_ = camera;
  }
  Frame frame;
  const TargetObservation seen = detector_.detect(gray, *rectifier_);
  frame.why = seen.refusal;
  if (seen.points) {
    // A refused frame adds nothing to the pool (estimate_pose adds only what it accepts).
    PatternPoseResult r = estimate_pose(rectifier_->rectified(), *seen.points, noise_, pose_options_);
    frame.pose = std::move(r.pose);
    if (frame.pose) frame.corners = raw_pixels(*seen.points, camera);
    else frame.why = r.refusal;
  }
  frames_.push_back(std::move(frame));
  return frames_.back();
}

std::optional<PatternPose> PooledDetector::pooled(std::size_t i) const {
  std::optional<PatternPose> pose = frames_.at(i).pose;
  if (!pose) return pose;
  const double variance = noise_.covariance_variance();
  pose->covariance *= variance / pose->covariance_variance;
  pose->pixel_sigma = noise_.sigma();
  pose->covariance_variance = variance;
  return pose;
}

}  // namespace images
}  // namespace handeye
