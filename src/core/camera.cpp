#include "handeye_covariance/core/camera.h"

#include <cmath>

#include "handeye_covariance/core/errors.h"

namespace handeye {

void check_camera_model(const CameraModel& camera, const std::string& where) {
  if (!camera.K.allFinite() || !(camera.K(0, 0) > 0.0) || !(camera.K(1, 1) > 0.0) || camera.K(2, 2) != 1.0) {
    throw HandEyeError(ErrorCode::MalformedFile, "the camera matrix K is not a pinhole matrix (fx, fy > 0, K[2][2] = 1)",
                       where, "calibrate the camera's intrinsics first (camera_calibration) and publish them in CameraInfo");
  }
  const std::size_t n = camera.distortion.size();
  if (!(n == 0 || n == 4 || n == 5 || n == 8 || n == 12 || n == 14)) {
    throw HandEyeError(ErrorCode::WrongLength, "distortion has " + std::to_string(n) + " coefficients", where,
                       "give plumb_bob (5) or rational_polynomial (8) coefficients, or none");
  }
  for (double d : camera.distortion) {
    if (!std::isfinite(d)) {
      throw HandEyeError(ErrorCode::NonFinite, "NaN or Inf in the distortion coefficients", where, "fix the camera info");
    }
  }
}

}  // namespace handeye
