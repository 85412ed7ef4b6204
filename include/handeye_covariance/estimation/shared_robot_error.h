// A robot error shared by nearby poses: the per-view noise model with a correlated
// part, a Gaussian process over the effector's position p_i (base frame, m):
//     Cov(e_i, e_j) = s S_i [i = j] + k(p_i, p_j) D_i diag(a I3, b I3) D_j^T,
//     k(p, q) = exp(-|p - q|^2 / (2 l^2)),
// S_i the per-view residual covariance, D_i as in joint_estimator.h, a (m^2) and b
// (rad^2) per axis in the base frame. (s, a, b) by REML at each length l, chosen over the
// per-view model by BIC; then one GLS step of (X, Y) with Kenward-Roger's covariance,
// and the model's linearised split-half check.
// Derivation: docs/how_it_works.md, "A robot error shared by nearby poses".
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/estimation/estimator.h"
#include "handeye_covariance/estimation/split_check.h"

namespace handeye {

/// What a session does with the model (SessionSettings::shared_robot_error).
enum class SharedErrorUse { Use, Advice, Off };
/// "use" / "advice" / "off"; throws HandEyeError(MalformedFile) naming the valid
/// values and `where` (the setting or option). Inline: the command line's options
/// parse it without linking the estimator.
inline SharedErrorUse shared_error_use_from_string(const std::string& name, const std::string& where) {
  if (name == "use") return SharedErrorUse::Use;
  if (name == "advice") return SharedErrorUse::Advice;
  if (name == "off") return SharedErrorUse::Off;
  throw HandEyeError(ErrorCode::MalformedFile, "unknown shared robot error setting `" + name + "`", where,
                     "use `use` (where the likelihood prefers it, X and its covariance are its own), `advice` (said, "
                     "not used) or `off`");
}

struct SharedRobotError {
  double length_scale = 0.0;       // m, l of the kernel; 0: none (the per-view model alone)
  double view_noise_scale = 1.0;   // s, on the per-view model's S_i
  double translation_sigma = 0.0;  // m, 1 sigma per axis of the shared error (base frame)
  double rotation_sigma = 0.0;     // rad
  double log_likelihood = 0.0;     // restricted, up to the constant the candidates share
};

struct SharedRobotErrorOptions {
  std::vector<double> length_scales = {0.05, 0.1, 0.2, 0.4, 0.8, 1.6};  // m
  int max_iterations = 50;
  /// Fitted from this many samples used (fewer: the per-view model alone). A
  /// workspace's error needs neighbours to be told from the views' own noise
  /// (docs/how_it_works.md). The runs look of split_check starts here too.
  int min_samples = 16;
  /// ... and up to this many (more: none): the dense 6n x 6n fit grows as n^3 (its
  /// time: docs/how_it_works.md).
  int max_samples = 40;
  /// Set: this model (its length, s, a and b) is taken as chosen, nothing fitted or
  /// compared (bic_gain 0): a part of a session judged with the whole session's model.
  std::optional<SharedRobotError> model;
};

struct SharedRobotErrorFit {
  std::vector<int> used;                // sample indices fitted (the calibration's rejected left out)
  SharedRobotError per_view;            // s = 1, no shared part: the calibration's own model
  std::vector<SharedRobotError> candidates;  // one per length scale, (s, a, b) at their REML
  SharedRobotError best;                // the candidate of the highest likelihood, or per_view when none beats it
  double bic_gain = 0.0;                // 2 (L_best - L_per_view) - 4 log(6n - 12)
  bool chosen = false;                  // bic_gain > 0
  /// X and Y under the chosen model (one GLS step) with their covariance; the
  /// calibration's, its covariances recomputed under the per-view model (the same
  /// linearisation), when not chosen.
  /// Chosen: (J^T C^-1 J)^-1 adjusted for the fitted (s, a, b)'s own error (Kenward
  /// and Roger's adjustment); covariance_inflation is its mean effect on X's, tr(Phi_x^-1 Phi_A,x) / 6.
  Eigen::Isometry3d T_parent_camera = Eigen::Isometry3d::Identity();
  Matrix6d pose_covariance = Matrix6d::Zero();
  double covariance_inflation = 1.0, pattern_covariance_inflation = 1.0;
  PoseWithCovariance pattern;
  Matrix6d cross_covariance = Matrix6d::Zero();
  /// The GLS step of X judged under the chosen model: its NEES under the step's own
  /// covariance (H0 + G) C (H0 + G)^T, H0 the per-view gain and -G the GLS one (a
  /// Hausman test: about 6 when the model explains why X moved; 0 when not chosen).
  double step_nees = 0.0;
  /// The per-view estimate's X covariance under the chosen model, H0 C H0^T: what
  /// the calibration's own covariance would have to be, were the model true.
  Matrix6d per_view_estimate_covariance = Matrix6d::Zero();
  /// ... with Y's block and the cross block, and each used view's position and H0_j D_j
  /// (Calibration::SharedError::views): what a check of new views predicts them with.
  Matrix6d per_view_estimate_pattern_covariance = Matrix6d::Zero(), per_view_estimate_cross_covariance = Matrix6d::Zero();
  std::vector<Calibration::SharedError::View> views;
};

/// The shared error fitted to `samples` about `calibration` (a joint fit of them:
/// Method::Joint, with its pattern pose). Throws InvalidNoise when a residual
/// covariance is singular, TooFewMotions for fewer than 8 samples used.
SharedRobotErrorFit fit_shared_robot_error(const SampleSet& samples, const Calibration& calibration,
                                           const SharedRobotErrorOptions& options = {});

/// `calibration` as the per-view model had it, when it uses the shared robot error's
/// model (Calibration::SharedError::used): the per-view X, Y and their covariances kept
/// beside the model's (covariance_kind "information"), inflated by its own honesty
/// check's factor (per_view_inflation, recorded as the honesty inflation); otherwise
/// `calibration` itself.
/// What the check of a saved calibration predicts new views about (calibration_check.h):
/// under the model where the record holds its `views`, with this alone where not.
Calibration per_view_calibration(const Calibration& calibration);

/// The fit as Calibration::shared_robot_error records it.
Calibration::SharedError shared_error_record(const SharedRobotErrorFit& fit);
/// The model a record holds (its length, s and sigmas).
SharedRobotError model_of(const Calibration::SharedError& record);
/// Throws MalformedFile, naming `where`, unless the record's model can predict new
/// views: a length scale and a view noise scale above 0, no negative sigma.
void require_predictable(const Calibration::SharedError& record, const std::string& where);
/// The per-view estimate's joint covariance of (X, Y) under the model, X first
/// (P = H0 C H0^T, from the record's three blocks).
Matrix12d per_view_estimate_joint_covariance(const Calibration::SharedError& record);

/// k(p, q) = exp(-|p - q|^2 / (2 l^2)): how much of their robot error two poses whose
/// effectors are at p and q (base frame) share, l > 0.
double shared_error_kernel(const Eigen::Vector3d& p, const Eigen::Vector3d& q, double length_scale);
/// E = diag(a I3, b I3): the shared error's covariance per pose (translation, rotation;
/// left perturbation in the base frame), so that Cov(e_i, e_j) = k(p_i, p_j) D_i E D_j^T.
Matrix6d shared_error_covariance(const SharedRobotError& model);

/// X, Y and their covariances become the chosen model's (its GLS step); the per-view
/// model's X, Y and covariances stay in `c.shared_robot_error` (which must
/// hold shared_error_record(fit)), marked used. Throws InvalidNoise when the fit did not
/// choose a model or `c` has no record or no pattern pose.
void use_shared_robot_error(Calibration& c, const SharedRobotErrorFit& fit);

/// Whose halves the linearised check splits: the calibration's own estimator (the
/// per-view weights S_i, X as the session reports it) or the GLS one under the model.
enum class SharedErrorEstimator { PerView, Gls };

/// The split-half check of `model` (a SharedRobotErrorFit's best, per_view or any
/// candidate) on the samples fit_shared_robot_error uses, about `calibration`, as
/// honesty_check (split_check.h) reads it: random halves and halves of runs
/// (options.run_length, 0: chosen from n), each against its own bootstrap reference
/// (options.replicates sessions r* ~ N(0, C) at the session's poses, each fitting its
/// (s, a, b) again at the model's length as the session's own fit did, drawn once for
/// both looks), the band corrected to the session's splits, the worse look deciding.
/// The halves are `estimator`'s; X's difference is judged under C with the cross-half
/// terms. options.hold_noise does not apply (the noise is the model's). Throws
/// InvalidNoise when the model's covariance is not positive definite, TooFewMotions for
/// splits or replicate_splits below 1 or replicates below 2.
HonestyCheck check_shared_robot_error(const SampleSet& samples, const Calibration& calibration, const SharedRobotError& model,
                                      const HonestyOptions& options = {},
                                      SharedErrorEstimator estimator = SharedErrorEstimator::Gls);

}  // namespace handeye
