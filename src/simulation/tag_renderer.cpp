#include "handeye_covariance/simulation/tag_renderer.h"

#include <Eigen/Dense>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/vision/tag_detector.h"

namespace handeye {
namespace {

using Eigen::Isometry3d;
using Eigen::Matrix3d;
using Eigen::Vector3d;

bool planar_z0(const TagLayout& layout) {
  for (const TagPlacement& tag : layout.tags) {
    if (std::abs(tag.T_pattern_tag.translation().z()) > 1e-9) return false;
    if ((tag.T_pattern_tag.linear().col(2) - Vector3d::UnitZ()).norm() > 1e-9) return false;
  }
  return true;
}

cv::Matx33d to_cv(const Matrix3d& m) {
  cv::Matx33d out;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) out(r, c) = m(r, c);
  return out;
}

}  // namespace

CameraModel simulated_camera() {
  CameraModel camera;
  camera.width = 640;
  camera.height = 480;
  camera.K << 600.0, 0.0, 319.5, 0.0, 600.0, 239.5, 0.0, 0.0, 1.0;
  camera.distortion = {-0.12, 0.08, 0.0005, -0.0003, 0.0};
  return camera;
}

TagRenderer::TagRenderer(const TagLayout& layout, const CameraModel& camera, const RenderOptions& options)
    : layout_(layout), camera_(camera), options_(options) {
  check_layout(layout, "renderer layout");
  check_camera_model(camera, "renderer camera");
  if (camera.width <= 0 || camera.height <= 0) {
    throw HandEyeError(ErrorCode::MalformedFile, "the camera has no image size", "renderer camera",
                       "set width and height");
  }
  double min_x = INFINITY, max_x = -INFINITY, min_y = INFINITY, max_y = -INFINITY, cell = 0.0;
  for (const TagPlacement& placement : layout.tags) {
    const TagBitmap bitmap = tag_bitmap(layout.family, placement.id);
    Tag tag;
    cv::Mat upscaled;
    cv::resize(bitmap.pixels, upscaled, cv::Size(), options.texels_per_cell, options.texels_per_cell, cv::INTER_NEAREST);
    // libapriltag's bitmap: 0 black, 255 white, and 0-alpha pixels outside a
    // circle tag's quiet zone would read as white here too.
    upscaled.convertTo(tag.texture, CV_32F, (options.white - options.black) / 255.0, options.black);
    cell = placement.size / bitmap.width_at_border;
    tag.texture_width = cell * bitmap.pixels.cols;
    tag.T_pattern_tag = placement.T_pattern_tag;
    tags_.push_back(tag);
    for (const Vector3d& c : {Vector3d(-0.5, -0.5, 0), Vector3d(0.5, 0.5, 0)}) {
      const Vector3d p = placement.T_pattern_tag * (c * tag.texture_width);
      min_x = std::min(min_x, p.x());
      max_x = std::max(max_x, p.x());
      min_y = std::min(min_y, p.y());
      max_y = std::max(max_y, p.y());
    }
  }
  if (planar_z0(layout)) {
    const double m = options.board_margin_cells * cell;
    board_corners_ = {Vector3d(min_x - m, min_y - m, 0), Vector3d(max_x + m, min_y - m, 0),
                      Vector3d(max_x + m, max_y + m, 0), Vector3d(min_x - m, max_y + m, 0)};
  }
  // For each distorted (sensor) pixel, the ideal pinhole pixel it sees.
  std::vector<cv::Point2f> sensor;
  sensor.reserve(static_cast<std::size_t>(camera.width) * camera.height);
  for (int v = 0; v < camera.height; ++v)
    for (int u = 0; u < camera.width; ++u) sensor.emplace_back(static_cast<float>(u), static_cast<float>(v));
  std::vector<cv::Point2f> ideal;
  const cv::Mat K(to_cv(camera.K));
  const cv::Mat D = camera.distortion.empty() ? cv::Mat::zeros(1, 4, CV_64F) : cv::Mat(camera.distortion, true).reshape(1, 1);
  cv::undistortPoints(sensor, ideal, K, D, cv::noArray(), K,
                      cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 50, 1e-6));
  map_x_.create(camera.height, camera.width, CV_32F);
  map_y_.create(camera.height, camera.width, CV_32F);
  for (int v = 0; v < camera.height; ++v) {
    for (int u = 0; u < camera.width; ++u) {
      map_x_.at<float>(v, u) = ideal[static_cast<std::size_t>(v) * camera.width + u].x;
      map_y_.at<float>(v, u) = ideal[static_cast<std::size_t>(v) * camera.width + u].y;
    }
  }
}

cv::Mat TagRenderer::render(const Isometry3d& T_camera_pattern, Rng& rng) const {
  const int s = std::max(1, options_.supersample);
  // Ideal pixel (x, y) -> supersampled pixel: pixel centres at integers in both.
  Matrix3d S;
  S << s, 0, 0.5 * (s - 1), 0, s, 0.5 * (s - 1), 0, 0, 1;
  const Matrix3d KS = S * camera_.K;
  cv::Mat canvas(camera_.height * s, camera_.width * s, CV_32F, cv::Scalar(options_.background));

  const auto project = [&](const Vector3d& p_camera) {
    const Vector3d h = KS * p_camera;
    return cv::Point2f(static_cast<float>(h.x() / h.z()), static_cast<float>(h.y() / h.z()));
  };
  if (!board_corners_.empty()) {
    std::vector<cv::Point> polygon;
    bool visible = true;
    for (const Vector3d& c : board_corners_) {
      const Vector3d p = T_camera_pattern * c;
      visible = visible && p.z() > 1e-3;
      const cv::Point2f q = project(p);
      polygon.emplace_back(cvRound(q.x * 16), cvRound(q.y * 16));  // 4 fractional bits
    }
    if (visible) cv::fillConvexPoly(canvas, polygon, cv::Scalar(options_.white), cv::LINE_AA, 4);
  }
  const cv::Rect frame(0, 0, canvas.cols, canvas.rows);
  for (const Tag& tag : tags_) {
    const Isometry3d T_camera_tag = T_camera_pattern * tag.T_pattern_tag;
    const double W = tag.texture.cols;
    // Texel (u, v) (row down) -> tag plane (x right, y up): centre texels at +-(W-1)/2.
    Matrix3d M;
    M << tag.texture_width / W, 0, -0.5 * tag.texture_width * (W - 1) / W, 0, -tag.texture_width / W,
        0.5 * tag.texture_width * (W - 1) / W, 0, 0, 1;
    Matrix3d plane;  // [r1 r2 t]: tag plane -> camera
    plane.col(0) = T_camera_tag.linear().col(0);
    plane.col(1) = T_camera_tag.linear().col(1);
    plane.col(2) = T_camera_tag.translation();
    const Matrix3d H = KS * plane * M;
    std::vector<cv::Point2f> outline;
    bool visible = true;
    const double lo = -0.5, hi = W - 0.5;
    for (const auto& texel : {Eigen::Vector2d(lo, lo), Eigen::Vector2d(hi, lo), Eigen::Vector2d(hi, hi), Eigen::Vector2d(lo, hi)}) {
      const Vector3d q = plane * M * Vector3d(texel.x(), texel.y(), 1.0);
      visible = visible && q.z() > 1e-3;
      const Vector3d h = KS * q;
      outline.emplace_back(static_cast<float>(h.x() / h.z()), static_cast<float>(h.y() / h.z()));
    }
    if (!visible) continue;
    cv::Rect bounds = cv::boundingRect(outline);
    bounds = cv::Rect(bounds.x - 2, bounds.y - 2, bounds.width + 4, bounds.height + 4);
    const cv::Rect roi = bounds & frame;
    if (roi.empty()) continue;
    Matrix3d shift = Matrix3d::Identity();
    shift(0, 2) = -roi.x;
    shift(1, 2) = -roi.y;
    cv::Mat target = canvas(roi);
    cv::warpPerspective(tag.texture, target, to_cv(shift * H), target.size(), cv::INTER_LINEAR, cv::BORDER_TRANSPARENT);
  }
  if (options_.blur_sigma_px > 0.0) cv::GaussianBlur(canvas, canvas, cv::Size(), options_.blur_sigma_px * s);
  cv::Mat ideal;
  cv::resize(canvas, ideal, cv::Size(camera_.width, camera_.height), 0, 0, cv::INTER_AREA);
  cv::Mat sensor;
  cv::remap(ideal, sensor, map_x_, map_y_, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  if (options_.noise_sigma > 0.0) {
    cv::Mat noise(sensor.size(), CV_32F);
    cv::RNG cv_rng(rng());
    cv_rng.fill(noise, cv::RNG::NORMAL, 0.0, options_.noise_sigma);
    sensor += noise;
  }
  cv::Mat out;
  sensor.convertTo(out, CV_8U);  // rounds and saturates
  return out;
}

}  // namespace handeye
