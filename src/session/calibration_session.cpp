#include "handeye_covariance/session/calibration_session.h"

#include <cstdlib>
#include <filesystem>

#include "handeye_covariance/core/units.h"
#include "handeye_covariance/estimation/calibration_check.h"
#include "handeye_covariance/estimation/outliers.h"
#include "handeye_covariance/estimation/shared_robot_error.h"
#include "handeye_covariance/estimation/solve.h"
#include "handeye_covariance/estimation/symmetric_views.h"
#include "handeye_covariance/io/check_text.h"
#include "handeye_covariance/io/honesty_text.h"
#include "handeye_covariance/io/noise_text.h"
#include "handeye_covariance/io/yaml_io.h"

namespace handeye {

using io::expand_home;

JointOptions::Robust robust_from_string(const std::string& name) {
  if (name == "auto") return JointOptions::Robust::Auto;
  if (name == "on") return JointOptions::Robust::On;
  if (name == "off") return JointOptions::Robust::Off;
  throw HandEyeError(ErrorCode::MalformedFile, "unknown robust mode `" + name + "`", "robust",
                     "use auto (Huber's loss and the sandwich covariance when the residuals are heavy-tailed), on or off");
}

SessionSettings session_settings(const SessionConfig& config) {
  SessionSettings s;
  s.rig = config.rig;
  if (!config.target_file.empty()) set_target(s.rig, io::read_target(expand_home(config.target_file)));
  s.sampler = config.sampler;
  if (!config.noise_config.empty()) s.noise = io::read_noise_file(expand_home(config.noise_config));
  s.reject_outliers = config.reject_outliers;
  s.method = method_from_string(config.method);
  s.robust = robust_from_string(config.robust);
  if (config.honesty_splits < 0 || config.honesty_sessions < 2 || config.honesty_run_length < 0) {
    throw HandEyeError(ErrorCode::MalformedFile,
                       "honesty_splits must be >= 0, honesty_sessions >= 2 and honesty_run_length >= 0, got " +
                           std::to_string(config.honesty_splits) + ", " + std::to_string(config.honesty_sessions) + " and " +
                           std::to_string(config.honesty_run_length),
                       "honesty_splits", "use e.g. honesty_splits: 200, honesty_sessions: 100 (honesty_splits: 0 turns the check off)");
  }
  s.honesty.splits = config.honesty_splits;
  s.honesty.replicates = config.honesty_sessions;
  s.honesty.run_length = config.honesty_run_length;
  s.inflate_when_overconfident = config.inflate_when_overconfident;
  s.shared_robot_error = shared_error_use_from_string(config.shared_robot_error, "shared_robot_error");
  s.suggest.criterion = criterion_from_string(config.suggest_criterion);  // a typo is refused at start
  s.suggest.working_distance = config.working_distance;
  s.suggest.candidates = config.suggest_candidates;
  s.suggest.max_step_translation = config.reach_translation;
  s.suggest.max_step_rotation = config.reach_rotation;
  if (!config.candidate_poses_file.empty()) {
    s.candidate_poses = io::read_candidate_poses(expand_home(config.candidate_poses_file));
  }
  s.target_object_sigma = metres(config.target_tolerance_mm);
  s.session_file = expand_home(config.session_file);
  return s;
}

SessionSettings session_settings(const SampleSet& samples, const SessionConfig& config) {
  SessionSettings s = session_settings(config);
  const Rig configured = s.rig;
  s.rig = samples.rig;
  if (!config.target_file.empty()) {  // the configured target over the file's
    s.rig.T_pattern_face = configured.T_pattern_face;
    s.rig.face_size = configured.face_size;
    s.rig.symmetric_face = configured.symmetric_face;
  }
  s.noise = samples.noise;
  s.session_file.clear();
  return s;
}

CalibrationSession::CalibrationSession(SessionSettings settings)
    : settings_(std::move(settings)),
      // A sample with the detector's covariance gets the configured robot noise, else none (exact).
      sampler_(settings_.sampler, settings_.noise ? settings_.noise->robot : PoseNoise{}) {
  if (settings_.method == Method::Corners && !settings_.refine_corners) throw corners_need_images();
}

// ------------------------------------------------------------------ changes

SessionEvent CalibrationSession::changed(std::string message) {
  ++generation_;
  SessionEvent event;
  event.success = true;
  event.changed = true;
  event.message = std::move(message);
  if (!settings_.session_file.empty()) {
    try {
      io::write_file_atomically(settings_.session_file, io::format_samples(sample_set()));
    } catch (const HandEyeError& e) {
      event.persist_error = e.what();
    }
  }
  return event;
}

std::optional<SessionEvent> CalibrationSession::observe(const Observation& observation) {
  if (check_) {  // a check collects its own views; the samples wait
    const std::optional<SampleOutcome> outcome = check_->views.observe(observation);
    if (!outcome) return std::nullopt;
    return check_view(*outcome);
  }
  const std::optional<SampleOutcome> outcome = sampler_.observe(observation);
  if (!outcome) return std::nullopt;
  if (outcome->accepted) return changed(outcome->message);
  return SessionEvent{false, false, outcome->message, ""};
}

SessionEvent CalibrationSession::take_sample(double now) {
  if (check_) return check_view(check_->views.take_sample(now));
  const SampleOutcome outcome = sampler_.take_sample(now);
  if (outcome.accepted) return changed(outcome.message);
  return {false, false, outcome.message, ""};
}

SessionEvent CalibrationSession::start_check(Calibration calibration, int views) {
  if (views < 1) return {false, false, "a check needs at least one view (5 is the figure it is measured at)", "", true};
  try {
    require_checkable(calibration);
  } catch (const HandEyeError& e) {
    return {false, false, std::string("this calibration cannot be checked: ") + e.what(), "", true};
  }
  check_ = Check{std::move(calibration), Sampler(settings_.sampler, settings_.noise ? settings_.noise->robot : PoseNoise{}),
                 views};
  return {true, false,
          "check started: move the robot to " + std::to_string(views) +
              " new poses (the board in view, still at each); the calibration's samples are not touched",
          "", true};
}

SessionEvent CalibrationSession::cancel_check() {
  if (!check_) return {false, false, "no check is collecting views", "", true};
  check_.reset();
  return {true, false, "check cancelled", "", true};
}

CalibrationSession::CheckState CalibrationSession::check_state() const {
  CheckState state;
  state.result = check_result_;
  if (check_) {
    state.collecting = true;
    state.taken = static_cast<int>(check_->views.samples().size());
    state.needed = check_->needed;
  }
  return state;
}

SessionEvent CalibrationSession::check_view(const SampleOutcome& outcome) {
  if (!outcome.accepted) return {false, false, "check: " + outcome.message, "", true};
  const int taken = static_cast<int>(check_->views.samples().size());
  if (taken < check_->needed) {
    return {true, false, "check: view " + std::to_string(taken) + " of " + std::to_string(check_->needed) + " taken", "", true};
  }
  SampleSet views;  // as sample_set() is made, from the check's own views
  views.rig = settings_.rig;
  views.noise = settings_.noise;
  views.samples = check_->views.samples();
  const Calibration calibration = std::move(check_->calibration);
  check_.reset();
  try {
    check_result_ = check_calibration(calibration, with_default_noise(views));
  } catch (const HandEyeError& e) {
    return {false, false, std::string("check: ") + e.what(), "", true};
  }
  return {true, false, "check: " + io::check_verdict(*check_result_), "", true};
}

SessionEvent CalibrationSession::remove(int index) {
  const std::size_t count = samples().size();
  if (index < 0 || !sampler_.remove(static_cast<std::size_t>(index))) {
    return {false, false,
            "no sample " + std::to_string(index) + ": valid indices are 0.." + std::to_string(static_cast<long>(count) - 1) +
                " (see list_samples)",
            ""};
  }
  return changed("removed sample " + std::to_string(index));
}

SessionEvent CalibrationSession::reset() {
  sampler_.reset();
  return changed("reset: all samples dropped");
}

SessionEvent CalibrationSession::replace(std::vector<PoseSample> samples, const std::string& what) {
  sampler_.set_samples(std::move(samples));
  return changed(what);
}

SessionEvent CalibrationSession::load(const std::string& path) {
  try {
    const SampleSet loaded = io::read_samples(expand_home(path));
    if (loaded.rig.setup != settings_.rig.setup) {
      throw HandEyeError(ErrorCode::MalformedFile,
                         std::string("the file is ") + to_string(loaded.rig.setup) + " but this session is " +
                             to_string(settings_.rig.setup),
                         path, "load a file recorded with the same setup");
    }
    const std::size_t n = loaded.samples.size();
    return replace(loaded.samples, "loaded " + std::to_string(n) + " samples from " + path);
  } catch (const HandEyeError& e) {
    return {false, false, e.what(), ""};  // the current samples are kept
  }
}

SessionEvent CalibrationSession::resume() {
  if (settings_.session_file.empty() || !std::filesystem::exists(settings_.session_file)) {
    return {false, false, "no session file to resume from", ""};
  }
  SessionEvent event = load(settings_.session_file);
  if (event.success) event.message = "resumed " + std::to_string(samples().size()) + " samples";
  return event;
}

SessionEvent CalibrationSession::save(const std::string& path) const {
  try {
    io::write_file_atomically(expand_home(path), io::format_samples(sample_set()));
    return {true, false, "saved " + std::to_string(samples().size()) + " samples to " + expand_home(path), ""};
  } catch (const HandEyeError& e) {
    return {false, false, e.what(), ""};
  }
}

// ------------------------------------------------------------------ the noise model

SampleSet CalibrationSession::sample_set() const {
  SampleSet set;
  set.rig = settings_.rig;
  set.noise = settings_.noise;
  set.samples = samples();
  return with_default_noise(std::move(set));  // samples without a covariance of their own get the mean block
}

// ------------------------------------------------------------------ computations

Calibration CalibrationSession::calibrate(const SessionSnapshot& snapshot) const {
  if (!settings_.rig.symmetric_face) return calibrate_decided(snapshot);
  // A symmetric target: each view's candidate from the robot's motion first.
  JointOptions joint;
  joint.robust = settings_.robust;
  const TurnDecision d = decide_half_turns(snapshot.samples, settings_.rig.face_half_turn(), joint);
  Calibration c = calibrate_decided({snapshot.generation, d.samples});
  for (Calibration::Rejected& r : c.rejected) r.index = d.kept.at(static_cast<std::size_t>(r.index));  // the snapshot's indices
  for (const TurnDecision::Undecided& u : d.undecided) {
    c.rejected.push_back(undecided_rejection(d, u));
  }
  std::sort(c.rejected.begin(), c.rejected.end(), [](const auto& a, const auto& b) { return a.index < b.index; });
  for (std::size_t i = 0; i < d.turned.size(); ++i) {
    if (d.turned[i]) c.turned.push_back(static_cast<int>(i));
  }
  Warning w;
  w.kind = Warning::Kind::SymmetricTarget;
  w.count = static_cast<int>(c.turned.size());
  w.views = static_cast<int>(snapshot.samples.samples.size());
  w.ambiguous = static_cast<int>(d.undecided.size());
  c.warnings.push_back(w);
  return c;
}

SampleSet CalibrationSession::decided(const SampleSet& samples, const Calibration& calibration) const {
  if (calibration.turned.empty()) return samples;
  std::vector<bool> turned(samples.samples.size(), false);
  for (int i : calibration.turned) turned.at(static_cast<std::size_t>(i)) = true;
  return apply_half_turns(samples, settings_.rig.face_half_turn(), turned);
}

Calibration CalibrationSession::calibrate_decided(const SessionSnapshot& snapshot) const {
  JointOptions joint;
  joint.robust = settings_.robust;
  if (settings_.method != Method::Corners) {
    return solve_samples(snapshot.samples, settings_.reject_outliers, settings_.method, joint);
  }
  // The joint estimate first: it rejects the outliers and starts the corners.
  const Calibration pose_level = solve_samples(snapshot.samples, settings_.reject_outliers, Method::Joint, joint);
  Calibration c = settings_.refine_corners(snapshot.samples, pose_level, settings_.robust);
  if (c.corner_fit) io::word_corner_fit(*c.corner_fit);
  return c;
}

std::optional<SharedRobotErrorFit> CalibrationSession::shared_error_fit(const SessionSnapshot& snapshot, const Calibration& c,
                                                                      std::string* not_fitted) const {
  if (c.method != Method::Joint || !c.pattern) {
    *not_fitted = "it is a model of the joint estimator's residuals (method " + std::string(to_string(c.method)) + ")";
    return std::nullopt;
  }
  if (c.covariance_kind == CovarianceKind::Sandwich) {
    *not_fitted = "robust mode: the Huber-weighted fit is not the least-squares one the model is linearised at";
    return std::nullopt;
  }
  const SharedRobotErrorOptions options;
  const int kept = static_cast<int>(snapshot.samples.samples.size() - c.rejected.size());
  if (kept < options.min_samples || kept > options.max_samples) {
    *not_fitted = std::to_string(kept) + " kept samples; it is fitted from " + std::to_string(options.min_samples) + " to " +
                  std::to_string(options.max_samples);
    return std::nullopt;
  }
  try {  // about c itself, on the samples as it decided them (its rejected left out by the fit)
    return fit_shared_robot_error(decided(snapshot.samples, c), c, options);
  } catch (const HandEyeError& e) {  // the calibration stands without it
    *not_fitted = std::string("the fit was refused: ") + e.what();
  }
  return std::nullopt;
}

Calibration CalibrationSession::calibrate_modelled(const SessionSnapshot& snapshot) const {
  Calibration c = calibrate(snapshot);
  // The shared robot error, about the per-view calibration.
  if (settings_.shared_robot_error != SharedErrorUse::Off) {
    Calibration::SharedError record;
    const std::optional<SharedRobotErrorFit> shared = shared_error_fit(snapshot, c, &record.not_fitted);
    if (shared) record = shared_error_record(*shared);
    c.shared_robot_error = record;
    if (shared && shared->chosen && settings_.shared_robot_error == SharedErrorUse::Use) use_shared_robot_error(c, *shared);
  }
  // How well it predicts a view it has not seen (leave-one-out), for a later check of
  // new views; one under the shared robot error predicts them under that model instead.
  const bool shared_used = c.shared_robot_error && c.shared_robot_error->used;
  if (settings_.method != Method::Corners && c.pattern && !shared_used) {
    const SessionSnapshot kept{snapshot.generation, without_rejected(decided(snapshot.samples, c), c)};
    c.prediction = prediction_check(kept.samples, [this, &kept](const SampleSet& others) {
      return calibrate_decided({kept.generation, others});
    });
  }
  return c;
}

Calibration CalibrationSession::calibrate_checked(const SessionSnapshot& snapshot) const {
  Calibration c = calibrate_modelled(snapshot);
  const auto not_run = [&c](const std::string& why) {
    Calibration::Honesty h;
    h.verdict = Honesty::NotRun;
    h.text = why;
    h.model_pose_covariance = c.pose_covariance;
    c.honesty = h;
  };
  if (settings_.honesty.splits <= 0) {
    not_run("the check is off (honesty_splits: 0)");
    return c;
  }
  if (settings_.method == Method::Corners) {
    not_run("method corners: the check solves simulated sessions at the pose level; run it on the joint estimate");
    return c;
  }
  // The kept samples, as the calibration decided them: what the check judges.
  const SessionSnapshot kept{snapshot.generation, without_rejected(decided(snapshot.samples, c), c)};
  if (kept.samples.samples.size() < 8) {
    not_run("it needs 8 kept samples (two halves of 4), there are " + std::to_string(kept.samples.samples.size()));
    return c;
  }
  if (c.shared_robot_error && c.shared_robot_error->used) {
    check_per_view(kept, c, settings_.honesty);
    try {  // the model in use judges itself
      const HonestyCheck check = honesty_check(kept, c, settings_.honesty);
      record_honesty(c, check, settings_.inflate_when_overconfident, io::honesty_text(check));
    } catch (const HandEyeError& e) {  // the calibration stands; the record says why there is no verdict
      not_run(std::string("the shared robot error's check was refused: ") + e.what());
    }
    return c;
  }
  // The reference simulates from the kept samples' own fit (without the rejected).
  const Calibration fitted = c.rejected.empty() ? c : calibrate_decided(kept);
  const HonestyCheck check = honesty_check(kept, fitted, settings_.honesty);
  record_honesty(c, check, settings_.inflate_when_overconfident, io::honesty_text(check));
  return c;
}

void CalibrationSession::check_per_view(const SessionSnapshot& kept, Calibration& c, const HonestyOptions& options) const {
  if (!c.shared_robot_error || !c.shared_robot_error->used) return;
  Calibration::SharedError& e = *c.shared_robot_error;
  Calibration per_view = per_view_calibration(c);
  per_view.honesty.reset();
  try {
    // Its reference simulates from the kept samples' own fit (without the rejected).
    const HonestyCheck own = honesty_check(kept, per_view.rejected.empty() ? per_view : calibrate_decided(kept), options);
    e.per_view_inflation = settings_.inflate_when_overconfident && own.verdict == Honesty::Overconfident ? own.inflation : 1.0;
    e.per_view_honesty = own.ran() ? io::honesty_text(own) : "not run: " + own.text;
  } catch (const HandEyeError& error) {
    e.per_view_inflation = 1.0;
    e.per_view_honesty = std::string("not run: ") + error.what();
  }
}

SplitCheck CalibrationSession::split_check(const SessionSnapshot& snapshot, int splits, unsigned seed) const {
  return handeye::split_check(
      snapshot.samples, [this, &snapshot](const SampleSet& half) { return calibrate_decided({snapshot.generation, half}); },
      splits, seed);
}

HonestyCheck CalibrationSession::honesty_check(const SessionSnapshot& snapshot, const Calibration& calibration,
                                               const HonestyOptions& options) const {
  if (calibration.shared_robot_error && calibration.shared_robot_error->used) {
    // The model in use judges itself (its GLS halves, its bootstrap), linearised where
    // it was fitted: at the per-view X and Y, on these kept samples.
    const Calibration::SharedError& e = *calibration.shared_robot_error;
    Calibration per_view = per_view_calibration(calibration);
    per_view.rejected.clear();  // the snapshot holds the kept samples
    const SharedRobotError model = model_of(e);
    return check_shared_robot_error(snapshot.samples, per_view, model, options, SharedErrorEstimator::Gls);
  }
  return handeye::honesty_check(
      snapshot.samples, calibration,
      [this, &snapshot](const SampleSet& half) { return calibrate_decided({snapshot.generation, half}); }, options);
}

SuggestOptions CalibrationSession::suggest_options(const std::string& criterion, std::size_t samples) const {
  SuggestOptions options = settings_.suggest;
  if (!criterion.empty()) options.criterion = criterion_from_string(criterion);
  options.min_translation = settings_.sampler.min_translation;  // as distinct as the sampler requires
  options.min_rotation = settings_.sampler.min_rotation;
  options.seed = settings_.suggest.seed + static_cast<unsigned>(samples);  // fresh candidates after each sample
  return options;
}

SuggestResult CalibrationSession::suggest(const SessionSnapshot& snapshot, const SuggestRequest& request) const {
  const std::size_t n = snapshot.samples.samples.size();
  if (n < static_cast<std::size_t>(kMinimumSamples)) {
    throw HandEyeError(ErrorCode::TooFewMotions,
                       "no estimate yet: " + std::to_string(n) + " sample(s); take at least " +
                           std::to_string(kMinimumSamples) + " (rotating about different axes) first",
                       "samples", "take more samples, then ask again");
  }
  SuggestResult r;
  r.options = suggest_options(request.criterion, n);
  r.estimate = calibrate(snapshot);
  r.samples = without_rejected(decided(snapshot.samples, r.estimate), r.estimate);  // plan from the consistent samples
  const std::vector<Eigen::Isometry3d> candidates = settings_.candidate_poses.empty()
                                                        ? sample_candidates(r.samples, r.estimate, r.options)
                                                        : settings_.candidate_poses;
  r.suggestion = rank_candidates(r.samples, r.estimate, candidates, r.options);
  if (r.suggestion.ranked.empty()) {
    throw HandEyeError(ErrorCode::NoData, "every candidate was refused by the prediction", "candidates",
                       "give candidates that rotate about new axes, or widen the reach (reach_translation_mm, "
                       "reach_rotation_deg)");
  }
  r.target_object_sigma = request.target_object_sigma > 0.0 ? request.target_object_sigma : settings_.target_object_sigma;
  r.count = request.count > 0 ? request.count : 5;
  r.plan = plan_poses(r.samples, r.estimate, r.target_object_sigma, settings_.max_plan_poses, r.options,
                      settings_.candidate_poses);
  return r;
}

Analysis CalibrationSession::analyse(const SessionSnapshot& snapshot) const {
  Analysis a;
  a.generation = snapshot.generation;
  a.samples = snapshot.samples.samples.size();
  if (a.samples < static_cast<std::size_t>(kMinimumSamples)) return a;
  try {
    a.estimate = calibrate(snapshot);
  } catch (const HandEyeError& e) {
    a.problem = std::string("no estimate yet: ") + e.what();
    return a;
  }
  try {
    const SampleSet as_decided = decided(snapshot.samples, *a.estimate);
    a.fits = sample_fits(as_decided, *a.estimate);
    const SampleSet kept = without_rejected(as_decided, *a.estimate);
    const SuggestOptions options = suggest_options("", a.samples);
    const std::vector<Eigen::Isometry3d> candidates =
        settings_.candidate_poses.empty() ? sample_candidates(kept, *a.estimate, options) : settings_.candidate_poses;
    Suggestion s = rank_candidates(kept, *a.estimate, candidates, options);
    if (!s.ranked.empty()) a.next_pose = s.ranked.front();
    a.ranked = std::move(s.ranked);
  } catch (const HandEyeError& e) {
    a.problem = std::string("no next pose: ") + e.what();
  }
  return a;
}

}  // namespace handeye
