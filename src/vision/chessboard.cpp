#include "handeye_covariance/vision/chessboard.h"

#include <algorithm>
#include <cmath>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "handeye_covariance/core/errors.h"

namespace handeye {

void check_chessboard(const ChessboardTarget& t, const std::string& where) {
  if (t.columns < 3 || t.rows < 3) {
    throw HandEyeError(ErrorCode::InvalidLayout,
                       "a chessboard needs at least 3 x 3 inner corners, got " + std::to_string(t.columns) + " x " +
                           std::to_string(t.rows),
                       where, "count the inner corners (where four squares meet), not the squares: a board of 10 x 7 "
                              "squares has 9 x 6 inner corners");
  }
  if (!(t.square > 0.0) || !std::isfinite(t.square)) {
    throw HandEyeError(ErrorCode::InvalidLayout, "the square size must be a positive length in m", where,
                       "measure one printed square's edge, e.g. square: 0.0236");
  }
  // A symmetric board (columns + rows even) is read: its pose is one of two
  // candidates, decided from the robot's motion (estimation/symmetric_views.h). A
  // square one also looks the same turned by 90 degrees (its rows become its
  // columns): four candidates, which neither its colours nor a half turn tell apart.
  if (t.columns == t.rows) {
    throw HandEyeError(ErrorCode::InvalidLayout,
                       "a board of " + std::to_string(t.columns) + " x " + std::to_string(t.rows) +
                           " inner corners looks the same turned by 90 degrees, so its pose is ambiguous",
                       where, "use a board with different numbers of inner corners along its two sides (e.g. 9 x 6), "
                              "or ChArUco");
  }
}

std::vector<Eigen::Vector3d> chessboard_points(const ChessboardTarget& t) {
  std::vector<Eigen::Vector3d> points;
  for (int r = 0; r < t.rows; ++r) {
    for (int c = 0; c < t.columns; ++c) points.emplace_back(c * t.square, r * t.square, 0.0);
  }
  return points;
}

namespace {

/// The gray level at a sub-pixel point (bilinear), or -1 outside the image.
double gray_at(const cv::Mat& gray, const cv::Point2f& p) {
  if (!(p.x >= 0.0f && p.y >= 0.0f && p.x < gray.cols - 1.0f && p.y < gray.rows - 1.0f)) return -1.0;
  cv::Mat patch;
  cv::getRectSubPix(gray, cv::Size(3, 3), p, patch, CV_32F);
  return cv::mean(patch)[0];
}

/// OpenCV's frame (chessboard.h), whatever order a detector lists the corners in.
/// Handedness: seen from the camera, the board's x (along a row) and y (down the
/// rows) turn like the image's x and y (z points into the board); a mirrored
/// list has its rows reversed. Origin: the square between the first corner and
/// its diagonal neighbour is white (the one outside it is white too, but may be
/// out of the image), the next square along the row black; a list that starts
/// at the other end of the board sees them the other way round and is reversed.
/// A symmetric board (columns + rows even, core/target.h is_half_turn_symmetric)
/// has the same colours at both ends: the two orders cannot be told apart, and
/// whichever OpenCV gave is kept. Its pose is then one of two candidates, P and
/// P * half_turn(target), decided later from the robot's motion.
void put_in_opencv_frame(const cv::Mat& gray, const ChessboardTarget& t, std::vector<cv::Point2f>& corners) {
  const std::size_t columns = static_cast<std::size_t>(t.columns);
  const cv::Point2f along_row = corners[1] - corners[0], down = corners[columns] - corners[0];
  if (along_row.x * down.y - along_row.y * down.x < 0.0f) {
    for (int r = 0; r < t.rows; ++r) {
      std::reverse(corners.begin() + r * t.columns, corners.begin() + (r + 1) * t.columns);
    }
  }
  if (is_half_turn_symmetric(make_target(t))) return;
  const double first_square = gray_at(gray, 0.5f * (corners[0] + corners[columns + 1]));
  const double next_square = gray_at(gray, 0.5f * (corners[1] + corners[columns + 2]));
  if (first_square < next_square) std::reverse(corners.begin(), corners.end());
}

/// A corner closer to the border than its window is half outside the image:
/// OpenCV places it, but badly (1.3 px off on a rendered board).
bool clear_of_border(const cv::Mat& image, const cv::Point2f& p, int half_window) {
  const float margin = static_cast<float>(half_window + 2);
  return p.x >= margin && p.y >= margin && p.x <= image.cols - 1 - margin && p.y <= image.rows - 1 - margin;
}

}  // namespace

int saddle_window(float spacing) { return std::max(2, std::min(5, static_cast<int>(0.4f * spacing))); }

int refine_saddle_points(const cv::Mat& gray, std::vector<cv::Point2f>& corners, float spacing) {
  // cornerSubPix converges on each saddle point: measured on rendered boards
  // (test_targets) the sector detector's own corners are biased outwards by
  // 0.02-0.03 px with an RMS error of 0.07 px; refined, 0.002 px and 0.025 px.
  // The window stays inside the squares around the corner.
  const int half_window = saddle_window(spacing);
  cv::cornerSubPix(gray, corners, cv::Size(half_window, half_window), cv::Size(-1, -1),
                   cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 100, 1e-4));
  return half_window;
}

void refine_saddle_points_in_raw_image(const cv::Mat& raw_gray, const ImageRectifier& rectifier, int half_window,
                                       std::vector<Eigen::Vector2d>& rectified_pixels) {
  if (!rectifier.distorted() || rectified_pixels.empty() || half_window <= 0) return;
  const std::vector<cv::Point2f> start = rectifier.to_raw(rectified_pixels);
  std::vector<cv::Point2f> inside;
  std::vector<std::size_t> which;
  for (std::size_t i = 0; i < start.size(); ++i) {
    if (clear_of_border(raw_gray, start[i], half_window)) {
      inside.push_back(start[i]);
      which.push_back(i);
    }
  }
  if (inside.empty()) return;
  cv::cornerSubPix(raw_gray, inside, cv::Size(half_window, half_window), cv::Size(-1, -1),
                   cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 100, 1e-4));
  const std::vector<Eigen::Vector2d> back = rectifier.from_raw(inside);
  for (std::size_t k = 0; k < which.size(); ++k) rectified_pixels[which[k]] = back[k];
}

TargetObservation detect_chessboard(const cv::Mat& gray, const ChessboardTarget& t) {
  TargetObservation out;
  if (gray.type() != CV_8UC1) {
    throw HandEyeError(ErrorCode::MalformedFile, "the image is not 8-bit single-channel", "detect_chessboard",
                       "convert it to mono8 first");
  }
  const cv::Size size(t.columns, t.rows);
  std::vector<cv::Point2f> corners;
  // The classic detector is fast; the sector-based one finds boards it misses
  // (blur, steep views), exhaustively at 5-10x the time, so last.
  bool found = cv::findChessboardCorners(gray, size, corners, cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE);
  if (!found) found = cv::findChessboardCornersSB(gray, size, corners, cv::CALIB_CB_EXHAUSTIVE);
  if (!found || static_cast<int>(corners.size()) != t.columns * t.rows) {
    out.refusal = "no " + std::to_string(t.columns) + " x " + std::to_string(t.rows) +
                  " chessboard found (is the whole board in view, and are these its inner corners?)";
    return out;
  }
  put_in_opencv_frame(gray, t, corners);
  float spacing = INFINITY;
  for (int r = 0; r < t.rows; ++r) {
    for (int c = 0; c + 1 < t.columns; ++c) {
      const int i = r * t.columns + c;
      spacing = std::min(spacing, static_cast<float>(cv::norm(corners[i + 1] - corners[i])));
    }
  }
  for (const cv::Point2f& c : corners) {
    if (!clear_of_border(gray, c, saddle_window(spacing))) {
      out.refusal = "the chessboard touches the image border; bring the whole board, with a margin, into view";
      return out;
    }
  }
  out.saddle_half_window = refine_saddle_points(gray, corners, spacing);
  PointCorrespondences points;
  points.object = chessboard_points(t);
  for (std::size_t i = 0; i < corners.size(); ++i) {
    points.image.emplace_back(corners[i].x, corners[i].y);
    points.ids.push_back(static_cast<int>(i));
  }
  points.blocks = 2;  // independent corners (identity per corner)
  out.points = points;
  return out;
}

}  // namespace handeye
