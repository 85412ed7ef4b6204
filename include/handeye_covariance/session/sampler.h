// Turning a stream of stamp-matched observations into calibration samples.
// ROS-free: the node and the offline bag replay feed it the same way.
//
// An observation is a pattern pose T_camera_pattern with its stamp, paired with
// the robot pose T_base_effector looked up AT THAT STAMP (never "latest"), so a
// sample never mixes two instants. A sample is taken only when robot and
// pattern have both been still for `still_window` seconds: latency between the
// two sources and motion blur then cannot corrupt it.
#pragma once

#include <deque>
#include <optional>
#include <string>
#include <vector>

#include "handeye_covariance/core/measurements.h"
#include "handeye_covariance/core/units.h"

namespace handeye {

struct SamplerOptions {
  bool auto_sample = true;             // take a sample by itself once still
  double still_window = 1.0;           // s of stillness required
  double still_translation = 0.0005;   // m: the robot moves less than this in the window
  double still_rotation = radians(0.1);  // rad, likewise
  // The pattern pose carries the detector's noise, so its limits are looser;
  // they still catch a pattern (or camera) that moves while the robot stands.
  double pattern_still_translation = 0.005;  // m
  double pattern_still_rotation = radians(1.0);  // rad
  double max_gap = 0.5;                // s: larger gaps between observations break stillness
  double min_translation = 0.01;       // m: a new sample must differ from every other by this ...
  double min_rotation = radians(2.0);  // rad ... or by this
  double max_age = 1.0;                // s: take_sample() refuses an older latest observation
};


enum class SamplerState { WaitingForData, WaitingForStillness, WaitingForMotion };
const char* to_string(SamplerState state);

struct SampleOutcome {
  bool accepted = false;
  std::string message;  // "accepted sample 4" or the reason for refusing
};

class Sampler {
 public:
  /// `robot_noise` goes with every sample that carries the detector's covariance
  /// (zero: the robot taken as exact, as in the paper's real-data study).
  explicit Sampler(SamplerOptions options = {}, PoseNoise robot_noise = {});

  /// Feeds one observation. With auto_sample, returns the outcome when this
  /// observation completed a still period (a sample was taken or refused).
  /// Observations whose stamp goes backwards (a looping bag, a clock reset)
  /// clear the stillness history; accepted samples are kept.
  std::optional<SampleOutcome> observe(const Observation& observation);

  /// Manual sampling: the latest observation, if it is recent (relative to
  /// `now`) and robot and pattern are still.
  SampleOutcome take_sample(double now);

  const std::vector<PoseSample>& samples() const { return samples_; }
  void set_samples(std::vector<PoseSample> samples) { samples_ = std::move(samples); }
  /// Removes sample `index`; false when out of range.
  bool remove(std::size_t index);
  void reset();

  SamplerState state() const;
  const SamplerOptions& options() const { return options_; }

 private:
  bool still() const;
  SampleOutcome try_add(const Observation& observation);

  SamplerOptions options_;
  PoseNoise robot_noise_;
  std::deque<Observation> history_;  // the last still_window (+ margin) seconds
  std::vector<PoseSample> samples_;
  bool waiting_for_motion_ = false;
  std::optional<Observation> anchor_;  // where the robot stood at the last sample attempt
};

}  // namespace handeye
