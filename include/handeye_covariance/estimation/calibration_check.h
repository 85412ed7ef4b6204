// Is a saved calibration still right? A statistical test of a few new views
// against X, Y, their joint covariance and the noise model they were computed with.
//
// A new view i (robot pose E_i, detected pattern pose P_i) has the residual e_i of
// joint_estimator.h at the calibration's (X, Y). If nothing changed,
//     e_i = J_i delta + n_i,   delta ~ N(0, Sigma) (the calibration's own error: 12
//     numbers, X's then Y's left perturbations, with their cross block), n_i ~ N(0, S_i)
//     (the view's noise under the calibration's model, residual_covariances),
// so the stacked residual of k views is e ~ N(0, C), C = blockdiag(S_i) + J Sigma J^T:
// the views share the calibration's error, and are not independent of each other.
//
// If X moved by d (its perturbation in its parent frame, ROS order, pose_covariance.h: the
// new X has translation t_X + d_t and rotation exp(d_R) R_X), e gains -J_X d (J_X = de/dxi_X at the saved X). Its generalised-least-squares
// estimate and covariance
//     d_X = -(J_X^T C^-1 J_X)^-1 J_X^T C^-1 e,   Cov(d_X) = (J_X^T C^-1 J_X)^-1,
// and the drop of the joint chi2 e^T C^-1 e it buys, T_X = d_X^T Cov(d_X)^-1 d_X, is
// chi2(6) when nothing changed; it is the most powerful test of a change of X alone
// (noncentral chi2(6) with d^T Cov^-1 d under the change). Likewise Y (T_Y), and
// both (T_XY, 12). Cov(d_X) is X's own uncertainty plus what the new views' noise
// adds: the combined 1 sigma of the change estimate.
//
// The test: T = max(T_X, T_Y), the generalised likelihood ratio of "X or Y moved" over
// "nothing moved". Its p-value is from its null distribution at these views: T_X and T_Y
// are projections of one white residual onto two 6-dof subspaces that share part of
// their directions, so neither chi2(6) nor a Bonferroni bound is exact; a seeded
// Monte-Carlo of the two projections (40 000 draws: +-0.0005 at p = 0.01) gives it,
// with each estimated noise number drawn from its own error. A test that must catch X
// or Y at one alpha cannot reach one that knows which would move: at 5 sigma no test
// detects more than 91% instead of 92.7% at a session's usual views, 89.8% when the
// views tell X from Y well (the Neyman-Pearson bound against both, check_study.h
// two_hypothesis_power_bound); this one is within 2 points of it (the likelihood ratio
// against that mixture as the statistic did no better, at 20x the time). Changed when p < alpha. Which: both when the second change explains
// beyond chi2(6) at alpha what the better single one leaves (T_XY - T), else the one
// with the larger drop. The omnibus chi2 (6k dof) is reported beside: what is left
// after the change, chi2 - T_h against chi2(6k - dof h), says whether a rigid change
// of X or Y explains the views at all (a wrong detection or a changed noise does not).
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "handeye_covariance/estimation/estimator.h"

namespace handeye {

struct CheckOptions {
  double alpha = 0.01;          // the false-alarm rate of the verdict
  int null_draws = 40000;       // Monte-Carlo draws of the test's null distribution, at most ...
  int null_exceedances = 500;   // ... or until this many fall beyond the statistic (a valid p; relative error 1/sqrt(500), 4.5%)
  unsigned seed = 1;            // for those draws: a check is deterministic
};

/// One new view against the calibration's prediction.
struct CheckedView {
  Vector6d residual = Vector6d::Zero();          // e_i: camera frame, ROS order (m, rad)
  Matrix6d predicted_covariance = Matrix6d::Zero();  // S_i + J_i Sigma J_i^T
  double translation_error = 0.0;                // |e_t|, m
  double rotation_error = 0.0;                   // |e_r|, rad
  double predicted_translation_sigma = 0.0;      // sqrt(trace) of the translation block: |e_t|'s RMS, m
  double predicted_rotation_sigma = 0.0;         // likewise, rad
  double mahalanobis = 0.0;                      // sqrt(e_i^T C_ii^-1 e_i): chi(6) when nothing changed
  /// What this view alone still explains once the larger single change (X's or Y's) is
  /// fitted: the chi2's further drop with its own 6 numbers freed, chi2(6) when that
  /// change is all there is. Beyond the outlier gate: a wrong detection, whatever moved.
  /// 0 with 2 views or fewer (the change and the view's 6 numbers fit all 12).
  double chi2_beyond_the_change = 0.0;
};

/// Which pose a change is of.
enum class ChangedPose { X, Y, Both };
const char* to_string(ChangedPose pose);  // "X" / "Y" / "both"

/// A change of X or Y (or both) as the new views estimate it.
struct EstimatedChange {
  std::optional<ChangedPose> what;    // none: not fitted (both, from one or two views)
  double chi2_drop = 0.0;             // T_X, T_Y or T_XY
  int dof = 6;                        // 6, or 12 for both
  double residual_chi2 = 0.0;         // the joint chi2 the change leaves ...
  double residual_p_value = 1.0;      // ... and its p against chi2(6k - dof)
  /// X's change (X or both) and Y's (Y or both), each with its covariance: the
  /// perturbation of pose_covariance.h from the saved pose to the new (t = t_saved +
  /// change_t, R = exp(change_R) R_saved), in the parent frame, ROS order.
  struct Delta {
    Vector6d value = Vector6d::Zero();
    Matrix6d covariance = Matrix6d::Zero();
  };
  std::optional<Delta> X_change, Y_change;
  /// The change a verdict reports: X's (X or both), else Y's.
  const Delta& reported() const { return X_change ? *X_change : *Y_change; }
};

struct CalibrationCheck {
  std::vector<CheckedView> views;
  /// A view beyond the outlier gate alone that stays beyond it once the larger change is
  /// fitted (CheckedView::chi2_beyond_the_change; with 2 views the gate alone), and whose
  /// leaving out left the rest consistent: a wrong detection.
  std::vector<int> left_out;
  std::vector<int> turned;  // a symmetric target: the views whose other candidate the calibration predicts
  double chi2 = 0.0;        // e^T C^-1 e over the new views
  int dof = 0;              // 6 k
  double chi2_p_value = 1.0;
  double statistic = 0.0;   // max(T_X, T_Y)
  /// How much a moved X and a moved Y look alike at these views: the cosine of the
  /// smallest angle between the residual directions they can explain (1: the views
  /// cannot tell them apart; views turned about different axes lower it).
  double x_y_overlap = 0.0;
  Vector6d x_y_cosines = Vector6d::Zero();  // all six principal angles' cosines, largest first
  /// The likelihood ratio of the named change over the other single one, exp((T_a - T_b) / 2):
  /// below 19 (95 : 5) the name is uncertain and the verdict says so.
  double naming_odds = 1.0;
  double p_value = 1.0;     // of `statistic` under no change
  double alpha = 0.01;
  bool changed = false;     // p_value < alpha
  /// The change that explains the views best (`what` is "X", "Y" or "both"): when
  /// changed, the verdict's; otherwise the largest one, for the record.
  EstimatedChange change;
  EstimatedChange X_alone, Y_alone, both;  // each hypothesis, as fitted
  /// What the words need beyond the numbers (io/check_text.h check_verdict and check_advice
  /// write them): p is below the null draws' resolution; the name is uncertain (changed,
  /// X or Y named, naming_odds below 19 : 1); and the findings advice is given for, in order.
  bool p_below_resolution = false;
  bool naming_uncertain = false;
  enum class Finding {
    LeftOutView,           // left_out's view disagrees with the calibration and the other views
    TargetMoved,           // Y changed: X may still hold
    CameraMoved,           // X (or both) changed: calibrate again
    ResidualBeyondChange,  // the estimated change leaves the views beyond their chi2
    ScatterBeyondNoise,    // no change, yet the views scatter beyond the noise model
    XAndYAlike,            // the views barely tell a moved camera from a moved target
    NoPrediction,          // the calibration has no leave-one-out prediction scale
    FewViews,              // fewer than 3 views
  };
  std::vector<Finding> findings;
};

/// The test above. `calibration` needs Y (calibration.pattern), the cross block and
/// the noise model it was computed with (residual_noise): one without them is refused
/// (NoiseUnidentifiable, saying to save it again with `handeye solve` or the node).
/// When its honesty check inflated the covariance, the views' noise is inflated by the
/// same factor (the check that found the model short found its noise short). One that
/// uses the shared robot error (Calibration::SharedError::used, with its `views`) is
/// checked about its per-view X and Y under that model, scaled by the model's honesty
/// factor (no leave-one-out scale). Throws MalformedFile for a model in use without a
/// positive length or view noise scale. `views`:
/// the new samples (the calibration's setup; their own noise when the detector states
/// one; `views.rig` must be the calibration's setup). Throws NoData for no view.
CalibrationCheck check_calibration(const Calibration& calibration, const SampleSet& views, const CheckOptions& options = {});

/// Calibration::Prediction of `fitted`, the calibration of `samples` (its kept views,
/// decided), each view left out in turn and solved by `solve` (as the calibration was).
/// A left-out set the estimator refuses is skipped; nullopt with fewer than 4 views or
/// fewer than 4 predictions.
std::optional<Calibration::Prediction> prediction_check(
    const SampleSet& samples, const std::function<Calibration(const SampleSet&)>& solve);

/// Throws NoiseUnidentifiable (with the fix) unless `calibration` carries what a check
/// predicts views from: Y and the noise model (Calibration::pattern, residual_noise).
/// The one rule the offline check, the session's check and the monitor share.
void require_checkable(const Calibration& calibration);

/// Whether the calibration's own views, left out in turn, scattered more than it
/// predicts (scale > 1): then a check scales its prediction by it, else the model stands.
bool prediction_disagrees(const Calibration::Prediction& prediction);

}  // namespace handeye
