// The estimation's front door: pose samples to X and Y with their covariance, by the
// chosen estimator, with or without outlier rejection. The session, the tools and
// the studies solve through here.
#pragma once

#include "handeye_covariance/estimation/joint_estimator.h"
#include "handeye_covariance/estimation/outliers.h"

namespace handeye {

/// Pose samples by either estimator: solve_joint, or solve (the paper's pairs).
/// (options: the joint estimator's; the pairs estimator takes its defaults.)
Calibration estimate(const SampleSet& samples, Method method, const JointOptions& options = {});

/// Solves (by `method`) with outlier rejection; Calibration::rejected lists what
/// was dropped (indices into `samples`) and why. Throws like the estimator, and
/// TooManyOutliers when more than max_rejected_fraction would be rejected.
Calibration solve_robust(const SampleSet& samples, Method method = Method::Joint, const OutlierOptions& options = {},
                         const JointOptions& joint = {});

/// solve_robust, or the plain estimator when `reject` is false: one switch for every tool.
Calibration solve_samples(const SampleSet& samples, bool reject, Method method = Method::Joint,
                          const JointOptions& joint = {});

}  // namespace handeye
