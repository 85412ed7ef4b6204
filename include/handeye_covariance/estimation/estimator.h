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
#include "handeye_covariance/estimation/corner_fit_record.h"
#include "handeye_covariance/estimation/honesty_record.h"
#include "handeye_covariance/estimation/noise_record.h"
#include "handeye_covariance/estimation/prediction_record.h"
#include "handeye_covariance/estimation/shared_error_record.h"

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

/// Something the user should know that did not stop the calibration: what it is and its
/// figures. io/warning_text.h writes the words.
struct Warning {
  enum class Kind {
    StageAboveStatedNoise,  // pairs: a stage's residuals above the stated noise (rotation_stage, chi2_per_dof)
    AboveStatedNoise,       // joint: the residuals above the stated noise, no noise estimated (chi2_per_dof)
    StatedNoiseTooSmall,    // joint: the same, the missing noise estimated (chi2_per_dof)
    OutliersRejected,       // samples rejected as outliers (count)
    Inflated,               // the honesty check inflated the covariances (factor: its ratio; run_length: the look that decided)
    SymmetricTarget,        // views turned by 180 degrees (count of views; ambiguous ones left out)
  };
  Kind kind = Kind::AboveStatedNoise;
  double chi2_per_dof = 0.0;
  bool rotation_stage = false;
  int count = 0, views = 0, ambiguous = 0;
  double factor = 1.0;
  int run_length = 1;
};

/// A calibration: X, Y and their joint covariance, how they were estimated, and one
/// section per check or model that produced a diagnostic, each declared in its own
/// record header and described once (core/fields.h) for files, messages and summaries.
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
  /// Joint, noise estimated: the model the residuals supported (io::noise_model_text).
  std::optional<NoiseModelChoice> noise_model;
  using NoiseComponent = handeye::NoiseComponent;
  std::vector<NoiseComponent> noise_components;
  using NoiseCandidate = handeye::NoiseCandidate;
  std::vector<NoiseCandidate> noise_candidates;
  using ResidualNoise = handeye::ResidualNoise;
  std::optional<ResidualNoise> residual_noise;
  using ResidualCheck = handeye::ResidualCheck;
  std::vector<ResidualCheck> residual_checks;
  Loss loss = Loss::Squared;
  CovarianceKind covariance_kind = CovarianceKind::Information;
  int downweighted = 0;                      // robust mode: samples the Huber loss weighed below 1
  /// Joint: the factors on the inverse information for the noise estimate's (or the
  /// sandwich's) own uncertainty, X's and the pattern pose's (the X-pattern block
  /// takes their geometric mean).
  double covariance_inflation = 1.0, pattern_covariance_inflation = 1.0;
  std::vector<Warning> warnings;  // e.g. residuals far larger than the stated noise

  /// A symmetric target (Rig::symmetric_face): the samples whose detected pose was
  /// replaced by its other candidate, turned by 180 degrees about the face's normal
  /// (CalibrationSession::calibrate; indices into its input, ascending).
  std::vector<int> turned;

  /// A sample left out (outliers.h, symmetric_views.h), by its index into the input: why,
  /// and the figures that decided it (io::rejected_text words them).
  struct Rejected {
    enum class Why {
      MotionsBreakAXXB,      // pairs: its motions to `disagreeing` of `compared` others beyond the gates
      FarFromPrediction,     // joint: its pattern pose `sigmas` from the prediction, beyond `gate_sigmas`
      AmbiguousBothFit,      // a symmetric target: both candidates within the gate
      AmbiguousNeitherFits,  // a symmetric target: neither
    };
    int index = 0;
    Why why = Why::FarFromPrediction;
    int disagreeing = 0, compared = 0;          // MotionsBreakAXXB
    double angle_gate = 0.0, pitch_gate = 0.0;  // MotionsBreakAXXB: rad, m
    /// Mahalanobis lengths (6 dof): the pose as detected, turned by 180 degrees (ambiguous), the gate.
    double sigmas = 0.0, turned_sigmas = 0.0, gate_sigmas = 0.0;
    /// Files carry the index and the words (result_file.cpp adds `reason`), not the figures.
    template <class Self, class Visit>
    static void fields(Self& s, Visit&& visit) {
      visit("index", s.index);
      visit("why", s.why, kInMemory);
      visit("disagreeing", s.disagreeing, kInMemory);
      visit("compared", s.compared, kInMemory);
      visit("angle_gate", s.angle_gate, kInMemory);
      visit("pitch_gate", s.pitch_gate, kInMemory);
      visit("sigmas", s.sigmas, kInMemory);
      visit("turned_sigmas", s.turned_sigmas, kInMemory);
      visit("gate_sigmas", s.gate_sigmas, kInMemory);
    }
  };
  std::vector<Rejected> rejected;

  /// The split-half check calibrated to the session (split_check.h, honesty_check), when it ran.
  using Honesty = HonestyRecord;
  std::optional<Honesty> honesty;

  using SharedError = handeye::SharedErrorRecord;
  std::optional<SharedError> shared_robot_error;

  using Prediction = handeye::PredictionRecord;
  std::optional<Prediction> prediction;

  using CornerFit = handeye::CornerFitRecord;
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
