// The pattern pose from detected tag corners, with its covariance (no ROS).
//
// PnP on every corner of every detected tag of the layout (OpenCV: IPPE for a
// planar pattern, then Levenberg-Marquardt), distortion included. The
// covariance is first-order: Sigma = sigma_px^2 (J^T J)^-1, with J the
// reprojection Jacobian d(pixels)/d(pose perturbation) in the package's
// convention (ROS order, translation t = t_hat + dt, rotation R = exp([xi]) R_hat,
// both in the camera frame). J comes from cv::projectPoints's own derivatives,
// so the distortion model is differentiated by the library that applies it.
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <deque>
#include <optional>
#include <string>
#include <vector>

#include "handeye_covariance/core/camera.h"
#include "handeye_covariance/core/pose_covariance.h"
#include "handeye_covariance/core/tag_layout.h"
#include "handeye_covariance/vision/tag_detector.h"

namespace handeye {

/// The pixel of a point in the camera frame (z > 0), by cv::projectPoints.
Eigen::Vector2d project(const CameraModel& camera, const Eigen::Vector3d& p_camera);

/// Removes the lens distortion from images. libapriltag fits straight lines to
/// the tag edges, so on a distorted image its corners are biased (about 0.02 px
/// outwards here, i.e. 0.2-0.4 mm of depth at 0.6 m; test_vision measures it).
/// The detector therefore runs on the rectified image, whose camera is
/// rectified(): the same K and no distortion.
///
/// The image is resampled with Lanczos interpolation (8 x 8 pixels), not
/// bilinear. A sensor's pixels average the light over their area; resampled
/// bilinearly at the distortion's ever-changing sub-pixel offsets, the rectified
/// image's corners moved towards the image centre: by 0.011 px (AprilTag) and
/// 0.012 px (chessboard) on average over rendered sessions (corners_study
/// --corner-bias, k1 = -0.12), enough to make X's NEES 400 at 2 gray levels of
/// noise. Lanczos: 0.0001 px (AprilTag); bicubic overshoots (0.009 px outwards).
class ImageRectifier {
 public:
  explicit ImageRectifier(const CameraModel& camera);
  /// The image itself when the camera has no distortion.
  cv::Mat rectify(const cv::Mat& image) const;
  const CameraModel& rectified() const { return rectified_; }
  /// The raw image's camera, with its distortion.
  const CameraModel& camera() const { return camera_; }
  bool distorted() const { return !map_x_.empty(); }
  /// Rectified pixels -> raw pixels (OpenCV's distortion model).
  std::vector<cv::Point2f> to_raw(const std::vector<Eigen::Vector2d>& rectified_pixels) const;
  /// Raw pixels -> rectified pixels (undistortPoints, iterated to 1e-12).
  std::vector<Eigen::Vector2d> from_raw(const std::vector<cv::Point2f>& raw_pixels) const;

 private:
  CameraModel camera_, rectified_;
  cv::Mat map_x_, map_y_;  // empty: nothing to undo
};


/// Pooled pixel noise: the residual variance over the recent frames. One frame
/// of one tag leaves 8 - 6 = 2 degrees of freedom, far too few for an honest
/// sigma (the mean of 1/chi2_2 is infinite); pooling over a window of frames
/// gives hundreds. The camera's pixel noise is a property of the camera and the
/// scene, so it changes slowly.
class PixelNoise {
 public:
  explicit PixelNoise(double floor_px = 0.02, std::size_t window_frames = 200)
      : floor_(floor_px), window_(window_frames) {}

  void add(double residual_sum_of_squares, int degrees_of_freedom);
  /// sqrt(pooled RSS / pooled dof), at least the floor; the floor alone
  /// until some frame had residual degrees of freedom.
  double sigma() const;
  /// The variance a pose covariance uses (px^2): s^2 x nu / (nu - 2) for s^2 =
  /// RSS / nu estimated from nu pooled degrees of freedom, and at least the
  /// floor^2. With sigma estimated, the error over s^2 (J^T C^-1 J)^-1 is
  /// Student-t, not Gaussian: its 6-dof NEES averages 6 nu / (nu - 2) (6.55 for
  /// 12 views of one marker, nu = 24; test_images), and nu / (nu - 2) is the
  /// covariance of that t (the posterior predictive under Jeffreys' prior on
  /// sigma). Below nu = 3 it is infinite; the factor stops at 3.
  double covariance_variance() const;
  int degrees_of_freedom() const { return dof_; }
  double floor() const { return floor_; }

 private:
  double floor_;
  std::size_t window_;
  std::deque<std::pair<double, int>> frames_;
  double rss_ = 0.0;
  int dof_ = 0;
};

/// How the corner errors of one tag are modelled.
///   EdgeFit: libapriltag fits a line to each edge, and a corner is where two
///     lines meet. A line fitted to l edge points with independent noise sigma
///     moves its two ends (perpendicular to it) with variance 4 sigma^2 / l
///     each and correlation -1/2 (offset plus tilt about the middle). The 8 x 8
///     corner covariance of a tag follows from its four lines; sigma is the
///     noise of one edge point, in px.
///   Independent: every corner coordinate independent with variance sigma^2.
///     Simpler, but on rendered images its translation covariance is about 2x
///     too large (NEES t 1.6 instead of 3; R 3.0, test_vision).
enum class CornerNoiseModel { EdgeFit, Independent };

struct PatternPoseOptions {
  int min_tags = 1;                  // tags of the layout that must be seen
  double max_rms_px = 2.0;           // refuse a fit worse than this (a wrong tag, a bad corner)
  /// Refuse a frame whose residuals are beyond this many times the pooled pixel
  /// variance (and its chi2 spread), once 100 degrees of freedom are pooled: one
  /// misplaced corner among well-placed ones, which max_rms_px lets through when
  /// the corners are good to 0.02 px.
  double max_variance_ratio = 10.0;
  CornerNoiseModel corner_noise = CornerNoiseModel::EdgeFit;
};

/// The 8 x 8 covariance, per unit sigma^2, of a tag's corners (x0, y0, ..., x3, y3)
/// under the EdgeFit model, at the detected corners (in order around the tag).
Eigen::Matrix<double, 8, 8> edge_fit_corner_covariance(const std::array<Eigen::Vector2d, 4>& corners);

struct PatternPose {
  Eigen::Isometry3d T_camera_pattern = Eigen::Isometry3d::Identity();
  Matrix6d covariance = Matrix6d::Zero();  // ROS order, m^2 and rad^2
  std::vector<int> ids;                    // the layout's tags used
  int points = 0;                          // corners used
  double rms_px = 0.0;                     // this frame's reprojection RMS
  double residual_sum_of_squares = 0.0;    // weighted by the corner noise model (r^T C^-1 r)
  int degrees_of_freedom = 0;              // 2 * points - 6
  double pixel_sigma = 0.0;                // px, the pooled sigma (floored)
  double covariance_variance = 0.0;        // px^2, what the covariance is scaled by (PixelNoise::covariance_variance)
};

struct PatternPoseResult {
  std::optional<PatternPose> pose;
  std::string refusal;  // why there is no pose (empty when there is one)
};

/// PnP (IPPE for a planar target, SQPnP otherwise; then Levenberg-Marquardt), a
/// Gauss-Newton refinement weighed by the corner noise model, and the covariance
/// sigma^2 (J^T C^-1 J)^-1 with sigma pooled by `noise` (this frame's residuals
/// added first). Every detector ends here.
PatternPoseResult estimate_pose(const CameraModel& camera, const PointCorrespondences& points, PixelNoise& noise,
                                const PatternPoseOptions& options = {});

/// What a detector saw of a target in one image: its correspondences, or why not
/// (every detector returns it: chessboard, ChArUco, tags and markers).
struct TargetObservation {
  std::optional<PointCorrespondences> points;
  std::string refusal;  // why not (empty when found)
  int saddle_half_window = 0;  // chessboard and ChArUco: cornerSubPix's, to refine again in the raw image
};

/// The corners of the detected tags that belong to `layout` (others are ignored),
/// with the corner noise model of `options` (EdgeFit: one 8 x 8 block per tag);
/// or a refusal, e.g. too few tags, a tag seen twice or edge-on.
TargetObservation tag_correspondences(const TagLayout& layout, const std::vector<TagCorners>& detections,
                                       const PatternPoseOptions& options = {});

/// The pattern pose from the detected tags that belong to `layout` (others are
/// ignored): tag_correspondences, then estimate_pose. The covariance uses `noise.sigma()` after adding this frame's
/// residuals to it (the caller keeps one PixelNoise per camera).
PatternPoseResult estimate_pattern_pose(const TagLayout& layout, const CameraModel& camera,
                                        const std::vector<TagCorners>& detections, PixelNoise& noise,
                                        const PatternPoseOptions& options = {});

/// d(pixels)/d(pose perturbation) (2n x 6, ROS order) of the pattern points
/// at T_camera_pattern; exposed for the numerical check in test_vision.
Eigen::Matrix<double, Eigen::Dynamic, 6> reprojection_jacobian(const CameraModel& camera,
                                                               const Eigen::Isometry3d& T_camera_pattern,
                                                               const std::vector<Eigen::Vector3d>& points);

/// d(pixels)/d(fx, fy, cx, cy) (2n x 4) of the pattern points at T_camera_pattern,
/// by cv::projectPoints: how the intrinsics' uncertainty (CameraModel::intrinsics_sigma)
/// enters a view's pose covariance, sigma^2 (J^T C^-1 J)^-1 + A diag(sigma_K^2) A^T,
/// A = (J^T C^-1 J)^-1 J^T C^-1 J_K.
Eigen::Matrix<double, Eigen::Dynamic, 4> intrinsics_jacobian(const CameraModel& camera,
                                                             const Eigen::Isometry3d& T_camera_pattern,
                                                             const std::vector<Eigen::Vector3d>& points);

/// The corners of a detection on the rectified image (camera.rectified(): K, no
/// distortion) in the raw image's pixels, their covariance carried by the 2x2
/// Jacobian of the distortion at each corner.
PointCorrespondences raw_pixels(const PointCorrespondences& rectified, const CameraModel& camera);

}  // namespace handeye
