// Watching a published calibration (publish.launch monitor:=true): still views as they
// come (the sampler's stillness and distinctness rules, distinct within the window), a
// sliding window of the last N, and the check of estimation/calibration_check.h on each
// new one. It only reads: the calibration it watches is never changed. ROS-free: the
// monitor node and the tests drive it the same way.
//
// Levels. Each check's p-value is of "nothing changed" at these views; the windows
// overlap, so one run makes many checks of much the same views. WARN below warn_alpha
// (1%: a single check's false alarm), ERROR below error_alpha (1e-4): over 200 checks
// a false ERROR has at most 200 x 1e-4 = 2% (the union bound), while a camera moved by
// a few of its sigma drives p to the Monte-Carlo's floor within a few views.
#pragma once

#include <optional>
#include <string>

#include "handeye_covariance/estimation/calibration_check.h"
#include "handeye_covariance/session/sampler.h"

namespace handeye {

enum class MonitorLevel { Waiting, Ok, Warn, Error };
const char* to_string(MonitorLevel level);  // "waiting" / "ok" / "warn" / "error"

struct MonitorOptions {
  int window = 10;            // the views checked together, the newest
  int min_views = 3;          // before the first verdict
  double warn_alpha = 0.01;
  double error_alpha = 1e-4;
  SamplerOptions sampler;
};

struct MonitorVerdict {
  MonitorLevel level = MonitorLevel::Waiting;
  int views = 0;                          // in the window
  std::optional<CalibrationCheck> check;  // of the window (from min_views on)
  std::string message;                    // the plain verdict, or what it waits for
};

class CalibrationMonitor {
 public:
  /// `rig`: the setup and frames (and a symmetric target); `noise`: the views' stated
  /// noise when the detector gives none of its own (the session's noise block).
  /// Throws HandEyeError when the calibration cannot be checked (calibration_check.h).
  CalibrationMonitor(Calibration calibration, Rig rig, std::optional<MeasurementNoise> noise, MonitorOptions options = {});

  /// A new verdict when this observation completed a still, distinct view; else nullopt.
  std::optional<MonitorVerdict> observe(const Observation& observation);
  const MonitorVerdict& latest() const { return latest_; }

 private:
  Calibration calibration_;
  Rig rig_;
  std::optional<MeasurementNoise> noise_;
  MonitorOptions options_;
  Sampler views_;
  MonitorVerdict latest_;
};

}  // namespace handeye
