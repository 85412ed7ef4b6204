// Calibrating from a folder of images (no ROS): which robot pose belongs to which
// image, the camera file, and each image's target pose with its covariance, as
// samples for the session. `handeye images` and test_real_data run it.
#pragma once

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "handeye_covariance/core/measurements.h"
#include "handeye_covariance/core/target.h"
#include "handeye_covariance/io/yaml_io.h"
#include "handeye_covariance/vision/pattern_pose.h"

namespace handeye {
namespace images {

/// The camera: a ROS camera_info YAML (camera_matrix, distortion_coefficients,
/// image_width, image_height) or OpenCV's YAML/XML (cv::FileStorage:
/// camera_matrix, distortion_coefficients, optional image_width/image_height).
/// Throws HandEyeError naming the file and what is missing.
CameraModel read_camera(const std::string& path);

/// OpenCV's camera file (cv::FileStorage YAML or XML, in memory): camera_matrix
/// (3 x 3), distortion_coefficients (optional), image_width and image_height
/// (optional). Every number checked as io::parse_camera_info checks them; the
/// pinhole check is read_camera's. Throws HandEyeError naming the source.
CameraModel parse_opencv_camera(const std::string& text, const std::string& source);

struct ImageWithPose {
  std::filesystem::path image;
  std::optional<Eigen::Isometry3d> T_base_effector;  // absent: no pose found (why says so)
  std::string pose_source;                           // the pose file, or "poses.csv line 3"
  std::string why;                                   // why there is no pose
};

/// Every .png/.jpg/.jpeg in `images` (sorted by name), each with its robot pose
/// T_base_effector (m) from `poses`:
///   a folder: the pose file with the image's stem (000_image.png <-> 000_image.yaml),
///     failing that the one whose stem ends in the same number (000_image.png <->
///     000_pose.csv, franka_image-3.png <-> franka_pose_rPe_3.yaml); any format of
///     io::read_robot_pose (.yaml, .yml, .json, .csv, .txt);
///   a CSV file: `image,tx,ty,tz,qx,qy,qz,qw` per line (a header line is skipped),
///     the image by file name or stem.
/// Throws HandEyeError when the folder has no image or two pose files claim one.
std::vector<ImageWithPose> pair_images_with_poses(const std::filesystem::path& images, const std::filesystem::path& poses);

struct ImageReport {
  std::string image;
  bool used = false;
  std::string why;       // why not (no pose, not detected, refused by the PnP)
  int points = 0;
  double rms_px = 0.0, sigma_px = 0.0, distance = 0.0;  // reprojection RMS, the pooled sigma, the target's distance (m)
};

struct ImageSession {
  /// One sample per used image, each with its detection's covariance and its
  /// corners in raw pixels (TargetCorners::source: the image's name).
  SampleSet samples;
  std::vector<ImageReport> images;  // one per image, in order
  double pixel_sigma = 0.0;        // pooled over every detected image
};

/// Detects the target in every image (rectified first when the camera has
/// distortion), pools the pixel noise over all of them, then gives each image its
/// pose and covariance under the pooled sigma. `progress(i, n, report)` is called
/// after each image's detection.
ImageSession detect_images(const std::vector<ImageWithPose>& inputs, const CameraModel& camera, const Target& target,
                           const Rig& rig,
                           const std::function<void(std::size_t, std::size_t, const ImageReport&)>& progress = {});
/// The same with the images in memory (images[i] is inputs[i]'s, 8-bit gray; empty:
/// unreadable): rendered sessions for the studies.
ImageSession detect_images(const std::vector<ImageWithPose>& inputs, const std::vector<cv::Mat>& images,
                           const CameraModel& camera, const Target& target, const Rig& rig);

}  // namespace images
}  // namespace handeye
