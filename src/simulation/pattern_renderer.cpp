#include "handeye_covariance/simulation/pattern_renderer.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "handeye_covariance/core/errors.h"

namespace handeye {
namespace {

using Eigen::Isometry3d;
using Eigen::Matrix3d;
using Eigen::Vector3d;

/// Every marker in the pattern's z = 0 plane, facing either way.
bool planar_z0(const TagLayout& layout) {
  for (const TagPlacement& tag : layout.tags) {
    if (std::abs(tag.T_pattern_tag.translation().z()) > 1e-9) return false;
    if (std::abs(std::abs(tag.T_pattern_tag.linear()(2, 2)) - 1.0) > 1e-9) return false;
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

// Each kind's drawing (src/simulation/targets/; the markers' below), listed once.
RenderKind chessboard_render();
RenderKind charuco_render();

const std::vector<RenderKind>& render_kinds() {
  const auto markers = [](const Target& target, const RenderOptions& options) {
    return marker_planes(target.as<TagLayout>(), options);
  };
  static const std::vector<RenderKind> kinds = {chessboard_render(), charuco_render(), {"aruco", markers},
                                                {"apriltag", markers}};
  return kinds;
}

const RenderKind& render_kind(const std::string& name) {
  return layer_entry(render_kinds(), name, "drawing", "renderer", "RenderKind", "src/simulation/pattern_renderer.cpp");
}

TargetPlanes marker_planes(const TagLayout& layout, const RenderOptions& options) {
  TargetPlanes out;
  double min_x = INFINITY, max_x = -INFINITY, min_y = INFINITY, max_y = -INFINITY, cell = 0.0;
  for (const TagPlacement& placement : layout.tags) {
    const TagBitmap bitmap = tag_bitmap(layout.family, placement.id);
    cv::Mat upscaled;
    cv::resize(bitmap.pixels, upscaled, cv::Size(), options.texels_per_cell, options.texels_per_cell, cv::INTER_NEAREST);
    // libapriltag's bitmap: 0-alpha pixels outside a circle tag's quiet zone read as white here too.
    cell = placement.size / bitmap.width_at_border;
    const double width = cell * bitmap.pixels.cols;
    out.planes.push_back({upscaled, placement.T_pattern_tag, width, width});
    for (const Vector3d& c : {Vector3d(-0.5, -0.5, 0), Vector3d(0.5, 0.5, 0)}) {
      const Vector3d p = placement.T_pattern_tag * (c * width);
      min_x = std::min(min_x, p.x());
      max_x = std::max(max_x, p.x());
      min_y = std::min(min_y, p.y());
      max_y = std::max(max_y, p.y());
    }
  }
  if (planar_z0(layout)) {
    const double m = options.board_margin_cells * cell;
    out.board_corners = {Vector3d(min_x - m, min_y - m, 0), Vector3d(max_x + m, min_y - m, 0),
                         Vector3d(max_x + m, max_y + m, 0), Vector3d(min_x - m, max_y + m, 0)};
  }
  return out;
}

PatternRenderer::PatternRenderer(const TagLayout& layout, const CameraModel& camera, const RenderOptions& options)
    : PatternRenderer(make_target(layout), camera, options) {}

PatternRenderer::PatternRenderer(const Target& target, const CameraModel& camera, const RenderOptions& options)
    : camera_(camera), options_(options) {
  check_target(target, "renderer target");
  check_camera_model(camera, "renderer camera");
  if (camera.width <= 0 || camera.height <= 0) {
    throw HandEyeError(ErrorCode::MalformedFile, "the camera has no image size", "renderer camera",
                       "set width and height");
  }
  TargetPlanes drawn = render_kind(target.kind_name()).draw(target, options);
  for (PrintedPlane& plane : drawn.planes) {
    // 0 black, 255 white in every source bitmap.
    cv::Mat gray;
    plane.texture.convertTo(gray, CV_32F, (options_.white - options_.black) / 255.0, options_.black);
    plane.texture = gray;
    std::vector<cv::Mat> pyramid;
    for (cv::Mat level = gray; level.cols > 1 || level.rows > 1;) {
      cv::Mat half;  // each texel the mean of the finer texels it covers (a side of odd length: area weights)
      cv::resize(level, half, cv::Size((level.cols + 1) / 2, (level.rows + 1) / 2), 0, 0, cv::INTER_AREA);
      pyramid.push_back(half);
      level = half;
    }
    pyramids_.push_back(std::move(pyramid));
    planes_.push_back(std::move(plane));
  }
  board_corners_ = std::move(drawn.board_corners);
  build_distortion_map();
}

void PatternRenderer::build_distortion_map() {
  // For each distorted (sensor) pixel, the ideal pinhole pixel it sees.
  std::vector<cv::Point2f> sensor;
  sensor.reserve(static_cast<std::size_t>(camera_.width) * camera_.height);
  for (int v = 0; v < camera_.height; ++v)
    for (int u = 0; u < camera_.width; ++u) sensor.emplace_back(static_cast<float>(u), static_cast<float>(v));
  std::vector<cv::Point2f> ideal;
  const cv::Mat K(to_cv(camera_.K));
  const cv::Mat D =
      camera_.distortion.empty() ? cv::Mat::zeros(1, 4, CV_64F) : cv::Mat(camera_.distortion, true).reshape(1, 1);
  cv::undistortPoints(sensor, ideal, K, D, cv::noArray(), K,
                      cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 50, 1e-6));
  // The sensor sees beyond the ideal image's frame (barrel distortion: about 13 px at
  // the simulated camera's corners): the ideal image is rendered with a margin that
  // covers all of it, not its border replicated there.
  double overshoot = 0.0;
  for (const cv::Point2f& p : ideal) {
    overshoot = std::max({overshoot, -static_cast<double>(p.x), -static_cast<double>(p.y), p.x - (camera_.width - 1.0),
                          p.y - (camera_.height - 1.0)});
  }
  if (!(overshoot <= std::max(camera_.width, camera_.height))) {
    throw HandEyeError(ErrorCode::MalformedFile,
                       "the distortion maps the image's edge " + std::to_string(overshoot) + " px beyond its frame",
                       "renderer camera", "check the distortion coefficients (OpenCV's order: k1, k2, p1, p2, k3)");
  }
  ideal_margin_ = static_cast<int>(std::ceil(overshoot)) + 2;
  const int s = std::max(1, options_.supersample);
  canvas_size_ = cv::Size((camera_.width + 2 * ideal_margin_) * s, (camera_.height + 2 * ideal_margin_) * s);
  cv::Mat map_x(camera_.height, camera_.width, CV_32F), map_y(camera_.height, camera_.width, CV_32F);
  for (int v = 0; v < camera_.height; ++v) {
    for (int u = 0; u < camera_.width; ++u) {
      map_x.at<float>(v, u) = ideal[static_cast<std::size_t>(v) * camera_.width + u].x + static_cast<float>(ideal_margin_);
      map_y.at<float>(v, u) = ideal[static_cast<std::size_t>(v) * camera_.width + u].y + static_cast<float>(ideal_margin_);
    }
  }
  // The distortion is applied at the supersampled resolution, and the sensor's
  // pixels are area averages of the distorted image. Remapping the 1x ideal image
  // instead (bilinear between its pixels, then again when a detector rectifies)
  // moved the saddle points towards the image centre: ChArUco corners by 0.0014 px
  // on average over 100 rendered sessions (none without distortion), X's RMS error
  // 1.24x the corner model's bound in translation (0.97x without distortion).
  // The map is smooth: interpolating it to the supersampled grid (resize's pixel
  // centres are the renderer's) is exact to ~1e-5 px.
  cv::resize(map_x, map_x_, cv::Size(camera_.width * s, camera_.height * s), 0, 0, cv::INTER_LINEAR);
  cv::resize(map_y, map_y_, cv::Size(camera_.width * s, camera_.height * s), 0, 0, cv::INTER_LINEAR);
  map_x_ = map_x_ * s + 0.5 * (s - 1);  // ideal pixel -> supersampled canvas pixel
  map_y_ = map_y_ * s + 0.5 * (s - 1);
  // Which canvas pixels each tile of the distorted image reads (bilinear: the pixel at
  // the map's floor and the next), so that a render remaps only the tiles that can see
  // the target.
  map_tiles_.clear();
  constexpr int kTile = 32;
  for (int y = 0; y < map_x_.rows; y += kTile) {
    for (int x = 0; x < map_x_.cols; x += kTile) {
      MapTile tile;
      tile.distorted = cv::Rect(x, y, std::min(kTile, map_x_.cols - x), std::min(kTile, map_x_.rows - y));
      double x_min, x_max, y_min, y_max;
      cv::minMaxLoc(map_x_(tile.distorted), &x_min, &x_max);
      cv::minMaxLoc(map_y_(tile.distorted), &y_min, &y_max);
      // Clamped to the canvas, as BORDER_REPLICATE reads beyond it (the margin keeps the maps inside).
      const int columns = canvas_size_.width, rows = canvas_size_.height;
      const auto clamp = [](double v, int n) { return std::clamp(static_cast<int>(std::floor(v)), 0, n - 1); };
      const int left = clamp(x_min, columns), top = clamp(y_min, rows);
      tile.reads = cv::Rect(left, top, std::min(clamp(x_max, columns) + 1, columns - 1) + 1 - left,
                            std::min(clamp(y_max, rows) + 1, rows - 1) + 1 - top);
      map_tiles_.push_back(tile);
    }
  }
}

cv::Mat PatternRenderer::render(const Isometry3d& T_camera_pattern, Rng& rng) const {
  const int s = std::max(1, options_.supersample);
  // Ideal pixel (x, y) -> supersampled pixel: pixel centres at integers in both.
  Matrix3d S;
  S << s, 0, 0.5 * (s - 1), 0, s, 0.5 * (s - 1), 0, 0, 1;
  Matrix3d K = camera_.K;  // the ideal image, with its margin on every side
  K(0, 2) += ideal_margin_;
  K(1, 2) += ideal_margin_;
  const Matrix3d KS = S * K;
  // The supersampled images are about 12 MB each for a 640 x 480 camera: kept per thread,
  // not allocated (and page-faulted in) for every render.
  thread_local cv::Mat canvas, distorted;
  canvas.create(canvas_size_, CV_32F);
  canvas.setTo(cv::Scalar(options_.background));
  const cv::Rect frame(0, 0, canvas.cols, canvas.rows);
  cv::Rect drawn;  // what differs from the background

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
    if (visible) {
      cv::fillConvexPoly(canvas, polygon, cv::Scalar(options_.white), cv::LINE_AA, 4);
      const cv::Rect fixed = cv::boundingRect(polygon);  // in 1/16 pixels
      drawn |= cv::Rect(fixed.x / 16 - 2, fixed.y / 16 - 2, fixed.width / 16 + 5, fixed.height / 16 + 5);
    }
  }
  for (std::size_t p = 0; p < planes_.size(); ++p) {
    const PrintedPlane& plane = planes_[p];
    const Isometry3d T_camera_plane = T_camera_pattern * plane.T_pattern_plane;
    Matrix3d on_plane;  // [r1 r2 t]: plane -> camera
    on_plane.col(0) = T_camera_plane.linear().col(0);
    on_plane.col(1) = T_camera_plane.linear().col(1);
    on_plane.col(2) = T_camera_plane.translation();
    // Texel (u, v) (row down) -> plane (x right, y up): centre texels at +-(W-1)/2.
    const auto texel_to_plane = [&plane](const cv::Mat& texture) {
      const double W = texture.cols, H_texels = texture.rows;
      Matrix3d M;
      M << plane.width / W, 0, -0.5 * plane.width * (W - 1) / W, 0, -plane.height / H_texels,
          0.5 * plane.height * (H_texels - 1) / H_texels, 0, 0, 1;
      return M;
    };
    // warpPerspective samples the texture at each canvas pixel's centre (bilinearly): texels
    // smaller than the canvas's pixels are skipped, and a square's edge lands by the phase of
    // the two grids (on the simulated arm's pixel-aligned views, 96 texels a 20 mm square at
    // 0.5 m, 0.75 canvas px a texel: every corner of a view off by the same 0.02 px). The
    // texture is taken from the finest level whose texels span a canvas pixel or more, where
    // they are smallest on the plane (its corners; a homography's scale changes monotonically).
    const cv::Mat* texture = &plane.texture;
    for (std::size_t level = 0;; ++level) {
      const double W = texture->cols, H_texels = texture->rows;
      const Matrix3d H = KS * on_plane * texel_to_plane(*texture);
      double smallest = INFINITY;  // canvas px a texel spans, least over the plane's corners and directions
      for (const auto& texel : {Eigen::Vector2d(-0.5, -0.5), Eigen::Vector2d(W - 0.5, -0.5),
                                Eigen::Vector2d(W - 0.5, H_texels - 0.5), Eigen::Vector2d(-0.5, H_texels - 0.5)}) {
        const Vector3d h = H * Vector3d(texel.x(), texel.y(), 1.0);
        if (!(h.z() > 0.0)) continue;
        Eigen::Matrix2d J;  // d canvas / d texel
        J.col(0) = (H.block<2, 1>(0, 0) - h.head<2>() / h.z() * H(2, 0)) / h.z();
        J.col(1) = (H.block<2, 1>(0, 1) - h.head<2>() / h.z() * H(2, 1)) / h.z();
        smallest = std::min(smallest, Eigen::JacobiSVD<Eigen::Matrix2d>(J).singularValues()(1));
      }
      if (!(smallest < 1.0) || level >= pyramids_[p].size()) break;
      texture = &pyramids_[p][level];
    }
    const double W = texture->cols, H_texels = texture->rows;
    const Matrix3d M = texel_to_plane(*texture);
    const Matrix3d H = KS * on_plane * M;
    std::vector<cv::Point2f> outline;
    bool visible = true;
    for (const auto& texel : {Eigen::Vector2d(-0.5, -0.5), Eigen::Vector2d(W - 0.5, -0.5),
                              Eigen::Vector2d(W - 0.5, H_texels - 0.5), Eigen::Vector2d(-0.5, H_texels - 0.5)}) {
      const Vector3d q = on_plane * M * Vector3d(texel.x(), texel.y(), 1.0);
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
    cv::warpPerspective(*texture, target, to_cv(shift * H), target.size(), cv::INTER_LINEAR, cv::BORDER_TRANSPARENT);
    drawn |= roi;
  }
  cv::Rect changed = drawn;  // the canvas differs from the background only here
  if (options_.blur_sigma_px > 0.0) {
    // Blurred where the target is, out to the kernel's reach (OpenCV's Gaussian for float
    // images spans 4 sigma); the background beyond is uniform, which the blur leaves as it
    // is. A filter on a sub-matrix reads the pixels around it, so the result there is the
    // whole canvas's blur, at a fraction of its cost.
    const double sigma = options_.blur_sigma_px * s;
    const int reach = static_cast<int>(std::ceil(4.0 * sigma)) + 2;
    const cv::Rect blurred = cv::Rect(drawn.x - reach, drawn.y - reach, drawn.width + 2 * reach, drawn.height + 2 * reach) & frame;
    if (!drawn.empty() && !blurred.empty()) {
      cv::Mat region = canvas(blurred);
      cv::GaussianBlur(region, region, cv::Size(), sigma);
      changed = blurred;
    }
  }
  // Distorted: the background, and the tiles that read the changed part of the canvas
  // remapped (a map's values are canvas coordinates, so a tile's maps remap on their own).
  distorted.create(map_x_.size(), CV_32F);
  distorted.setTo(cv::Scalar(options_.background));
  cv::Rect remapped;
  if (!changed.empty()) {
    for (const MapTile& tile : map_tiles_) {
      if (!(tile.reads & changed).empty()) remapped |= tile.distorted;
    }
  }
  if (!remapped.empty()) {
    cv::Mat into = distorted(remapped);
    cv::remap(canvas, into, map_x_(remapped), map_y_(remapped), cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  }
  cv::Mat sensor;
  cv::resize(distorted, sensor, cv::Size(camera_.width, camera_.height), 0, 0, cv::INTER_AREA);
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
