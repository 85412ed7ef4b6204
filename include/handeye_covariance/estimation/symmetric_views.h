// Targets that look the same turned by 180 degrees (core/target.h,
// is_half_turn_symmetric): each view's detected pose P = T_camera_pattern is P or
// P * F, F = half_turn, the turn by pi about the face's normal through its centre.
// The views are labelled from the robot's motion (synchronise_half_turns: pairs, then
// spectral sign synchronisation; refine_half_turns: from the joint fit, a chi2(6) 99.9%
// gate); a turned view's pose, stated covariance and corners move to the turned frame.
// Only relative labels are observable: a global turn moves Y, never X. Frames: rig.h
// (T_a_b maps points in b to a; left perturbations, ROS order). No ROS, no OpenCV.
// Derivation: docs/how_it_works.md, "Symmetric boards: each view's pose decided from the motion".
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
  /// A view left out, by its index in the input: both candidates fit, or neither
  /// (their distances in `candidates`, the gate in `gate_sigmas`).
  struct Undecided {
    int index = 0;
    bool both_fit = false;
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

/// The undecided view `u` of `d` as a sample the calibration leaves out: ambiguous, with
/// its two candidates' distances and the gate (its index the input's).
Calibration::Rejected undecided_rejection(const TurnDecision& d, const TurnDecision::Undecided& u);

}  // namespace handeye
