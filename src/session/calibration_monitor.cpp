#include "handeye_covariance/session/calibration_monitor.h"

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/io/check_text.h"

namespace handeye {

const char* to_string(MonitorLevel level) {
  switch (level) {
    case MonitorLevel::Waiting: return "waiting";
    case MonitorLevel::Ok: return "ok";
    case MonitorLevel::Warn: return "warn";
    case MonitorLevel::Error: return "error";
  }
  return "unknown";
}

CalibrationMonitor::CalibrationMonitor(Calibration calibration, Rig rig, std::optional<MeasurementNoise> noise,
                                       MonitorOptions options)
    : calibration_(std::move(calibration)),
      rig_(std::move(rig)),
      noise_(std::move(noise)),
      options_(options),
      views_(options.sampler, noise_ ? noise_->robot : PoseNoise{}) {
  require_checkable(calibration_);
  if (options_.window < 1 || options_.min_views < 1 || options_.min_views > options_.window ||
      !(options_.error_alpha > 0.0 && options_.error_alpha <= options_.warn_alpha && options_.warn_alpha < 1.0)) {
    throw HandEyeError(ErrorCode::MalformedFile,
                       "the monitor needs 1 <= min_views <= window and 0 < error_alpha <= warn_alpha < 1",
                       "the monitor's parameters", "e.g. window 10, min_views 3, warn_alpha 0.01, error_alpha 1e-4");
  }
  latest_.message = "waiting for " + std::to_string(options_.min_views) + " still views of the target";
}

std::optional<MonitorVerdict> CalibrationMonitor::observe(const Observation& observation) {
  const std::optional<SampleOutcome> outcome = views_.observe(observation);
  if (!outcome || !outcome->accepted) return std::nullopt;
  // The window: the newest views; distinct from each other (the sampler's rule), not
  // from every view ever seen, so a robot that comes back is watched again.
  while (static_cast<int>(views_.samples().size()) > options_.window) views_.remove(0);
  MonitorVerdict verdict;
  verdict.views = static_cast<int>(views_.samples().size());
  if (verdict.views < options_.min_views) {
    verdict.message = "waiting: " + std::to_string(verdict.views) + " of " + std::to_string(options_.min_views) +
                      " still views before the first check";
    latest_ = verdict;
    return verdict;
  }
  SampleSet window;
  window.rig = rig_;
  window.noise = noise_;
  window.samples = views_.samples();
  CheckOptions check_options;
  check_options.alpha = options_.warn_alpha;
  verdict.check = check_calibration(calibration_, with_default_noise(window), check_options);
  const double p = verdict.check->p_value;
  verdict.level = p < options_.error_alpha ? MonitorLevel::Error
                  : p < options_.warn_alpha ? MonitorLevel::Warn
                                            : MonitorLevel::Ok;
  verdict.message = io::check_verdict(*verdict.check);
  if (verdict.check->changed && verdict.views == options_.window) {
    verdict.message += " (a window of views that straddles the change names it only once all its views come after it)";
  }
  latest_ = verdict;
  return verdict;
}

}  // namespace handeye
