// The AX = XB estimator with its covariance (Nguyen & Pham, "On the covariance
// of X in AX = XB", sections II-III).
//
//  1. Park-Martin closed form for the initial rotation and translation.
//  2. Rotation: covariance-weighted Gauss-Newton on SO(3), eq. (18-35). The
//     beta_i block is eliminated by its Schur complement, written per pair with
//     the matrix inversion lemma,
//         U_i - W_i Z_i^-1 W_i^T = [R b_i]^T (Sigma_alpha_i + R Sigma_beta_i R^T)^-1 [R b_i],
//     so time and memory are O(k) and a noise-free robot (Sigma_A = 0, as in the
//     paper's real-data experiment) needs no inverse of a singular matrix.
//  3. Translation: the iterative solution of eq. (36-56), same elimination of
//     the R_Ai block.
//  4. Covariance: full first-order propagation of every input noise through
//     the converged estimator (a "sandwich"). Eq. (35) and (56) assume each pair
//     carries its own independent error; they do not. The rotation estimate's
//     error enters every q_i = R t_Bi - t_Ai (shared by all pairs), q_i is
//     correlated with R_Ai, and on a pose stream consecutive motions share a
//     pose. The propagation below carries all three, and gives the R-t cross
//     block. Its cost is O(k): each input noise touches at most two motions.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/core/fields.h"
#include "handeye_covariance/core/measurements.h"
#include "handeye_covariance/core/units.h"
#include "handeye_covariance/estimation/honesty_record.h"

namespace handeye {

struct SolverOptions {
  int max_iterations = 50;
  /// Stop when the step's squared Mahalanobis length under the current
  /// information matrix falls below this: the step is then < 1e-4 sigma, a
  /// relative criterion that works at every noise level and every k.
  double step_tolerance = 1e-8;
  /// ... or when the relative change of the weighted cost falls below this.
  double cost_tolerance = 1e-14;
  /// A motion counts as rotating when both its angles exceed this ...
  double min_rotation_angle = radians(0.5);
  /// ... and this many sigma of its rotation-angle noise.
  double min_rotation_sigmas = 3.0;
  /// Two rotation axes count as different beyond this angle.
  double min_axis_angle = radians(1.0);
  /// |angle(A) - angle(B)| beyond this many sigma refuses the input.
  double angle_mismatch_sigmas = 8.0;
  /// With no noise given the spread is the motions' own, which anisotropic
  /// detector noise makes uneven (axes along the optical axis are better known):
  /// a mismatch is then refused only beyond this too. Smaller ones are left to
  /// the outlier stage (outliers.h) and the residuals.
  double min_angle_mismatch_without_noise = radians(1.0);
  /// Refuse a result whose rotation 1-sigma exceeds this (rad): the first-order
  /// covariance is meaningless there.
  double max_rotation_sigma = 0.1;
  /// Pose input: each sample forms a motion with each of the next pair_window
  /// samples (all pairs for sessions up to pair_window + 1 samples; O(n w)
  /// beyond). 1 uses consecutive motions only. Every pair's correlation through
  /// the shared poses is in the covariance, whatever the window.
  int pair_window = 30;
};

enum class StopReason {
  StepBelowTolerance,  // converged: the last step was negligible against sigma
  CostChangeBelowTolerance,  // converged: the cost no longer changes
  MaxIterations,       // not converged
};
const char* to_string(StopReason reason);

struct StageDiagnostics {
  int iterations = 0;
  StopReason stop_reason = StopReason::MaxIterations;
  double chi2 = 0.0;  // weighted residual sum of squares at the solution
  int dof = 0;        // expected chi2: 3k minus what the fit absorbs (3k - 3 for independent motions)
  bool converged() const { return stop_reason != StopReason::MaxIterations; }
  template <class Self, class Visit>
  static void fields(Self& s, Visit&& visit) {
    visit("iterations", s.iterations);
    visit("stop_reason", s.stop_reason);
    visit("chi2", s.chi2);
    visit("dof", s.dof);
  }
};

/// Where the noise came from.
enum class NoiseOrigin { Given, EstimatedFromResiduals };
const char* to_string(NoiseOrigin origin);  // "given" / "estimated_from_residuals"

/// Which estimator made a Calibration.
enum class Method {
  Pairs,  // the paper's AX = XB on motion pairs (estimator.h)
  Joint,  // X and the pattern pose Y jointly from the absolute poses (joint_estimator.h)
  Corners,  // X and Y from every image corner's reprojection error (corners/corner_calibration.h)
};
const char* to_string(Method method);  // "pairs" / "joint" / "corners"
/// A session's method: "pairs", "joint" or "corners" (which needs the samples'
/// corners and a program that links the corner estimator: CornerRefiner). Throws
/// HandEyeError(MalformedFile) naming the valid values.
Method method_from_string(const std::string& name);
/// The refusal of method corners where only poses can be solved (estimate, and a
/// session without a CornerRefiner): HandEyeError(MalformedFile) with the fix.
HandEyeError corners_need_images();

/// How samples far out weigh: each alike (least squares), or less (Huber, robust mode).
enum class Loss { Squared, Huber };
const char* to_string(Loss loss);  // "squared" / "huber"
/// What the covariance is: the inverse information; the model-robust sandwich (robust
/// mode); or the GLS covariance of a robot error shared by nearby poses (shared_robot_error.h).
enum class CovarianceKind { Information, Sandwich, SharedRobotError };
const char* to_string(CovarianceKind kind);  // "information" / "sandwich" / "shared_robot_error"

/// A corner fit's refined intrinsics, each (value, 1 sigma): fx, fy, cx, cy (px), k1, k2.
/// At namespace scope: an optional of it is built while Calibration is incomplete.
struct RefinedIntrinsics {
  Eigen::Vector2d fx = Eigen::Vector2d::Zero(), fy = Eigen::Vector2d::Zero(), cx = Eigen::Vector2d::Zero(),
                  cy = Eigen::Vector2d::Zero(), k1 = Eigen::Vector2d::Zero(), k2 = Eigen::Vector2d::Zero();
  template <class Self, class Visit>
  static void fields(Self& s, Visit&& visit) {
    visit("fx", s.fx);
    visit("fy", s.fy);
    visit("cx", s.cx);
    visit("cy", s.cy);
    visit("k1", s.k1);
    visit("k2", s.k2);
  }
};

struct Calibration {
  /// X: T_effector_camera (eye_in_hand) or T_base_camera (eye_to_hand); for motion
  /// input, the X of A X = X B.
  Eigen::Isometry3d T_parent_camera = Eigen::Isometry3d::Identity();
  Eigen::Matrix3d rotation_covariance = Eigen::Matrix3d::Zero();     // rad^2, left perturbation
  Eigen::Matrix3d translation_covariance = Eigen::Matrix3d::Zero();  // m^2
  Matrix6d pose_covariance = Matrix6d::Zero();  // ROS order (x,y,z,rx,ry,rz), with R-t cross block

  /// Eq. (35) and (56) as printed: each pair's error taken as independent.
  /// For comparison only; it is overconfident wherever the rotation error,
  /// shared by all pairs, dominates the translation error.
  DecoupledCovariance per_pair_covariance;

  /// Y, the pattern's pose: T_base_pattern (eye_in_hand) or T_effector_pattern
  /// (eye_to_hand), with its covariance; and Cov(X, Y) (X's ROS order in the
  /// rows, Y's in the columns). The joint estimator only.
  std::optional<PoseWithCovariance> pattern;
  Matrix6d cross_covariance = Matrix6d::Zero();

  Method method = Method::Pairs;
  Eigen::Isometry3d initial_guess = Eigen::Isometry3d::Identity();  // Park-Martin
  /// Pairs: the two stages. Joint: both hold the one joint solve (its chi2 over
  /// all 6n residuals, dof 6n - 12).
  StageDiagnostics rotation_stage, translation_stage;
  int motions_used = 0;
  int samples_used = 0;  // pose input only; 0 for motion input

  NoiseOrigin noise_origin = NoiseOrigin::Given;
  /// The noise the covariance is based on: as given, or the estimate (isotropic
  /// camera noise, robot taken as exact) when none was given.
  MeasurementNoise noise;
  std::string noise_model;  // when estimated: which model the residuals supported, e.g. "a full 6x6 camera noise ..."
  /// Joint: each noise number the residuals estimated (joint_estimator.h).
  struct NoiseComponent {
    std::string name;      // e.g. "camera z", "robot rotation", "stated camera noise scale"
    std::string unit;      // "m", "rad" (value is a sigma) or "" (a scale of variances)
    double value = 0.0;    // sigma (m, rad) or the scale
    double sigma = 0.0;    // 1 sigma of that value, from the residuals (0 when at its bound)
    bool supported = true; // false: the residuals do not support it, held at 0 (or its lowest value)
    template <class Self, class Visit>
    static void fields(Self& s, Visit&& visit) {
      visit("name", s.name);
      visit("value", s.value);
      visit("sigma", s.sigma);
      visit("unit", s.unit, kOptional);
      visit("supported", s.supported, kOptional);
    }
  };
  std::vector<NoiseComponent> noise_components;
  /// Joint, noise estimated: the noise models that were compared, by BIC (the
  /// restricted log-likelihood, less half of log(6n - 12) per number), and which one
  /// the covariance uses. A candidate whose score test at the chosen model promised
  /// less than BIC's price of its one number is not fitted.
  struct NoiseCandidate {
    std::string name;             // e.g. "camera variances, robot rotation", "+ view-following"
    int numbers = 0;              // its free noise numbers
    double score = 0.0;           // the score test that decided whether to fit it (0 for the first)
    bool fitted = false, chosen = false;
    double log_likelihood = 0.0;  // restricted, up to a constant the candidates share (fitted only)
    double bic = 0.0;             // -2 log_likelihood + numbers log(6n - 12) (fitted only)
    template <class Self, class Visit>
    static void fields(Self& s, Visit&& visit) {
      visit("name", s.name);
      visit("numbers", s.numbers);
      visit("score", s.score);
      visit("fitted", s.fitted);
      visit("chosen", s.chosen);
      visit("log_likelihood", s.log_likelihood, Only{s.fitted});
      visit("bic", s.bic, Only{s.fitted});
    }
  };
  std::vector<NoiseCandidate> noise_candidates;
  /// Joint: the residual noise the covariance was computed with, for any view
  /// (the samples' and new ones; joint_estimator.h residual_covariance):
  ///   S = camera_scale Sigma_P + camera + view_scale G(P) + D (Sigma_E + robot) D^T,
  /// Sigma_P and Sigma_E the view's stated noise (its own, else the set's; zero
  /// when none), D = d P_hat / d E at (X, Y). Absent (pairs): `noise` is S's.
  struct ResidualNoise {
    double camera_scale = 1.0;
    Matrix6d camera = Matrix6d::Zero();  // camera frame, ROS order
    Matrix6d robot = Matrix6d::Zero();   // base (or effector) frame, as E's perturbation
    /// The view-following part, view_scale G(P) (core/view_noise.h: planar_view_covariance
    /// of view_points at the view P); 0 when the model has none.
    double view_scale = 0.0;
    std::vector<Eigen::Vector3d> view_points;
    template <class Self, class Visit>
    static void fields(Self& s, Visit&& visit) {
      visit("camera_scale", s.camera_scale);
      visit("camera", s.camera);
      visit("robot", s.robot);
      visit("view_scale", s.view_scale, kOptional);
      visit("view_points", s.view_points, kWhenSet);
    }
  };
  std::optional<ResidualNoise> residual_noise;
  /// Joint: the check of the residuals against the noise model and what followed.
  struct ResidualCheck {
    std::string test;        // e.g. "chi2 of the stated noise", "kurtosis of the Mahalanobis residuals"
    double statistic = 0.0;  // chi2/dof, or the kurtosis z score
    double bound = 0.0;      // the statistic's 99.9% bound under the model
    bool passed = true;
    template <class Self, class Visit>
    static void fields(Self& s, Visit&& visit) {
      visit("test", s.test);
      visit("statistic", s.statistic);
      visit("bound", s.bound);
      visit("passed", s.passed);
    }
  };
  std::vector<ResidualCheck> residual_checks;
  Loss loss = Loss::Squared;
  CovarianceKind covariance_kind = CovarianceKind::Information;
  int downweighted = 0;                      // robust mode: samples the Huber loss weighed below 1
  /// Joint: the factors on the inverse information for the noise estimate's (or the
  /// sandwich's) own uncertainty, X's and the pattern pose's (the X-pattern block
  /// takes their geometric mean).
  double covariance_inflation = 1.0, pattern_covariance_inflation = 1.0;
  std::vector<std::string> warnings;  // e.g. residuals far larger than the stated noise

  /// A symmetric target (Rig::symmetric_face): the samples whose detected pose was
  /// replaced by its other candidate, turned by 180 degrees about the face's normal
  /// (CalibrationSession::calibrate; indices into its input, ascending).
  std::vector<int> turned;

  /// Samples left out by solve_robust (outliers.h), indices into its input.
  struct Rejected {
    int index = 0;
    std::string reason;
    template <class Self, class Visit>
    static void fields(Self& s, Visit&& visit) {
      visit("index", s.index);
      visit("reason", s.reason);
    }
  };
  std::vector<Rejected> rejected;

  /// The split-half check calibrated to the session (split_check.h, honesty_check), when it ran.
  using Honesty = HonestyRecord;
  std::optional<Honesty> honesty;

  /// A robot error shared by nearby poses (shared_robot_error.h), fitted about this
  /// calibration by CalibrationSession::calibrate_checked (a joint fit without robust
  /// mode, 16 to 40 kept samples; otherwise `not_fitted` says why): whether the
  /// likelihood prefers it (BIC), its numbers, and X and its covariance under it.
  /// `used`: the session took them (X, Y and the covariances above are the model's);
  /// otherwise advice, and when `chosen` the per-view covariance understates X's by
  /// what per_view_estimate_covariance says.
  struct SharedError {
    /// Empty when fitted; otherwise why not (too few or too many samples, robust
    /// mode, method corners, the fit refused): the fields below are then unset.
    std::string not_fitted;
    bool chosen = false;
    /// The calibration's X, Y and covariances are this model's (chosen, and the
    /// session uses it); the per-view model's X and its covariance are kept below.
    bool used = false;
    double bic_gain = 0.0;            // 2 (L - L0) - 4 log(6n - 12): > 0 chosen
    double length_scale = 0.0;        // m, over the effector positions
    double translation_sigma = 0.0;   // m, per axis, base frame
    double rotation_sigma = 0.0;      // rad
    double view_noise_scale = 1.0;    // on the per-view model's residual covariances
    double step_nees = 0.0;           // X's step under its own covariance (about 6 when the model explains it)
    double covariance_inflation = 1.0;  // in X's covariance, its factor for (s, a, b)'s own error (Kenward-Roger)
    PoseWithCovariance X;             // after the GLS step, with its covariance
    Matrix6d per_view_estimate_covariance = Matrix6d::Zero();  // the per-view X's covariance under the model
    PoseWithCovariance per_view_X;
    PoseWithCovariance per_view_pattern;  // Y, where the model is linearised
    Matrix6d per_view_cross_covariance = Matrix6d::Zero();
    /// The per-view model's own honesty check (calibrate_checked runs it too): its
    /// verdict and inflation (1 unless overconfident and inflate_when_overconfident).
    /// A check of new views from a file without `views` below predicts with the per-view
    /// model times it; with them, under the model (whose own honesty factor applies).
    std::string per_view_honesty;
    double per_view_inflation = 1.0;
    /// What a check of new views needs to predict them under the model (calibration_check.h),
    /// about the per-view X and Y: their joint covariance under the model, H0 C H0^T (X's
    /// block is per_view_estimate_covariance), and for each view the fit used, the
    /// effector's position and H0_j D_j, how the per-view estimate moves with that view's
    /// robot error: a new view's shared error is correlated with theirs.
    Matrix6d per_view_estimate_pattern_covariance = Matrix6d::Zero(), per_view_estimate_cross_covariance = Matrix6d::Zero();
    struct View {
      Eigen::Vector3d position = Eigen::Vector3d::Zero();          // m, the effector's, base frame
      Eigen::Matrix<double, 12, 6> gain = Eigen::Matrix<double, 12, 6>::Zero();  // H0_j D_j: (xi_X, xi_Y) per xi_E
      template <class Self, class Visit>
      static void fields(Self& s, Visit&& visit) {
        visit("position", s.position);
        visit("gain", s.gain);  // 12 x 6 row-major: (xi_X, xi_Y) in ROS order per the robot error xi_E
      }
    };
    std::vector<View> views;
    /// The per-view fit's own factors for its noise estimate's error and its noise
    /// model's text, which the model's replaced in the calibration (not in files).
    double per_view_covariance_inflation = 1.0, per_view_pattern_covariance_inflation = 1.0;
    std::string per_view_noise_model;

    bool fitted() const { return not_fitted.empty(); }
    bool chosen_fit() const { return fitted() && chosen; }
    bool used_fit() const { return fitted() && chosen && used; }
    template <class Self, class Visit>
    static void fields(Self& s, Visit&& visit) {
      visit("not_fitted", s.not_fitted, kWhenSet);
      visit("chosen", s.chosen, Only{s.fitted()});
      visit("used", s.used, Only{s.fitted(), true});  // files of earlier versions lack it: not used
      visit("bic_gain", s.bic_gain, Only{s.fitted()});
      visit("length_scale", s.length_scale, Only{s.chosen_fit()});
      visit("translation_sigma", s.translation_sigma, Only{s.chosen_fit()});
      visit("rotation_sigma", s.rotation_sigma, Only{s.chosen_fit()});
      visit("view_noise_scale", s.view_noise_scale, Only{s.chosen_fit()});
      visit("step_nees", s.step_nees, Only{s.chosen_fit()});
      visit("covariance_inflation", s.covariance_inflation, Only{s.chosen_fit()});
      visit("X", s.X, Only{s.chosen_fit()});
      visit("per_view_covariance_under_it", s.per_view_estimate_covariance, Only{s.chosen_fit()});
      // Used: the per-view model's X and Y with their own covariances, which the model's replaced.
      visit("per_view_X", s.per_view_X, Only{s.used_fit()});
      visit("per_view_pattern", s.per_view_pattern, Only{s.used_fit()});
      visit("per_view_cross_covariance", s.per_view_cross_covariance, Only{s.used_fit()});
      visit("per_view_honesty", s.per_view_honesty, Only{s.used_fit()});
      visit("per_view_inflation", s.per_view_inflation, Only{s.used_fit()});
      // What a check predicts new views with under the model (files of earlier versions lack them).
      visit("per_view_pattern_covariance_under_it", s.per_view_estimate_pattern_covariance, Only{s.used_fit(), true});
      visit("per_view_cross_covariance_under_it", s.per_view_estimate_cross_covariance, Only{s.used_fit(), true});
      visit("views", s.views, Only{s.used_fit(), true});
      visit("per_view_covariance_inflation", s.per_view_covariance_inflation, kInMemory);
      visit("per_view_pattern_covariance_inflation", s.per_view_pattern_covariance_inflation, kInMemory);
      visit("per_view_noise_model", s.per_view_noise_model, kInMemory);
    }
  };
  std::optional<SharedError> shared_robot_error;

  /// How well the noise model and the covariance predict a view the calibration has not
  /// seen, measured on its own kept views by leave-one-out (calibration_check.h
  /// prediction_check): each view predicted from the others' X, Y, covariance and noise
  /// (estimated again without it). `scale` is the mean of d_i^2 / 6, d_i each view's
  /// Mahalanobis length under its predicted covariance (1 when the model predicts
  /// right); `dof` that mean's degrees of freedom from the d_i's own spread (6 n when
  /// they scatter as chi2(6)). A check of new views (calibration_check.h) scales its
  /// prediction by it.
  struct Prediction {
    double scale = 1.0;
    double dof = 0.0;
    int views = 0;
    template <class Self, class Visit>
    static void fields(Self& s, Visit&& visit) {
      visit("scale", s.scale);
      visit("dof", s.dof);
      visit("views", s.views, kOptional);
    }
  };
  std::optional<Prediction> prediction;

  /// Corners: the fit of every image's corners (corners/corner_calibration.h).
  struct CornerFit {
    double pixel_sigma = 0.0;  // px, estimated from the residuals (or given)
    bool pixel_sigma_estimated = true;
    double rms_px = 0.0;       // over every corner coordinate
    int corners = 0;
    struct Image {
      std::string name;
      int corners = 0;
      double rms_px = 0.0;
      double sigma_px = 0.0;  // the pixel sigma it was weighed with
      template <class Self, class Visit>
      static void fields(Self& s, Visit&& visit) {
        visit("image", s.name);
        visit("corners", s.corners);
        visit("rms_px", s.rms_px);
        visit("sigma_px", s.sigma_px);
      }
    };
    std::vector<Image> images;
    /// The test of one pixel sigma for every image and what followed ("one pixel
    /// sigma: Bartlett chi2 12.3 on 11 dof, 99.9% bound 31.3", or each image its own).
    std::string pixel_noise;
    bool per_image_sigma = false;
    std::string robot;  // how the robot poses entered: "exact" or their prior
    bool robot_noise_estimated = false;  // the robot's noise estimated from the corners, off its floor
    /// The printed target's points' 1 sigma (m, per axis; estimated or given, 0:
    /// exact) and how it entered the covariance.
    double target_point_sigma = 0.0;
    std::string target_points;
    /// Refined intrinsics; none when kept.
    using Intrinsics = RefinedIntrinsics;
    std::optional<Intrinsics> intrinsics;
    template <class Self, class Visit>
    static void fields(Self& s, Visit&& visit) {
      visit("pixel_sigma", s.pixel_sigma);
      visit("pixel_sigma_estimated", s.pixel_sigma_estimated);
      visit("rms_px", s.rms_px);
      visit("corners", s.corners);
      visit("robot_poses", s.robot);
      visit("target_point_sigma", s.target_point_sigma);  // m, per axis
      visit("target_points", s.target_points, kWhenSet);
      visit("pixel_noise", s.pixel_noise, kWhenSet);
      visit("per_image_sigma", s.per_image_sigma);
      visit("intrinsics", s.intrinsics, kBlock);
      visit("images", s.images);
      visit("robot_noise_estimated", s.robot_noise_estimated, kInMemory);
    }
  };
  std::optional<CornerFit> corner_fit;
};

/// The 12x12 covariance of (X, Y): X's, Y's and their cross block (Y's blocks zero when the
/// calibration has no Y), symmetrised.
Eigen::Matrix<double, 12, 12> joint_covariance(const Calibration& calibration);
/// X's covariance (ROS order) and its translation and rotation blocks, set together.
void set_pose_covariance(Calibration& calibration, const Matrix6d& covariance);
/// X's, Y's and their cross covariance times k (an inflation), the 3x3 blocks with them.
void scale_covariances(Calibration& calibration, double k);

/// Park-Martin closed form (the paper's [3]): R from the polar decomposition of
/// sum beta_i alpha_i^T, then t by linear least squares. Throws on < 2 motions.
Eigen::Isometry3d park_martin(const std::vector<MotionPair>& motions);

/// What the degeneracy checks of both estimators read: each motion's rotation
/// vectors log R_A, log R_B, and the 1 sigma of their angle difference.
struct MotionRotations {
  std::vector<Eigen::Vector3d> alpha, beta;
  std::vector<double> sigma;  // 0 when the noise is not given
  bool noise_given = true;
  std::function<std::string(std::size_t)> label;  // where motion i came from, for messages
};
/// Throws the named degeneracy errors: TooFewMotions, AngleMismatch (far beyond
/// the noise and the other motions), PureTranslation, RotationTooSmallForNoise,
/// ParallelRotationAxes.
void check_motion_rotations(const MotionRotations& motions, const SolverOptions& options);

/// The closed-form start for pose input in O(n): the degeneracy checks of
/// solve() (it throws the same named errors) on consecutive motions, then
/// Park-Martin on them.
Eigen::Isometry3d checked_initial_guess(const SampleSet& samples, const SolverOptions& options = {});

/// Solve from independent motion pairs.
Calibration solve(const MotionSet& motions, const SolverOptions& options = {});

/// Solve from absolute pose samples. Each sample forms motions with the next
/// pair_window samples (all pairs for short sessions), and each sample's noise
/// is propagated into every motion that uses it, so their correlation is in the
/// covariance.
Calibration solve(const SampleSet& samples, const SolverOptions& options = {});

}  // namespace handeye
