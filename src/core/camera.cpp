#include "handeye_covariance/core/camera.h"

#include <Eigen/Cholesky>
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

void check_corners(const PointCorrespondences& points, const std::string& where) {
  const std::size_t n = points.image.size();
  if (n == 0 || n > kMaxTargetPoints) {
    throw HandEyeError(ErrorCode::NoData, std::to_string(n) + " corners", where,
                       "give the target's detected corners (1 to " + std::to_string(kMaxTargetPoints) + ")");
  }
  if (points.object.size() != n) {
    throw HandEyeError(ErrorCode::WrongLength,
                       std::to_string(n) + " image points for " + std::to_string(points.object.size()) + " target points",
                       where, "give one target point per image point, in the same order");
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (!points.object[i].allFinite() || !points.image[i].allFinite()) {
      throw HandEyeError(ErrorCode::NonFinite, "NaN or Inf in point " + std::to_string(i), where, "fix the detector");
    }
  }
  const Eigen::MatrixXd& C = points.corner_covariance;
  if (C.size() == 0) return;  // independent corners, identity
  const auto m = static_cast<Eigen::Index>(2 * n);
  const int block = points.blocks;
  if (block < 2 || block % 2 != 0 || block > kMaxCornerBlock || m % block != 0 || C.rows() != m || C.cols() != m) {
    throw HandEyeError(ErrorCode::WrongLength,
                       "the corner covariance is " + std::to_string(C.rows()) + " x " + std::to_string(C.cols()) +
                           " in blocks of " + std::to_string(block) + " for " + std::to_string(m) + " coordinates",
                       where, "give a (2n x 2n) block-diagonal corner covariance in even blocks of at most " +
                                  std::to_string(kMaxCornerBlock) + ", or none");
  }
  for (Eigen::Index start = 0; start < m; start += block) {
    const Eigen::MatrixXd Cb = C.block(start, start, block, block);
    if (!Cb.allFinite() || (Cb - Cb.transpose()).cwiseAbs().maxCoeff() > 1e-9 * Cb.cwiseAbs().maxCoeff() ||
        Eigen::LLT<Eigen::MatrixXd>(Cb).info() != Eigen::Success) {
      throw HandEyeError(ErrorCode::InvalidNoise,
                         "the corner covariance of coordinates " + std::to_string(start) + ".." +
                             std::to_string(start + block - 1) + " is not symmetric positive definite",
                         where, "check the detector's corner-noise model");
    }
  }
}

std::vector<double> covariance_blocks(const PointCorrespondences& points) {
  const Eigen::MatrixXd& C = points.corner_covariance;
  const Eigen::Index b = points.blocks;
  std::vector<double> values;
  for (Eigen::Index start = 0; C.size() > 0 && start < C.rows(); start += b)
    for (Eigen::Index r = 0; r < b; ++r)
      for (Eigen::Index c = 0; c < b; ++c) values.push_back(C(start + r, start + c));
  return values;
}

Eigen::MatrixXd from_covariance_blocks(const std::vector<double>& values, int block) {
  const auto b = static_cast<Eigen::Index>(block);
  const auto m = static_cast<Eigen::Index>(values.size()) / b;
  Eigen::MatrixXd C = Eigen::MatrixXd::Zero(m, m);
  std::size_t k = 0;
  for (Eigen::Index start = 0; start < m; start += b)
    for (Eigen::Index r = 0; r < b; ++r)
      for (Eigen::Index c = 0; c < b; ++c) C(start + r, start + c) = values[k++];
  return C;
}

}  // namespace handeye
