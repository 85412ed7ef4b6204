// A printed chessboard as a calibration target (no ROS): OpenCV's
// findChessboardCornersSB finds the inner corners to sub-pixel accuracy, and
// estimate_pose (pattern_pose.h) gives the board's pose with its covariance.
//
// The pattern frame is OpenCV's calibration convention: the origin at the first
// inner corner OpenCV reports, which is the corner whose outer diagonal square is
// white (the board's colours fix it); x along the board's `columns` corners, y
// along its `rows`, z into the board (away from a camera that sees it).
// A board whose numbers of inner corners are both even or both odd (e.g. 9 x 7)
// looks the same turned by 180 degrees about its centre (core/target.h
// is_half_turn_symmetric): the colours cannot tell its two ends apart, so the
// corner order OpenCV gave is kept and the pose is one of two candidates, P or
// P * half_turn(target), decided later from the robot's motion
// (estimation/symmetric_views.h, decide_half_turns). A square board (as many
// corners each way) also looks the same turned by 90 degrees, and is refused.
// Detection: OpenCV's classic detector (the sector-based one when it fails), the
// origin checked by the colours, then cornerSubPix on every corner.
// Corner noise: each corner independent, the same sigma in x and y (cornerSubPix
// fits each corner on its own), pooled from the residuals.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "handeye_covariance/core/targets/chessboard.h"
#include "handeye_covariance/vision/pattern_pose.h"

namespace handeye {

/// Throws HandEyeError(InvalidLayout) for fewer than 3 corners either way, a
/// square that is not a positive length, or a square board (as many corners each
/// way: four candidate poses). A board symmetric by a half turn is accepted (above).
void check_chessboard(const ChessboardTarget& target, const std::string& where);

/// The inner corners in the pattern frame, in OpenCV's order (row by row).
std::vector<Eigen::Vector3d> chessboard_points(const ChessboardTarget& target);

/// cornerSubPix to convergence on chessboard saddle points (chessboards and
/// ChArUco boards), with a half window of 0.4 x `spacing` (the smallest distance
/// between neighbouring corners, px), 2 to 5 px. Returns the half window.
int refine_saddle_points(const cv::Mat& gray, std::vector<cv::Point2f>& corners, float spacing);
int saddle_window(float spacing);

/// Saddle points found in the rectified image, refined again in the raw image
/// they came from (cornerSubPix, the same half window) and carried back to
/// rectified pixels. Why: a sensor's pixels average the light over their own
/// area, and any resampling moves a saddle point's fit. Measured on rendered
/// sessions (corners_study --corner-bias, k1 = -0.12), the mean shift towards
/// the image centre: 0.012 px on the bilinearly rectified image, 0.0016 px on
/// the Lanczos-rectified one, 0.0008 px refined in the raw image. A corner whose
/// window leaves the raw image keeps its rectified position.
void refine_saddle_points_in_raw_image(const cv::Mat& raw_gray, const ImageRectifier& rectifier, int half_window,
                                       std::vector<Eigen::Vector2d>& rectified_pixels);

/// The board's inner corners in an 8-bit image (every corner, or a refusal).
TargetObservation detect_chessboard(const cv::Mat& gray, const ChessboardTarget& target);

}  // namespace handeye
