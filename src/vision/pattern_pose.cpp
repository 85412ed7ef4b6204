#include "handeye_covariance/vision/pattern_pose.h"

#include <Eigen/Dense>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/core/lie.h"

namespace handeye {
namespace {

using Eigen::Isometry3d;
using Eigen::Matrix3d;
using Eigen::Vector3d;

cv::Mat camera_matrix(const CameraModel& camera) {
  cv::Mat K;
  cv::eigen2cv(camera.K, K);
  return K;
}

/// Each rectified pixel u = K (x, y, 1): the normalised points (x, y, 1).
std::vector<cv::Point3d> normalised_points(const CameraModel& camera, const std::vector<Eigen::Vector2d>& pixels) {
  const Eigen::Matrix3d K_inverse = camera.K.inverse();
  std::vector<cv::Point3d> normalised;
  for (const Eigen::Vector2d& u : pixels) {
    const Vector3d p = K_inverse * Vector3d(u.x(), u.y(), 1.0);
    normalised.emplace_back(p.x() / p.z(), p.y() / p.z(), 1.0);
  }
  return normalised;
}

cv::Mat distortion(const CameraModel& camera) {
  return camera.distortion.empty() ? cv::Mat::zeros(1, 4, CV_64F) : cv::Mat(camera.distortion, true).reshape(1, 1);
}

std::vector<cv::Point3d> cv_points(const std::vector<Vector3d>& points) {
  std::vector<cv::Point3d> out;
  out.reserve(points.size());
  for (const Vector3d& p : points) out.emplace_back(p.x(), p.y(), p.z());
  return out;
}

/// True when every point lies within 1e-9 of the best-fit plane (relative to the pattern's extent).
bool coplanar(const std::vector<Vector3d>& points) {
  Vector3d centre = Vector3d::Zero();
  for (const Vector3d& p : points) centre += p;
  centre /= static_cast<double>(points.size());
  Matrix3d scatter = Matrix3d::Zero();
  for (const Vector3d& p : points) scatter += (p - centre) * (p - centre).transpose();
  const Eigen::SelfAdjointEigenSolver<Matrix3d> eig(scatter);
  return eig.eigenvalues()(0) <= 1e-18 * eig.eigenvalues()(2);
}

Isometry3d pose_of(const cv::Mat& rvec, const cv::Mat& tvec) {
  cv::Mat R;
  cv::Rodrigues(rvec, R);
  Matrix3d R_eigen;
  Vector3d t;
  cv::cv2eigen(R, R_eigen);
  cv::cv2eigen(tvec.reshape(1, 3), t);
  return se3::make_pose(R_eigen, t);
}

}  // namespace

Eigen::Vector2d project(const CameraModel& camera, const Vector3d& p_camera) {
  std::vector<cv::Point2d> pixels;
  cv::projectPoints(cv_points({p_camera}), cv::Mat::zeros(3, 1, CV_64F), cv::Mat::zeros(3, 1, CV_64F), camera_matrix(camera),
                    handeye::distortion(camera), pixels);
  return {pixels[0].x, pixels[0].y};
}

ImageRectifier::ImageRectifier(const CameraModel& camera) : camera_(camera), rectified_(camera) {
  check_camera_model(camera, "camera");
  rectified_.distortion.clear();
  bool distorted = false;
  for (double d : camera.distortion) distorted = distorted || d != 0.0;
  if (!distorted) return;
  if (camera.width <= 0 || camera.height <= 0) {
    throw HandEyeError(ErrorCode::MalformedFile, "the camera has distortion but no image size", "camera",
                       "set width and height in the CameraInfo");
  }
  const cv::Mat K = camera_matrix(camera);
  // Fixed-point maps (1/32 px), made once rather than from float maps on every
  // remap call (not bit-identical: test_vision's calibration NEES 4.56 -> 4.58).
  cv::initUndistortRectifyMap(K, distortion(camera), cv::noArray(), K, cv::Size(camera.width, camera.height), CV_16SC2,
                              map_x_, map_y_);
}

cv::Mat ImageRectifier::rectify(const cv::Mat& image) const {
  if (map_x_.empty()) return image;
  cv::Mat out;
  cv::remap(image, out, map_x_, map_y_, cv::INTER_LANCZOS4, cv::BORDER_CONSTANT);
  return out;
}

std::vector<cv::Point2f> ImageRectifier::to_raw(const std::vector<Eigen::Vector2d>& rectified_pixels) const {
  std::vector<cv::Point2f> raw;
  if (rectified_pixels.empty()) return raw;
  std::vector<cv::Point2d> projected;
  cv::projectPoints(normalised_points(camera_, rectified_pixels), cv::Mat::zeros(3, 1, CV_64F),
                    cv::Mat::zeros(3, 1, CV_64F), camera_matrix(camera_), distortion(camera_), projected);
  for (const cv::Point2d& p : projected) raw.emplace_back(static_cast<float>(p.x), static_cast<float>(p.y));
  return raw;
}

std::vector<Eigen::Vector2d> ImageRectifier::from_raw(const std::vector<cv::Point2f>& raw_pixels) const {
  std::vector<Eigen::Vector2d> out;
  if (raw_pixels.empty()) return out;
  std::vector<cv::Point2d> raw(raw_pixels.begin(), raw_pixels.end()), rectified;
  const cv::Mat K = camera_matrix(camera_);
  cv::undistortPoints(raw, rectified, K, distortion(camera_), cv::noArray(), K,
                      cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 100, 1e-12));
  for (const cv::Point2d& p : rectified) out.emplace_back(p.x, p.y);
  return out;
}

void PixelNoise::add(double residual_sum_of_squares, int degrees_of_freedom) {
  if (degrees_of_freedom <= 0 || !std::isfinite(residual_sum_of_squares)) return;
  frames_.emplace_back(residual_sum_of_squares, degrees_of_freedom);
  rss_ += residual_sum_of_squares;
  dof_ += degrees_of_freedom;
  while (frames_.size() > window_) {
    rss_ -= frames_.front().first;
    dof_ -= frames_.front().second;
    frames_.pop_front();
  }
}

double PixelNoise::sigma() const {
  if (dof_ <= 0) return floor_;
  return std::max(floor_, std::sqrt(std::max(0.0, rss_) / dof_));
}

double PixelNoise::covariance_variance() const {
  if (dof_ <= 0) return floor_ * floor_;
  const double nu = std::max(dof_, 3);
  // The floor is a stated minimum, not an estimate: no factor on it (and none of a jump where it starts to hold).
  return std::max(floor_ * floor_, std::max(0.0, rss_) / dof_ * nu / (nu - 2.0));
}

Eigen::Matrix<double, 8, 8> edge_fit_corner_covariance(const std::array<Eigen::Vector2d, 4>& corners) {
  // d: the perpendicular displacement of each edge line at its two ends;
  // edge e runs from corner e to corner e + 1, so d(2e) is at corner e and
  // d(2e + 1) at corner e + 1.
  Eigen::Matrix<double, 8, 8> D = Eigen::Matrix<double, 8, 8>::Zero();
  std::array<Eigen::Vector2d, 4> normal;
  for (int e = 0; e < 4; ++e) {
    const Eigen::Vector2d along = corners[(e + 1) % 4] - corners[e];
    const double length = std::max(along.norm(), 1e-9);
    normal[e] = Eigen::Vector2d(-along.y(), along.x()) / length;
    // A line fitted to `length` unit-spaced points of noise 1: offset variance
    // 1/l, tilt variance 12/l^3; at the ends +-l/2 that is 4/l each, covariance -2/l.
    D.block<2, 2>(2 * e, 2 * e) << 4.0 / length, -2.0 / length, -2.0 / length, 4.0 / length;
  }
  // Corner c is on edges c - 1 (its end) and c (its start): n_{c-1} . dc = d, n_c . dc = d'.
  Eigen::Matrix<double, 8, 8> G = Eigen::Matrix<double, 8, 8>::Zero();
  for (int c = 0; c < 4; ++c) {
    const int previous = (c + 3) % 4;
    Eigen::Matrix2d N;
    N.row(0) = normal[previous].transpose();
    N.row(1) = normal[c].transpose();
    const Eigen::Matrix2d N_inverse = N.inverse();
    G.block<2, 1>(2 * c, 2 * previous + 1) = N_inverse.col(0);
    G.block<2, 1>(2 * c, 2 * c) = N_inverse.col(1);
  }
  return G * D * G.transpose();
}

Eigen::Matrix<double, Eigen::Dynamic, 6> reprojection_jacobian(const CameraModel& camera, const Isometry3d& T_camera_pattern,
                                                               const std::vector<Vector3d>& points) {
  std::vector<Vector3d> in_camera;
  in_camera.reserve(points.size());
  for (const Vector3d& p : points) in_camera.push_back(T_camera_pattern * p);
  // With rvec = tvec = 0, d(pixel)/d(tvec) is d(pixel)/d(point in the camera frame).
  std::vector<cv::Point2d> pixels;
  cv::Mat jacobian;
  cv::projectPoints(cv_points(in_camera), cv::Mat::zeros(3, 1, CV_64F), cv::Mat::zeros(3, 1, CV_64F), camera_matrix(camera),
                    distortion(camera), pixels, jacobian);
  Eigen::Matrix<double, Eigen::Dynamic, 6> J(2 * points.size(), 6);
  for (std::size_t i = 0; i < points.size(); ++i) {
    Eigen::Matrix<double, 2, 3> d_pixel_d_point;
    for (int r = 0; r < 2; ++r) {
      for (int c = 0; c < 3; ++c) d_pixel_d_point(r, c) = jacobian.at<double>(static_cast<int>(2 * i) + r, 3 + c);
    }
    // p_c = R p + t: d p_c = dt - [R p] xi for R = exp([xi]) R_hat.
    const Vector3d rotated = in_camera[i] - T_camera_pattern.translation();
    J.block<2, 3>(2 * i, 0) = d_pixel_d_point;
    J.block<2, 3>(2 * i, 3) = -d_pixel_d_point * so3::hat(rotated);
  }
  return J;
}

Eigen::Matrix<double, Eigen::Dynamic, 4> intrinsics_jacobian(const CameraModel& camera, const Isometry3d& T_camera_pattern,
                                                             const std::vector<Vector3d>& points) {
  std::vector<cv::Point2d> pixels;
  cv::Mat jacobian;  // columns: rvec (3), tvec (3), fx, fy, cx, cy, the distortion's
  const Eigen::AngleAxisd axis_angle(T_camera_pattern.linear());
  const Vector3d r = axis_angle.angle() * axis_angle.axis(), t = T_camera_pattern.translation();
  cv::projectPoints(cv_points(points), cv::Mat(cv::Vec3d(r.x(), r.y(), r.z())), cv::Mat(cv::Vec3d(t.x(), t.y(), t.z())),
                    camera_matrix(camera), distortion(camera), pixels, jacobian);
  Eigen::Matrix<double, Eigen::Dynamic, 4> J(2 * points.size(), 4);
  for (int row = 0; row < J.rows(); ++row) {
    for (int c = 0; c < 4; ++c) J(row, c) = jacobian.at<double>(row, 6 + c);
  }
  return J;
}

TargetObservation tag_correspondences(const TagLayout& layout, const std::vector<TagCorners>& detections,
                                       const PatternPoseOptions& options) {
  TargetObservation result;
  PointCorrespondences points;
  for (const TagCorners& detection : detections) {
    const TagPlacement* tag = layout.find(detection.id);
    if (!tag) continue;
    if (std::find(points.ids.begin(), points.ids.end(), detection.id) != points.ids.end()) {
      result.refusal = "tag " + std::to_string(detection.id) +
                       " is seen twice; two printed copies of one id make the pose ambiguous, remove one";
      return result;
    }
    points.ids.push_back(detection.id);
    const auto corners = tag->corners();
    for (int c = 0; c < 4; ++c) {
      points.object.push_back(corners[c]);
      points.image.push_back(detection.corners[c]);
    }
  }
  if (static_cast<int>(points.ids.size()) < std::max(1, options.min_tags)) {
    result.refusal = "saw " + std::to_string(points.ids.size()) + " of the pattern's tags, need " +
                     std::to_string(std::max(1, options.min_tags)) + "; bring the pattern fully into view";
    return result;
  }
  // The corner noise model, one 8 x 8 block per tag (per unit sigma^2).
  const int n = static_cast<int>(points.object.size());
  points.corner_covariance = Eigen::MatrixXd::Identity(2 * n, 2 * n);
  if (options.corner_noise == CornerNoiseModel::EdgeFit) {
    for (int t = 0; t < n / 4; ++t) {
      std::array<Eigen::Vector2d, 4> corners;
      for (int c = 0; c < 4; ++c) corners[c] = points.image[static_cast<std::size_t>(4 * t + c)];
      points.corner_covariance.block<8, 8>(8 * t, 8 * t) = edge_fit_corner_covariance(corners);
      const Eigen::LLT<Eigen::Matrix<double, 8, 8>> llt(points.corner_covariance.block<8, 8>(8 * t, 8 * t));
      if (llt.info() != Eigen::Success) {
        result.refusal = "tag " + std::to_string(points.ids[static_cast<std::size_t>(t)]) +
                         " is seen edge-on (its corners are nearly collinear)";
        return result;
      }
    }
  }
  points.blocks = 8;
  result.points = points;
  return result;
}

PatternPoseResult estimate_pattern_pose(const TagLayout& layout, const CameraModel& camera,
                                        const std::vector<TagCorners>& detections, PixelNoise& noise,
                                        const PatternPoseOptions& options) {
  const TargetObservation found = tag_correspondences(layout, detections, options);
  if (!found.points) return {std::nullopt, found.refusal};
  return estimate_pose(camera, *found.points, noise, options);
}

PatternPoseResult estimate_pose(const CameraModel& camera, const PointCorrespondences& points, PixelNoise& noise,
                                const PatternPoseOptions& options) {
  PatternPoseResult result;
  const std::vector<Vector3d>& object = points.object;
  std::vector<cv::Point2d> image;
  for (const Eigen::Vector2d& p : points.image) image.emplace_back(p.x(), p.y());
  if (object.size() < 4 || object.size() != image.size()) {
    result.refusal = "PnP needs at least 4 points, got " + std::to_string(object.size());
    return result;
  }

  const cv::Mat K = camera_matrix(camera);
  const cv::Mat D = distortion(camera);
  const std::vector<cv::Point3d> object_cv = cv_points(object);
  cv::Mat rvec, tvec;
  const int method = coplanar(object) ? cv::SOLVEPNP_IPPE : (object.size() >= 6 ? cv::SOLVEPNP_SQPNP : -1);
  if (method < 0 || !cv::solvePnP(object_cv, image, K, D, rvec, tvec, false, method)) {
    result.refusal = "PnP found no pose for " + std::to_string(object.size()) +
                     " points (a non-planar target needs at least 6 in view)";
    return result;
  }
  cv::solvePnPRefineLM(object_cv, image, K, D, rvec, tvec);

  PatternPose pose;
  pose.T_camera_pattern = pose_of(rvec, tvec);
  std::vector<cv::Point2d> projected;
  cv::projectPoints(object_cv, rvec, tvec, K, D, projected);
  double unweighted = 0.0;
  for (std::size_t i = 0; i < image.size(); ++i) {
    const cv::Point2d r = projected[i] - image[i];
    unweighted += r.dot(r);
  }
  pose.points = static_cast<int>(object.size());
  pose.degrees_of_freedom = 2 * pose.points - 6;
  pose.rms_px = std::sqrt(unweighted / (2.0 * pose.points));
  pose.ids = points.ids;
  for (const Vector3d& p : object) {
    if ((pose.T_camera_pattern * p).z() <= 0.0) {
      result.refusal = "the PnP solution puts the pattern behind the camera; check the target's sizes and ids";
      return result;
    }
  }
  if (!(pose.rms_px <= options.max_rms_px)) {
    result.refusal = "reprojection RMS " + number_text(pose.rms_px) + " px exceeds " + number_text(options.max_rms_px) +
                     " px; a point is misdetected or the target file (sizes, positions) does not match the printed target";
    return result;
  }

  // The weights: the inverse of the detector's corner covariance, block by block.
  const int n = pose.points;
  Eigen::MatrixXd weight = Eigen::MatrixXd::Identity(2 * n, 2 * n);
  if (points.corner_covariance.rows() == 2 * n) {
    const int b = std::max(2, points.blocks);
    for (int start = 0; start < 2 * n; start += b) {
      const int size = std::min(b, 2 * n - start);
      weight.block(start, start, size, size) =
          points.corner_covariance.block(start, start, size, size).ldlt().solve(Eigen::MatrixXd::Identity(size, size));
    }
  }
  const auto residuals = [&](const Isometry3d& T) {
    Eigen::VectorXd r(2 * n);
    for (int i = 0; i < n; ++i) r.segment<2>(2 * i) = points.image[static_cast<std::size_t>(i)] - project(camera, T * object[i]);
    return r;
  };
  // Gauss-Newton on the weighted residuals, from the unweighted PnP solution
  // (R = exp([xi]) R, t = t + dt, as the covariance).
  Eigen::Matrix<double, Eigen::Dynamic, 6> J;
  Matrix6d information;
  for (int iteration = 0; iteration < 10; ++iteration) {
    J = reprojection_jacobian(camera, pose.T_camera_pattern, object);
    information = J.transpose() * weight * J;
    const Vector6d step = information.ldlt().solve(J.transpose() * weight * residuals(pose.T_camera_pattern));
    if (!step.allFinite()) break;
    pose.T_camera_pattern = se3::make_pose(so3::exp(step.tail<3>()) * pose.T_camera_pattern.linear(),
                                           pose.T_camera_pattern.translation() + step.head<3>());
    if (step.norm() < 1e-12) break;
  }
  J = reprojection_jacobian(camera, pose.T_camera_pattern, object);
  information = J.transpose() * weight * J;
  const Eigen::VectorXd r = residuals(pose.T_camera_pattern);
  pose.residual_sum_of_squares = r.dot(weight * r);
  const Eigen::SelfAdjointEigenSolver<Matrix6d> eig(information);
  if (!(eig.eigenvalues()(0) > 1e-12 * eig.eigenvalues()(5)) || !pose.T_camera_pattern.matrix().allFinite()) {
    result.refusal = "the points do not constrain all six pose parameters (degenerate view)";
    return result;
  }
  if (noise.degrees_of_freedom() >= 100 && pose.degrees_of_freedom > 0) {
    const double sigma2 = noise.sigma() * noise.sigma(), dof = pose.degrees_of_freedom;
    const double ratio = pose.residual_sum_of_squares / (sigma2 * dof);
    if (ratio > options.max_variance_ratio * (1.0 + 4.0 * std::sqrt(2.0 / dof))) {
      result.refusal = "the residuals are " + number_text(std::sqrt(ratio)) + " times the pooled pixel noise (" +
                       number_text(noise.sigma()) + " px): a point is misdetected (often at the image border, or " +
                       "blurred); the frame is left out";
      return result;
    }
  }
  noise.add(pose.residual_sum_of_squares, pose.degrees_of_freedom);
  pose.pixel_sigma = noise.sigma();
  pose.covariance_variance = noise.covariance_variance();
  pose.covariance = pose.covariance_variance * information.inverse();
  if ((camera.intrinsics_sigma.array() > 0.0).any()) {
    // The intrinsics' own uncertainty: the fit moves the pose by -A dK when the
    // projections move by J_K dK, A = (J^T W J)^-1 J^T W J_K.
    const Eigen::Matrix<double, 6, 4> A =
        information.ldlt().solve(J.transpose() * weight * intrinsics_jacobian(camera, pose.T_camera_pattern, object));
    pose.covariance += A * camera.intrinsics_sigma.cwiseAbs2().asDiagonal() * A.transpose();
  }
  pose.covariance = 0.5 * (pose.covariance + pose.covariance.transpose());
  result.pose = pose;
  return result;
}

PointCorrespondences raw_pixels(const PointCorrespondences& rectified, const CameraModel& camera) {
  check_camera_model(camera, "camera");
  bool distorted = false;
  for (double d : camera.distortion) distorted = distorted || d != 0.0;
  if (!distorted || rectified.image.empty()) return rectified;
  // The raw image has each rectified pixel where OpenCV's model puts its
  // normalised point (normalised_points). d(raw)/d(x, y) is projectPoints'
  // derivative by the translation (the point moves with it).
  const Eigen::Matrix3d K_inverse = camera.K.inverse();
  std::vector<cv::Point2d> raw;
  cv::Mat jacobian;  // 2n x (3 rvec + 3 tvec + 2 f + 2 c + distortion)
  cv::projectPoints(normalised_points(camera, rectified.image), cv::Mat::zeros(3, 1, CV_64F), cv::Mat::zeros(3, 1, CV_64F), camera_matrix(camera),
                    distortion(camera), raw, jacobian);
  PointCorrespondences out = rectified;
  const std::size_t n = rectified.image.size();
  std::vector<Eigen::Matrix2d> J(n);  // d raw / d rectified, per corner
  const Eigen::Matrix2d K2_inverse = K_inverse.topLeftCorner<2, 2>();
  for (std::size_t i = 0; i < n; ++i) {
    out.image[i] = Eigen::Vector2d(raw[i].x, raw[i].y);
    Eigen::Matrix2d d_raw_d_normalised;
    for (int r = 0; r < 2; ++r)
      for (int c = 0; c < 2; ++c) d_raw_d_normalised(r, c) = jacobian.at<double>(static_cast<int>(2 * i) + r, 3 + c);
    J[i] = d_raw_d_normalised * K2_inverse;
  }
  // The covariance is block-diagonal and so is J: J C J^T block by block (a dense
  // product would cost O(n^3) per image, 1 GFLOP for a board of 400 corners).
  const bool identity = rectified.corner_covariance.size() == 0;
  const Eigen::Index s = identity ? 2 : rectified.blocks, m = static_cast<Eigen::Index>(2 * n);
  out.blocks = static_cast<int>(s);
  out.corner_covariance = Eigen::MatrixXd::Zero(m, m);
  for (Eigen::Index start = 0; start < m; start += s) {
    Eigen::MatrixXd Jb = Eigen::MatrixXd::Zero(s, s);
    for (Eigen::Index k = 0; k < s / 2; ++k) Jb.block<2, 2>(2 * k, 2 * k) = J[static_cast<std::size_t>(start / 2 + k)];
    const Eigen::MatrixXd Cb =
        identity ? Eigen::MatrixXd(Eigen::MatrixXd::Identity(s, s)) : Eigen::MatrixXd(rectified.corner_covariance.block(start, start, s, s));
    out.corner_covariance.block(start, start, s, s) = Jb * Cb * Jb.transpose();
  }
  return out;
}

}  // namespace handeye
