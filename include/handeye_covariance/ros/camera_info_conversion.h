// The ROS <-> vision seam: CameraInfo and the vision library's CameraModel.
// Apart from msg_conversion.h so that the ROS bridge (and the rviz plugin that
// links it) does not link OpenCV.
#pragma once

#include <sensor_msgs/CameraInfo.h>

#include "handeye_covariance/vision/pattern_pose.h"

namespace handeye {
namespace conversions {

/// The camera model of a CameraInfo (K, D, size). Throws HandEyeError for an
/// uncalibrated camera (K all zeros) or an unknown distortion model.
CameraModel to_camera_model(const sensor_msgs::CameraInfo& info);
sensor_msgs::CameraInfo to_camera_info(const CameraModel& camera);

}  // namespace conversions
}  // namespace handeye
