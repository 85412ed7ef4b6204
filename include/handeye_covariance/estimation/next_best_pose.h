// Which pose to add next, and how many more (the paper's stated future work):
// candidates for the next effector pose are ranked by the covariance of X the
// estimator predicts once that pose is added, with the session's noise (given
// or estimated). For the joint estimator a candidate adds its rank-6 term
// H^T S^-1 H to the 12x12 information of (X, Y): no re-solve. For the pairs
// estimator the prediction is a solve of the current samples plus the
// candidate's noise-free predicted sample.
//
// Criteria:
//   object_sigma: the worst-axis 1 sigma of an object's position at the working
//     distance on the camera's optical axis (what the node's ~status reports);
//   determinant: log det of X's 6x6 covariance (D-optimal; its ranking does not
//     depend on the units of translation and rotation).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "handeye_covariance/core/units.h"
#include "handeye_covariance/estimation/estimator.h"
#include "handeye_covariance/estimation/noise_estimation.h"
#include "handeye_covariance/core/viewpoints.h"

namespace handeye {

enum class SuggestCriterion { ObjectSigma, Determinant };
const char* to_string(SuggestCriterion criterion);  // "object_sigma" / "determinant"
/// Throws HandEyeError(MalformedFile) naming the valid values.
SuggestCriterion criterion_from_string(const std::string& name);

struct SuggestOptions {
  SuggestCriterion criterion = SuggestCriterion::ObjectSigma;
  double working_distance = 0.7;  // m, along the camera's optical axis
  /// Sampled candidates (when none are given): views of the pattern within
  /// these limits ...
  int candidates = 150;
  ViewpointOptions views;
  /// ... reachable from the current effector pose in one move ...
  double max_step_translation = 0.5;            // m
  double max_step_rotation = radians(90.0);  // rad
  /// ... and distinct from every sample (as the sampler requires).
  double min_translation = 0.01;                // m
  double min_rotation = radians(2.0);     // rad
  unsigned seed = 1;
};

struct ScoredPose {
  Eigen::Isometry3d T_base_effector = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d T_camera_pattern = Eigen::Isometry3d::Identity();  // what the camera should see there
  double score = 0.0;          // the criterion after adding this pose (smaller is better)
  double object_sigma = 0.0;   // m, after adding it (always reported)
  Matrix6d predicted_covariance = Matrix6d::Zero();
  /// Joint: the predicted 12x12 covariance of (X, Y), for the next step of a plan.
  Eigen::Matrix<double, 12, 12> predicted_joint_covariance = Eigen::Matrix<double, 12, 12>::Zero();
};

struct Suggestion {
  double current_score = 0.0;
  double current_object_sigma = 0.0;   // m
  std::vector<ScoredPose> ranked;      // best first
  int considered = 0;                  // candidates scored
  int refused = 0;                     // candidates the prediction refused (degenerate with the samples)
};

/// The criterion for X with its covariance.
double criterion_value(const PoseWithCovariance& X, SuggestCriterion criterion, double working_distance);
/// Worst-axis 1 sigma (m) of a point at `working_distance` on the camera's
/// optical axis, in X's parent frame (the node's ~status object_error_mm).
double object_sigma(const PoseWithCovariance& X, double working_distance);

/// A calibration against a target object sigma: the one decision behind ~status's
/// target_reached, the arm's auto mode and its AutoCalibrate action, the report's
/// advice and the studies.
struct TargetProgress {
  double object_sigma = 0.0;  // m, object_sigma() of X at the working distance
  bool reached = false;
  std::string why_not;        // within the target but not reached: why (else empty)
};
/// The fewest samples from which a covariance that rests on a noise estimated from
/// the residuals can reach a target. Stopping at the first count whose estimated
/// sigma meets the target picks the sessions whose noise came out small by chance:
/// on the simulated arm with the node's estimated noise (handeye_auto_study --noise
/// estimated), sessions stopped at 5 samples had a NEES of X of 11.0, at 6 of 7.0;
/// from 7 the NEES is the fixed-count one (6.4). Calibrated on the joint estimator's noise
/// models (n - 2 samples' worth of residuals). A stated noise the residuals accept reaches
/// it from any count.
constexpr int kTargetMinimumSamplesEstimatedNoise = 7;
/// Reached when X's object sigma at `working_distance` is within `target` (m) and, if
/// its covariance rests on an estimated noise (noise_origin, a noise component the
/// residuals supported, or the corners method's robot noise estimated from the corners),
/// it has kTargetMinimumSamplesEstimatedNoise samples.
TargetProgress target_progress(const Calibration& calibration, double target, double working_distance);
/// How many samples `calibration`'s noise model needs beyond `samples` to reach a target
/// (0 with a stated noise the residuals accepted); plan_poses plans that many at least.
int samples_short_of_target(const Calibration& calibration, int samples);

/// Candidate effector poses: random views of the pattern (options.views) that
/// are within one move of the last sample's effector pose and distinct from
/// every sample. Deterministic for a given options.seed.
std::vector<Eigen::Isometry3d> sample_candidates(const SampleSet& samples, const Calibration& calibration,
                                                 const SuggestOptions& options);

/// Ranks `candidates` (effector poses) by the predicted criterion. Needs the
/// current calibration of `samples`. Throws NoData for no candidates.
Suggestion rank_candidates(const SampleSet& samples, const Calibration& calibration,
                           const std::vector<Eigen::Isometry3d>& candidates, const SuggestOptions& options);

/// "How many more, and which": greedily adds the best candidate (its predicted
/// sample) until the object sigma reaches `target_object_sigma` or `max_poses`
/// are added. Each step draws fresh candidates from the last added pose, unless
/// `fixed_candidates` are given (then each is used at most once).
struct Plan {
  std::vector<ScoredPose> poses;  // in order; poses[i].object_sigma is after adding poses[0..i]
  bool reached = false;
  double start_object_sigma = 0.0;
  /// Poses planned at least because the noise is estimated (samples_short_of_target at the start).
  int poses_for_the_noise = 0;
};
Plan plan_poses(const SampleSet& samples, const Calibration& calibration, double target_object_sigma, int max_poses,
                const SuggestOptions& options, const std::vector<Eigen::Isometry3d>& fixed_candidates = {});
/// What a reached plan says of the poses its noise model needs (handeye suggest and the
/// node's ~suggest_pose): "; at least 3, as the noise is estimated: a target counts from 7
/// samples", or "" when it needs none.
std::string poses_for_the_noise_text(const Plan& plan);

}  // namespace handeye
