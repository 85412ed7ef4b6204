// X and the pattern pose Y refined from the image corners themselves (no ROS): each
// detected corner against u_ij = pi(K, D, R_P o_j + t_P), P_i = X^-1 V_i Y (rig.h;
// OpenCV's pinhole and distortion, raw pixels), whitened by the detector's corner-noise
// model over the pixel sigma; the robot poses as measurements with a prior and, as an
// option, the intrinsics (fx, fy, cx, cy, k1, k2; the camera as their prior). Solved by
// Ceres from the pose-level estimate; the covariance of (xi_X, xi_Y), ROS order, left
// perturbations as everywhere, carries the target points' error as a consider parameter.
// Derivation: docs/how_it_works.md, "The corner estimator".
#pragma once

#include <Eigen/Core>
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "handeye_covariance/core/pose_covariance.h"
#include "handeye_covariance/core/rig.h"
#include "handeye_covariance/estimation/estimator.h"
#include "handeye_covariance/estimation/joint_estimator.h"
#include "handeye_covariance/vision/pattern_pose.h"

namespace handeye {

/// One image: the robot pose it was taken at, and the target's corners in it, in
/// the pixels of the calibration's camera (distortion included: raw_pixels maps a
/// rectified image's corners there, vision/pattern_pose.h).
struct CornerView {
  Eigen::Isometry3d T_base_effector = Eigen::Isometry3d::Identity();
  PointCorrespondences points;
  std::string name;  // the image, for reports
};

/// The intrinsics that `--method corners` can refine: fx, fy, cx, cy (px), k1, k2.
using IntrinsicsVector = Eigen::Matrix<double, 6, 1>;
IntrinsicsVector intrinsics_of(const CameraModel& camera);  // k1, k2 = 0 when the model has none

struct CornerOptions {
  /// Pixel sigma (px) of the corner-noise model; 0: estimated from the residuals.
  double pixel_sigma = 0.0;
  /// The robot poses as measurements with this covariance (ROS order, left
  /// perturbation in the base frame) as their prior; absent: taken as exact.
  std::optional<Matrix6d> robot_covariance;
  /// Robot poses free with an isotropic noise (one translation, one rotation
  /// variance) estimated from the data as variance components, alternating with
  /// the solve (robot_covariance, if given, is the start).
  bool estimate_robot_noise = false;
  /// Refine fx, fy, cx, cy, k1, k2, with the given camera as the prior.
  bool refine_intrinsics = false;
  /// The prior's 1 sigma: of fx and fy as a share of them, of cx and cy as a share
  /// of the image width, of k1 and k2 absolute.
  double focal_prior = 0.05, centre_prior = 0.05, distortion_prior = 0.2;
  int max_iterations = 100;
  int max_noise_rounds = 30;  // noise estimated with a prior's weight at stake: solve / estimate alternations
  /// With the pixel sigma estimated: Auto tests whether the images share one pixel
  /// noise (Bartlett's test of their residual variances at 99.9%) and, when they do
  /// not, gives each image its own sigma (On: always; Off: never).
  JointOptions::Robust robust = JointOptions::Robust::Auto;
  double homogeneity_level = 0.999;
  /// An image whose corners leave fewer degrees of freedom than this shares the
  /// sigma of the other such images rather than getting its own.
  double min_image_dof = 8.0;
  /// The target's points off their nominal positions by an isotropic 3-d error of
  /// this 1 sigma (m), each the same in every image (print accuracy, a board not
  /// flat, a detector's bias at each corner): negative, estimated from the corners;
  /// 0, the target exact; positive, as given. NaN or Inf: InvalidNoise.
  double target_point_sigma = -1.0;
};

struct ImageReprojection {
  std::string name;
  int points = 0;
  double rms_px = 0.0;
  double sigma_px = 0.0;  // the pixel sigma its corners were weighed with
  double dof = 0.0;       // its corners' share of the degrees of freedom
};

/// Bartlett's test that every image has the same pixel noise: chi2 on `dof`
/// (images - 1) degrees of freedom against its `bound` at homogeneity_level.
struct HomogeneityTest {
  double chi2 = 0.0, bound = 0.0;
  int dof = 0;
  bool passed = true;
};

struct CornerCalibration {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();  // T_effector_camera or T_base_camera
  Eigen::Isometry3d Y = Eigen::Isometry3d::Identity();  // T_base_pattern or T_effector_pattern
  /// Of (xi_X, xi_Y), ROS order each: X's 6x6, Y's 6x6 and their cross block.
  Eigen::Matrix<double, 12, 12> covariance = Eigen::Matrix<double, 12, 12>::Zero();
  double pixel_sigma = 0.0;    // px: as given, or the estimate (less the target's share when one is found)
  bool pixel_sigma_estimated = false;
  int degrees_of_freedom = 0;  // corner residuals m minus what the fit absorbs (rounded)
  double rms_px = 0.0;         // over every corner
  double chi2 = 0.0;           // the corners' sum r^T C^-1 r / sigma^2 (= dof when sigma is estimated)
  std::vector<ImageReprojection> images;
  /// With the pixel sigma estimated: the test of one sigma for all images (at the
  /// one-sigma fit), and whether each image got its own (then pixel_sigma is their
  /// pooled value, for reports).
  std::optional<HomogeneityTest> homogeneity;
  bool per_image_sigma = false;
  /// With refine_intrinsics: fx, fy, cx, cy, k1, k2 and their covariance.
  std::optional<IntrinsicsVector> intrinsics;
  Matrix6d intrinsics_covariance = Matrix6d::Zero();  // the target's error carried, as X's
  /// With estimate_robot_noise: the robot's 1 sigma per axis, translation (m) and
  /// rotation (rad); 1e-7 where the residuals do not support any.
  bool robot_noise_estimated = false;
  Eigen::Vector2d robot_sigma = Eigen::Vector2d::Zero();
  std::array<bool, 2> robot_at_bound = {false, false};  // not supported: held at 1e-7
  /// The target points' 1 sigma (m; target_point_sigma), as given or estimated (0:
  /// the residuals show none), and the factor it put on X's 1 sigma (root of the
  /// trace ratio; translation, rotation).
  double target_point_sigma = 0.0;
  bool target_point_sigma_estimated = false;
  Eigen::Vector2d target_inflation = Eigen::Vector2d::Ones();
  int iterations = 0;  // Ceres iterations, every noise round
  int noise_rounds = 1;
};

/// Every view's corner residuals, whitened by the corner-noise model (per unit
/// sigma, the robot poses and the intrinsics as given), and their Jacobian by
/// (xi_X, xi_Y) as the solver sees it; J^T J / sigma^2 is the information of the
/// corner model with the robot exact (its inverse the Cramer-Rao bound).
struct CornerResiduals {
  Eigen::VectorXd whitened;
  Eigen::Matrix<double, Eigen::Dynamic, 12> jacobian;
};
CornerResiduals corner_residuals(const Rig& rig, const CameraModel& camera, const std::vector<CornerView>& views,
                                 const Eigen::Isometry3d& X, const Eigen::Isometry3d& Y);

/// Refines X and Y from the corners of `views`, started from (X0, Y0) (the
/// pose-level estimate). Throws HandEyeError: NoData for fewer than 3 views or a
/// view without corners, InvalidNoise for a corner covariance that is not
/// positive definite or a robot covariance that is not, NotConverged when Ceres
/// fails, PoorlyConstrained when the information cannot be inverted.
CornerCalibration calibrate_corners(const Rig& rig, const CameraModel& camera, const std::vector<CornerView>& views,
                                    const Eigen::Isometry3d& X0, const Eigen::Isometry3d& Y0,
                                    const CornerOptions& options = {});

/// `--method corners` after the pose-level estimate `pose_level` of the same
/// samples: calibrate_corners started from its X and Y, its rejected samples left
/// out, each kept sample's corners (PoseSample::corners, all from one camera) as
/// its image. Unless `options` says otherwise, the robot poses are free: with the
/// robot noise the samples state when pose_level's residual checks trusted it,
/// else (6 images or more) with the robot noise estimated from the corners, else
/// with the one pose_level used (a zero block floored at 0.1 um / 0.1 urad); exact
/// when there is none. The Calibration holds X, Y, their covariances and cross
/// block (method Corners) and the corner fit; the pose-level residual checks and
/// noise components, which described the poses' fit, are replaced by the corners'.
/// The corner fit's words (robot, target_points, pixel_noise) are left empty for
/// io::word_corner_fit, which the session calls after this. Throws
/// HandEyeError(MalformedFile) naming a sample without corners or with another
/// camera's, and calibrate_corners's errors.
struct CornerMethodResult {
  Calibration calibration;
  CornerCalibration fit;
};
CornerMethodResult refine_with_corners(const SampleSet& samples, const Calibration& pose_level, CornerOptions options = {});

/// The session's hook for method corners (SessionSettings::refine_corners):
/// refine_with_corners with `options`, its robust mode the session's.
CornerRefiner corner_refiner(CornerOptions options = {});

}  // namespace handeye
