// One calibration session, without ROS: the samples, the sampler that takes
// them, the noise model, the estimate with its rejected samples, and the
// suggested next poses. The node, `handeye bag`, `handeye solve` (samples) and
// `handeye suggest` all go through this class, so each decision is made once:
// which noise a sample gets, when there is an estimate, which candidates are
// ranked with which seed, how far a plan goes.
//
// Threads: the class is not thread-safe; its owner serialises the changes. The
// computations (analyse, calibrate, suggest) are const and read only the
// settings, which never change after construction, so the node runs them on a
// snapshot() outside its lock, on a worker thread.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "handeye_covariance/estimation/estimator.h"
#include "handeye_covariance/estimation/joint_estimator.h"
#include "handeye_covariance/estimation/next_best_pose.h"
#include "handeye_covariance/estimation/outliers.h"
#include "handeye_covariance/estimation/shared_robot_error.h"
#include "handeye_covariance/estimation/calibration_check.h"
#include "handeye_covariance/estimation/split_check.h"
#include "handeye_covariance/session/sampler.h"
#include "handeye_covariance/session/session_config.h"

namespace handeye {

/// Everything a session needs, resolved from a SessionConfig (files read,
/// names checked) or set directly by a tool.
struct SessionSettings {
  Rig rig;
  SamplerOptions sampler;
  /// The configured noise: the global noise block of every sample set. Absent:
  /// the detector's per-sample covariances (their mean for samples without one),
  /// else estimated from the residuals.
  std::optional<MeasurementNoise> noise;
  bool reject_outliers = true;
  Method method = Method::Joint;  // the estimator (joint_estimator.h, the paper's pairs, or corners)
  /// Method corners: refines the joint estimate from the samples' corners. Set by
  /// the programs that link the corner estimator (corners/corner_calibration.h:
  /// corner_refiner); without it a session refuses method corners.
  CornerRefiner refine_corners;
  JointOptions::Robust robust = JointOptions::Robust::Auto;  // the joint estimator's robust mode
  /// The calibrated honesty check of calibrate_checked (splits 0: none), and
  /// whether an overconfident verdict inflates the covariance.
  HonestyOptions honesty;
  bool inflate_when_overconfident = true;
  /// calibrate_checked also fits a robot error shared by nearby poses
  /// (shared_robot_error.h, Calibration::shared_robot_error; 16 to 40 kept samples of
  /// a least-squares joint fit). Use: where the likelihood prefers it, X, Y and their
  /// covariances are the model's and the honesty check judges it; Advice: recorded
  /// and said, the per-view model's X kept; Off: not fitted.
  SharedErrorUse shared_robot_error = SharedErrorUse::Use;
  /// Next-best pose. The minimum step between poses is the sampler's
  /// (min_translation, min_rotation); candidates are drawn with
  /// suggest.seed + the number of samples, so each new sample brings fresh ones.
  SuggestOptions suggest;
  std::vector<Eigen::Isometry3d> candidate_poses;  // empty: sampled views
  int max_plan_poses = 30;                         // a plan adds at most this many
  double target_object_sigma = 1e-3;               // m, for plans and ~status
  std::string session_file;                        // empty: the samples are not persisted
};

/// The settings of a SessionConfig: reads noise_config and candidate_poses_file
/// and checks method, robust and suggest_criterion (HandEyeError naming the setting).
SessionSettings session_settings(const SessionConfig& config);
/// "auto" / "on" / "off"; throws HandEyeError(MalformedFile) naming the valid values.
JointOptions::Robust robust_from_string(const std::string& name);

/// A session over a samples file: the file's setup, frames and noise block, the
/// other settings from `config` (by default the node's defaults); nothing persisted.
SessionSettings session_settings(const SampleSet& samples, const SessionConfig& config = {});

/// What a change did.
struct SessionEvent {
  bool success = false;       // the request was honoured
  bool changed = false;       // the samples changed (generation() moved on)
  std::string message;        // "accepted sample 4", "removed sample 2", or why not
  std::string persist_error;  // non-empty: the session file could not be written
  bool check = false;         // an event of the check of a saved calibration (check_state() says more)
};

/// The samples at one moment, with their noise model: what the computations use.
struct SessionSnapshot {
  std::uint64_t generation = 0;
  SampleSet samples;
};

/// The running estimate of one generation of samples (the node's ~status).
struct Analysis {
  std::uint64_t generation = 0;
  std::size_t samples = 0;
  std::optional<Calibration> estimate;  // X with its covariance; `rejected` indexes the samples
  std::vector<SampleFit> fits;          // with an estimate: every sample's residual (outliers.h), rejected ones too
  std::optional<ScoredPose> next_pose;  // the best next pose by the configured criterion
  std::vector<ScoredPose> ranked;       // every candidate the prediction kept, best first (next_pose is the first)
  std::string problem;                  // why there is no estimate or no next pose; empty otherwise
};

struct SuggestRequest {
  std::string criterion;             // empty: the configured one
  int count = 5;                     // ranked poses wanted
  double target_object_sigma = 0.0;  // m; 0: the configured target
};

struct SuggestResult {
  Calibration estimate;     // of the consistent samples the suggestion starts from
  SampleSet samples;        // those samples
  SuggestOptions options;   // as used (criterion, seed)
  Suggestion suggestion;    // ranked candidates, best first
  Plan plan;                // greedy plan to the target
  double target_object_sigma = 0.0;
  int count = 0;
};

class CalibrationSession {
 public:
  static constexpr int kMinimumSamples = 3;

  /// Throws HandEyeError(MalformedFile) for method corners without refine_corners.
  explicit CalibrationSession(SessionSettings settings);

  const SessionSettings& settings() const { return settings_; }

  // Changes. Each one that changes the samples moves generation() on and, with a
  // session file, writes it atomically before it returns.

  /// Auto-sampling: an event when this observation completed a still period.
  std::optional<SessionEvent> observe(const Observation& observation);
  /// Manual sampling at `now` (s, the observations' clock).
  SessionEvent take_sample(double now);
  SessionEvent remove(int index);
  SessionEvent reset();
  /// Replaces the samples with a samples file's; refuses another setup and keeps
  /// the current samples on any error.
  SessionEvent load(const std::string& path);
  /// Replaces the samples (each keeps its own noise, if it has one).
  SessionEvent replace(std::vector<PoseSample> samples, const std::string& what);
  /// Reloads the session file when it exists.
  SessionEvent resume();
  /// Writes the samples with their noise model (the session file's format).
  SessionEvent save(const std::string& path) const;

  // A check of a saved calibration (estimation/calibration_check.h) from new views,
  // taken as samples are (the sampler's stillness and distinctness rules) into a list
  // of their own: the session's samples are not touched, its generation does not move.

  /// Begins a check of `calibration` from the next `views` views; an earlier check's
  /// views are dropped. Refuses a calibration the check cannot use (its reason).
  SessionEvent start_check(Calibration calibration, int views = 5);
  SessionEvent cancel_check();
  struct CheckState {
    bool collecting = false;
    int taken = 0, needed = 0;
    std::optional<CalibrationCheck> result;  // the last finished check
  };
  CheckState check_state() const;

  // State.
  std::uint64_t generation() const { return generation_; }
  const std::vector<PoseSample>& samples() const { return sampler_.samples(); }
  SamplerState state() const { return sampler_.state(); }
  /// The samples with the noise model (see SessionSettings::noise).
  SampleSet sample_set() const;
  SessionSnapshot snapshot() const { return {generation_, sample_set()}; }

  // Computations on a snapshot.

  /// The estimate and the best next pose; never throws (problems are reported).
  Analysis analyse(const SessionSnapshot& snapshot) const;
  /// X with its covariance, outliers rejected when configured; method corners
  /// refines the joint estimate from the kept samples' corners. A symmetric target
  /// (Rig::symmetric_face) has each view's candidate decided from the robot's motion
  /// first (estimation/symmetric_views.h): Calibration::turned lists the views
  /// turned, `rejected` the ones left out as ambiguous, with the rest. Throws HandEyeError.
  Calibration calibrate(const SessionSnapshot& snapshot) const;
  /// The samples as `calibration` decided them: each view it turned replaced by its
  /// other candidate (its noise and corners following); all of them, in order, so
  /// that `rejected`'s indices hold. The samples themselves without a symmetric target.
  SampleSet decided(const SampleSet& samples, const Calibration& calibration) const;
  /// calibrate() of samples decided already (decided()): no decision of turns.
  Calibration calibrate_decided(const SessionSnapshot& snapshot) const;
  /// calibrate(), then the shared robot error (settings' shared_robot_error;
  /// Calibration::shared_robot_error): with Use, where the likelihood prefers it, X, Y and
  /// their covariances become its own; then, unless it is used, the leave-one-out
  /// prediction (Calibration::prediction) a check of new views scales by. What
  /// calibrate_checked and the report judge. Throws HandEyeError.
  Calibration calibrate_modelled(const SessionSnapshot& snapshot) const;
  /// calibrate_modelled(), then the calibrated honesty check on the kept samples
  /// (Calibration::honesty; honesty_check below), the covariance inflated when it is
  /// overconfident and the settings say so. The check needs 8 kept samples and a
  /// pose-level method; otherwise the record says why it did not run. Seconds of
  /// work for 30 samples: the node runs it on its worker. Throws HandEyeError.
  Calibration calibrate_checked(const SessionSnapshot& snapshot) const;
  /// Where `calibration` uses the shared robot error's model: the per-view model's own
  /// honesty check on `kept` (its kept samples), recorded as per_view_inflation and
  /// per_view_honesty (the check of a saved calibration predicts about that model's X and
  /// Y under the shared error, and with that model alone from a file without its views:
  /// per_view_calibration). Never throws: a refused check is recorded as not run.
  void check_per_view(const SessionSnapshot& kept, Calibration& calibration, const HonestyOptions& options) const;
  /// The shared robot error about `calibration` of `snapshot` (calibrate()): the fit,
  /// or none with why in `not_fitted` (too few or too many kept samples, robust mode,
  /// another method, the fit refused).
  std::optional<SharedRobotErrorFit> shared_error_fit(const SessionSnapshot& snapshot, const Calibration& calibration,
                                                      std::string* not_fitted) const;
  /// The split-half check (split_check.h) of this session's calibration: `splits`
  /// random halves of the (decided) samples, each calibrated as calibrate_decided() does.
  SplitCheck split_check(const SessionSnapshot& snapshot, int splits = 40, unsigned seed = 1) const;
  /// The split-half check against its parametric-bootstrap reference at this
  /// session's own poses and fitted noise (split_check.h, honesty_check), from
  /// `calibration` (calibrate_modelled()'s of the snapshot, which holds its kept
  /// samples); of the shared robot error's model when the calibration uses it
  /// (check_shared_robot_error, its GLS halves). Throws HandEyeError.
  HonestyCheck honesty_check(const SessionSnapshot& snapshot, const Calibration& calibration,
                             const HonestyOptions& options = {}) const;
  /// Ranked next poses and the plan to the target. Throws HandEyeError (no
  /// estimate, every candidate refused, unknown criterion).
  SuggestResult suggest(const SessionSnapshot& snapshot, const SuggestRequest& request) const;

 private:
  SessionEvent changed(std::string message);
  /// A view taken for the check (or refused): counts it, and runs the check on the last.
  SessionEvent check_view(const SampleOutcome& outcome);
  SuggestOptions suggest_options(const std::string& criterion, std::size_t samples) const;

  const SessionSettings settings_;
  Sampler sampler_;
  std::uint64_t generation_ = 0;
  struct Check {
    Calibration calibration;
    Sampler views;
    int needed = 5;
  };
  std::optional<Check> check_;                     // collecting
  std::optional<CalibrationCheck> check_result_;  // the last finished check
};

}  // namespace handeye
