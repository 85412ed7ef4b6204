#include "handeye_covariance/estimation/solve.h"

#include <algorithm>
#include <cmath>

#include "handeye_covariance/core/errors.h"
#include "handeye_covariance/core/statistics.h"
#include "handeye_covariance/estimation/estimator.h"

namespace handeye {

Calibration estimate(const SampleSet& samples, Method method, const JointOptions& options) {
  if (method == Method::Corners) throw corners_need_images();
  return method == Method::Joint ? solve_joint(samples, options) : solve(samples);
}

Calibration solve_samples(const SampleSet& samples, bool reject, Method method, const JointOptions& joint) {
  return reject ? solve_robust(samples, method, {}, joint) : estimate(samples, method, joint);
}

Calibration solve_robust(const SampleSet& samples, Method method, const OutlierOptions& o, const JointOptions& joint) {
  const int n = static_cast<int>(samples.samples.size());
  const int max_rejected = static_cast<int>(std::floor(o.max_rejected_fraction * n));
  const auto too_many = [&](int count) {
    return HandEyeError(ErrorCode::TooManyOutliers,
                        std::to_string(count) + " of " + std::to_string(n) +
                            " samples disagree with the rest (at most " + std::to_string(max_rejected) +
                            " may be dropped)",
                        "samples", "check the detections and the stamp pairing (robot TF at the image time), "
                                   "and that the pattern is the configured one; then record the session again");
  };
  std::vector<Calibration::Rejected> rejected = n >= 6 ? consensus(samples, o) : std::vector<Calibration::Rejected>{};
  if (static_cast<int>(rejected.size()) > max_rejected) throw too_many(static_cast<int>(rejected.size()));
  std::vector<int> dropped;
  for (const auto& r : rejected) dropped.push_back(r.index);

  // Stage 2: residual gating, one sample at a time.
  for (;;) {
    std::vector<int> kept_index;
    for (int i = 0; i < n; ++i) {
      if (std::find(dropped.begin(), dropped.end(), i) == dropped.end()) kept_index.push_back(i);
    }
    const SampleSet kept = without(samples, dropped);
    Calibration c = estimate(kept, method, joint);
    std::vector<double> distance;
    for (const SampleFit& fit : fits_against(kept, c, kept)) distance.push_back(fit.sigmas * fit.sigmas);
    const double gate = o.residual_gate * residual_scale(distance);
    int worst = -1;
    double worst_distance = gate;
    for (std::size_t k = 0; k < distance.size(); ++k) {
      if (distance[k] > worst_distance) {
        worst_distance = distance[k];
        worst = static_cast<int>(k);
      }
    }
    if (worst < 0 || kept.samples.size() <= 4) {
      std::sort(rejected.begin(), rejected.end(), [](const auto& a, const auto& b) { return a.index < b.index; });
      c.rejected = rejected;
      if (!rejected.empty()) {
        Warning w;
        w.kind = Warning::Kind::OutliersRejected;
        w.count = static_cast<int>(rejected.size());
        c.warnings.push_back(w);
      }
      return c;
    }
    if (static_cast<int>(dropped.size()) + 1 > max_rejected) throw too_many(static_cast<int>(dropped.size()) + 1);
    const int index = kept_index[worst];
    dropped.push_back(index);
    Calibration::Rejected r;
    r.index = index, r.why = Calibration::Rejected::Why::FarFromPrediction;
    r.sigmas = std::sqrt(worst_distance), r.gate_sigmas = std::sqrt(gate);
    rejected.push_back(r);
  }
}

}  // namespace handeye
