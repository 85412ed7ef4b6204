#include "handeye_covariance/vision/chessboard.h"

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
  if (t.columns % 2 == t.rows % 2) {
    throw HandEyeError(ErrorCode::InvalidLayout,
                       "a board of " + std::to_string(t.columns) + " x " + std::to_string(t.rows) +
                           " inner corners looks the same turned by 180 degrees, so its pose is ambiguous",
                       where, "use a board with one even and one odd number of inner corners (e.g. 9 x 6), or ChArUco");
  }
}

std::vector<Eigen::Vector3d> chessboard_points(const ChessboardTarget& t) {
  std::vector<Eigen::Vector3d> points;
  for (int r = 0; r < t.rows; ++r) {
    for (int c = 0; c < t.columns; ++c) points.emplace_back(c * t.square, r * t.square, 0.0);
  }
  return points;
}

ChessboardDetection detect_chessboard(const cv::Mat& gray, const ChessboardTarget& t) {
  ChessboardDetection out;
  std::vector<cv::Point2f> corners;
  const bool found = cv::findChessboardCornersSB(gray, cv::Size(t.columns, t.rows), corners,
                                                 cv::CALIB_CB_EXHAUSTIVE | cv::CALIB_CB_ACCURACY);
  if (!found || static_cast<int>(corners.size()) != t.columns * t.rows) {
    out.refusal = "no " + std::to_string(t.columns) + " x " + std::to_string(t.rows) +
                  " chessboard found (is the whole board in view, and are these its inner corners?)";
    return out;
  }
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
