#include "handeye_covariance/ros/camera_info_conversion.h"

#include "handeye_covariance/core/errors.h"

namespace handeye {
namespace conversions {

CameraModel to_camera_model(const sensor_msgs::CameraInfo& info) {
  const std::string where = "CameraInfo of frame `" + info.header.frame_id + "`";
  CameraModel camera;
  camera.K = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(info.K.data());
  camera.width = static_cast<int>(info.width);
  camera.height = static_cast<int>(info.height);
  if (info.distortion_model != "plumb_bob" && info.distortion_model != "rational_polynomial" &&
      !(info.distortion_model.empty() && info.D.empty())) {
    throw HandEyeError(ErrorCode::MalformedFile, "distortion model `" + info.distortion_model + "` is not supported", where,
                       "calibrate with plumb_bob or rational_polynomial (camera_calibration does), or feed the "
                       "rectified image (image_rect) with ~image_is_rectified:=true");
  }
  camera.distortion.assign(info.D.begin(), info.D.end());
  if (camera.K.isZero()) {
    throw HandEyeError(ErrorCode::MalformedFile, "K is all zeros: the camera is not calibrated", where,
                       "calibrate the intrinsics first (rosrun camera_calibration cameracalibrator.py) so that the "
                       "driver publishes K and D");
  }
  check_camera_model(camera, where);
  return camera;
}

sensor_msgs::CameraInfo to_camera_info(const CameraModel& camera) {
  sensor_msgs::CameraInfo info;
  info.width = static_cast<uint32_t>(camera.width);
  info.height = static_cast<uint32_t>(camera.height);
  info.distortion_model = camera.distortion.size() > 5 ? "rational_polynomial" : "plumb_bob";
  info.D = camera.distortion;
  Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(info.K.data()) = camera.K;
  info.R = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  Eigen::Map<Eigen::Matrix<double, 3, 4, Eigen::RowMajor>> P(info.P.data());
  P.setZero();
  P.leftCols<3>() = camera.K;
  return info;
}

}  // namespace conversions
}  // namespace handeye
