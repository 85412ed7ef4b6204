// Targets that look the same turned by 180 degrees (core/target.h,
// is_half_turn_symmetric: a chessboard of 9 x 7 or 8 x 6 inner corners): each
// view's detected pose P = T_camera_pattern is one of two candidates, P and P * F,
// F = T_pattern_pattern' the turn by pi about the face's normal through its centre
// (half_turn). The detector cannot tell them apart; the robot's motion can.
//
// What is observable. Turning every view gives the same camera motions
// (P_j F (P_i F)^-1 = P_j P_i^-1) and moves only the pattern frame Y (Y -> Y F),
// never X: only the views' labels relative to each other count. The decision, in
// order (a wrong early choice must not lock in):
//  1. Pairs, before any X (synchronise_half_turns). For every pair i -> j the
//     robot motion A and the camera motion under "same candidate"
//     B = P_j P_i^-1 and under "one turned" B' = P_j F P_i^-1 (F = F^-1). A X = X B
//     demands that A and B rotate by the same angle and have the same screw pitch
//     (omega . t), whatever X is (Chen's screw congruence, as outliers.h's
//     consensus). Scales are robust (the lower quartile of the better hypothesis'
//     differences over all pairs). Each pair's evidence is the log-likelihood
//     ratio of the two, capped; a pair that cannot tell (a motion turning by about
//     90 degrees about the board's normal) weighs about 0, and one that fits neither
//     (a wrong detection in it) 0.
//  2. Synchronised globally, not greedily: the labels are the signs of the leading
//     eigenvector of W_ij = evidence_ij (+ same, - one turned) (spectral sign
//     synchronisation).
//  3. Refined from the fit (refine_half_turns). X and Y are solved by the joint
//     estimator from a core: the views whose labels agree with the pairs' (up to a
//     global turn, so labels half wrong still leave a consistent core) and whose
//     informative pairs mostly agree with them (the others are left out of the
//     solve, not decided; on a refusal the least trusted is dropped and the solve
//     redone). Then every view's two candidates are compared with the prediction
//     P_hat_i = X^-1 V_i Y under the residual covariance S_i of the fitted noise
//     model (residual_covariances) plus the prediction's own, J Cov(X, Y) J^T. Each
//     view takes its nearer candidate, the solve is redone from the views that
//     pass the gate below, until neither the labels nor that set change (bounded).
//  4. Gate: a view is kept when exactly one candidate lies within the chi2(6)
//     99.9% gate (scaled by outliers.h residual_scale: real detectors' covariances
//     are too small); both within or neither: it is left out, named with its two
//     Mahalanobis distances.
//  5. Normalised: when more than half of the kept views come out turned, every
//     label is turned (a global turn changes Y only), so that views detected
//     right stay as they are.
//
// A turned view's pose is P * F, and its stated camera noise follows it. The
// package's pose perturbation is additive in translation (pose_covariance.h): a
// pose's translation error is its origin's, and the turned frame's origin lies
// elsewhere (a board's: its opposite corner), a lever arm a = R_P t_F away, so
// xi_t' = xi_t - [a]x xi_R (Sigma' = J Sigma J^T, J = compose_jacobian_left(P, F);
// the rotation error is the same). Left as detected, it misweighs the turned
// views: on the real sessions of test_symmetric X moved by 0.25-0.8 sigma. Its
// corners (PoseSample::corners, for --method corners) are given in the turned
// frame (F^-1 o), each moved onto the view's own target point there when one is (a
// chessboard's corner k becomes its mirror n - 1 - k), so their coordinates and
// ids stay those of the target.
//
// The solves see the set as a session does: detections with their own
// covariance and no global noise block get the mean of theirs as the block
// (session/calibration_session.h); the kept samples keep the set's as given.
//
// Frames and conventions: rig.h (T_a_b maps points in b to a; left perturbations
// in the parent frame, ROS order x y z rx ry rz). No ROS, no OpenCV.
#pragma once

#include <string>
#include <vector>

#include "handeye_covariance/core/units.h"
#include "handeye_covariance/estimation/joint_estimator.h"

namespace handeye {

struct HalfTurnOptions {
  /// A pair fits a hypothesis within this many robust sigmas of its angle and
  /// pitch differences (outliers.h consensus_sigmas).
  double pair_gate_sigmas = 6.0;
  /// One pair's evidence (the log-likelihood ratio of its two hypotheses) is
  /// capped at this: a pair says "decided", not "decided a thousandfold".
  double max_pair_evidence = 8.0;
  /// Floors of the robust scales (noise-free input) ...
  double min_angle_sigma = 1e-5;  // rad
  double min_pitch_sigma = 1e-6;  // m
  /// ... and pitch is compared only for rotations beyond this (its axis is noise below).
  double min_pitch_angle = radians(5.0);
  /// A view whose informative pairs disagree with its label beyond this share is
  /// left out of the first solve.
  double disagreeing_share = 0.5;
  /// chi2(6) 99.9% quantile, the gate on each candidate's squared Mahalanobis distance.
  double view_gate = 22.458;
  int max_rounds = 10;
};

/// The pairs' verdict, before any X: relative labels.
struct TurnSynchronisation {
  /// Per input sample: turned relative to the others (the larger group is not).
  std::vector<bool> turned;
  /// Per input sample: its entry in the leading eigenvector, signed as `turned`
  /// (negative: turned); about 0 when no pair decides it.
  std::vector<double> support;
  int pairs = 0;             // all pairs i < j
  int decisive_pairs = 0;    // exactly one hypothesis fits
  int undecidable_pairs = 0; // both fit
  int misfit_pairs = 0;      // neither fits: a wrong detection or pairing in it
  double angle_sigma = 0.0;  // rad, the robust scale of the angle differences
  double pitch_sigma = 0.0;  // m, of the pitch differences
};

/// Stages 1-2 above (all labels false for F the identity). Throws HandEyeError:
/// NonFinite for a pose with NaN or Inf, InvalidLayout when F is not a half turn
/// (F F != I).
TurnSynchronisation synchronise_half_turns(const SampleSet& samples, const Eigen::Isometry3d& F,
                                           const HalfTurnOptions& options = {});

struct TurnDecision {
  /// Per input sample: its pose was replaced by P * F (false for the undecided).
  std::vector<bool> turned;
  /// A view left out, by its index in the input: both candidates fit, or neither.
  struct Undecided {
    int index = 0;
    std::string reason;
  };
  std::vector<Undecided> undecided;
  /// The kept samples, in input order, each with its decided candidate (a turned
  /// one with its stated noise and corners in the turned frame, above).
  SampleSet samples;
  std::vector<int> kept;  // the input index of each of `samples`
  int turned_count = 0;
  /// Per input sample, how far each candidate is from what X and its robot pose
  /// predict (Mahalanobis length, 6 dof, under S_i + J Cov(X, Y) J^T): the pose as
  /// given and the pose turned by F.
  struct Candidates {
    double as_given_sigmas = 0.0, turned_sigmas = 0.0;
  };
  std::vector<Candidates> candidates;
  double gate_sigmas = 0.0;  // the gate they were judged by (scaled)
  int rounds = 0;            // solves of stage 3
};

/// Stages 3-5 from the labels `turned` (one per sample, e.g. synchronise_half_turns'
/// or all false). Throws the estimator's named errors (HandEyeError) when no core of
/// views can be solved; NonFinite and InvalidLayout as synchronise_half_turns;
/// WrongLength when `turned` is not one label per sample. Never NaN.
TurnDecision refine_half_turns(const SampleSet& samples, const Eigen::Isometry3d& F, const std::vector<bool>& turned,
                               const JointOptions& joint = {}, const HalfTurnOptions& options = {});

/// `samples` with view i replaced by its other candidate P F where turned[i] (its
/// stated noise and corners following, as above): the views as a decision left
/// them. Throws HandEyeError(WrongLength) unless there is one label per sample.
SampleSet apply_half_turns(const SampleSet& samples, const Eigen::Isometry3d& F, const std::vector<bool>& turned);

/// Stages 1-5: each view's candidate decided from the robot's motion. F: half_turn
/// of the target (core/target.h); the identity (a target without the ambiguity)
/// keeps every sample as it is, with no solve.
TurnDecision decide_half_turns(const SampleSet& samples, const Eigen::Isometry3d& F, const JointOptions& joint = {},
                               const HalfTurnOptions& options = {});

}  // namespace handeye
