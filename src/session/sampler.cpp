#include "handeye_covariance/session/sampler.h"

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/core/units.h"

#include <cmath>

namespace handeye {

const char* to_string(SamplerState state) {
  switch (state) {
    case SamplerState::WaitingForData: return "waiting_for_data";
    case SamplerState::WaitingForStillness: return "waiting_for_stillness";
    case SamplerState::WaitingForMotion: return "waiting_for_motion";
  }
  return "unknown";
}

namespace {

double rotation_between(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return so3::log(a.linear() * b.linear().transpose()).norm();
}

double translation_between(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return (a.translation() - b.translation()).norm();
}

bool robot_close(const Observation& a, const Observation& reference, const SamplerOptions& o) {
  return translation_between(a.T_base_effector, reference.T_base_effector) <= o.still_translation &&
         rotation_between(a.T_base_effector, reference.T_base_effector) <= o.still_rotation;
}

/// Robot and pattern both within the stillness thresholds of `reference`.
bool close(const Observation& a, const Observation& reference, const SamplerOptions& o) {
  return robot_close(a, reference, o) &&
         translation_between(a.T_camera_pattern, reference.T_camera_pattern) <= o.pattern_still_translation &&
         rotation_between(a.T_camera_pattern, reference.T_camera_pattern) <= o.pattern_still_rotation;
}

}  // namespace

Sampler::Sampler(SamplerOptions options, PoseNoise robot_noise) : options_(options), robot_noise_(robot_noise) {}

std::optional<SampleOutcome> Sampler::observe(const Observation& observation) {
  if (!history_.empty() && observation.stamp < history_.back().stamp) {
    history_.clear();  // time went backwards: a looping bag or a restarted clock
  }
  history_.push_back(observation);
  while (history_.size() > 1 && history_.front().stamp < observation.stamp - 2.0 * options_.still_window) {
    history_.pop_front();
  }
  if (waiting_for_motion_ && anchor_ && !robot_close(observation, *anchor_, options_)) {
    // The robot moved on: the next still period may be sampled. (A wrong
    // detection alone does not re-arm: only the robot's own motion does.)
    waiting_for_motion_ = false;
  }
  if (!options_.auto_sample || waiting_for_motion_ || !still()) return std::nullopt;
  return try_add(observation);
}

bool Sampler::still() const {
  if (history_.empty()) return false;
  const Observation& latest = history_.back();
  const double start = latest.stamp - options_.still_window;
  if (history_.front().stamp > start) return false;  // the window is not covered yet
  double previous = latest.stamp;
  for (auto it = history_.rbegin(); it != history_.rend(); ++it) {
    if (previous - it->stamp > options_.max_gap) return false;  // a hole: unknown motion
    if (!close(*it, latest, options_)) return false;
    if (it->stamp <= start) break;
    previous = it->stamp;
  }
  return true;
}

SampleOutcome Sampler::try_add(const Observation& observation) {
  waiting_for_motion_ = true;
  anchor_ = observation;
  for (std::size_t i = 0; i < samples_.size(); ++i) {
    const double dt = translation_between(observation.T_base_effector, samples_[i].T_base_effector);
    const double dR = rotation_between(observation.T_base_effector, samples_[i].T_base_effector);
    if (dt < options_.min_translation && dR < options_.min_rotation) {
      return {false, "refused: too close to sample " + std::to_string(i) + " (" + number_text(millimetres(dt)) + " mm, " +
                         number_text(degrees(dR)) + " deg apart; need " + number_text(millimetres(options_.min_translation)) +
                         " mm or " + number_text(degrees(options_.min_rotation)) +
                         " deg); move the robot to a new pose"};
    }
  }
  PoseSample sample;
  sample.T_base_effector = observation.T_base_effector;
  sample.T_camera_pattern = observation.T_camera_pattern;
  sample.stamp = observation.stamp;
  sample.corners = observation.corners;
  if (observation.pattern_noise) sample.noise = MeasurementNoise{robot_noise_, *observation.pattern_noise};
  samples_.push_back(sample);
  return {true, "accepted sample " + std::to_string(samples_.size() - 1)};
}

SampleOutcome Sampler::take_sample(double now) {
  if (history_.empty()) {
    return {false, "refused: no stamp-matched observation yet (is the pattern detected, and is the robot TF "
                   "available at the detection stamps?)"};
  }
  const double age = now - history_.back().stamp;
  if (age > options_.max_age) {
    return {false, "refused: the latest observation is " + number_text(age) + " s old (limit " + number_text(options_.max_age) +
                       " s); is the pattern still detected?"};
  }
  if (!still()) {
    return {false, "refused: robot or pattern moved within the last " + number_text(options_.still_window) +
                       " s; hold still and call again"};
  }
  return try_add(history_.back());
}

bool Sampler::remove(std::size_t index) {
  if (index >= samples_.size()) return false;
  samples_.erase(samples_.begin() + static_cast<std::ptrdiff_t>(index));
  return true;
}

void Sampler::reset() {
  samples_.clear();
  history_.clear();
  waiting_for_motion_ = false;
  anchor_.reset();
}

SamplerState Sampler::state() const {
  if (history_.empty()) return SamplerState::WaitingForData;
  if (waiting_for_motion_) return SamplerState::WaitingForMotion;
  return SamplerState::WaitingForStillness;
}

}  // namespace handeye
