// The calibration report (make_report, write_report): how far this session's X can be
// trusted and what to mend, from the samples alone (no truth needed). Per axis of X (ROS
// order x y z rx ry rz; m and rad) three 1 sigma: predicted, leave-one-out (jackknife)
// and split-half (split_check.h, judged by the calibrated check); the motions' rotation
// axes in the camera frame, the weakest called out; advice. `handeye report` and the
// node's /save_calibration write it; its figures and page are scripts/report.py's.
// Derivation: docs/how_it_works.md, "The calibration report: three views of X's
// uncertainty, and the rotation axes".
#pragma once

#include <string>

#include "handeye_covariance/estimation/calibration_report.h"
#include "handeye_covariance/session/calibration_session.h"

namespace handeye {

struct ReportOptions {
  int splits = 200;                // random halves for the split-half check (0: leave it out)
  int reference_sessions = 100;    // simulated honest sessions for its reference (split_check.h)
  int run_length = -1;             // the second look's runs (split_check.h): -1 the session's, 0 auto, 1 none, k runs of k
  unsigned seed = 1;
  /// A sample beyond this many sigmas (6-dof Mahalanobis length of its residual)
  /// is called out: sqrt of the chi2(6) 0.999 quantile.
  double advice_sigma = 4.74;
  /// Leave-one-out or split-half sigma over the predicted one, per axis, beyond
  /// which the advice calls the covariance overconfident (what honest sessions reach:
  /// docs/offline.md, the calibration report).
  double ratio_advice = 2.0;
  double weak_axis_share = 0.1;    // weakest over strongest eigenvalue of M
  std::size_t max_rotation_axes = 2000;  // motions kept for the figure (M uses every pair)
};

/// The report of `snapshot` as `session` calibrates it (calibrate_modelled: with the
/// shared robot error's model where the session uses it, whose check the split-half
/// section then is). Throws HandEyeError as calibrate() does (too few samples,
/// degenerate motions).
CalibrationReport make_report(const CalibrationSession& session, const SessionSnapshot& snapshot,
                              const ReportOptions& options = {});
/// The same of `calibration`, which session.calibrate_modelled(snapshot) or
/// calibrate_checked(snapshot) gave already (the node's last /calibrate): it is not
/// solved again.
CalibrationReport make_report(const CalibrationSession& session, const SessionSnapshot& snapshot,
                              Calibration calibration, const ReportOptions& options = {});

/// Efron's jackknife 1 sigma per axis from the leave-one-out estimates d_i (each
/// X_(i) against any one reference, ROS order): sqrt((n-1)/n * sum_i (d_i - mean)^2).
/// Zero for fewer than 3 estimates.
Vector6d jackknife_sigma(const std::vector<Vector6d>& leave_one_out);

/// What write_report left in its directory.
struct ReportFiles {
  std::string directory;
  std::string html;             // report.html; empty when the figures could not be made
  std::string problem;          // why not (the page needs Debian's python3-matplotlib), else empty
};

/// Writes DIR/calibration.yaml (the result file), DIR/report.yaml (format_report)
/// and, by scripts/report.py, the figures (PNG) and DIR/report.html. Creates DIR.
/// Throws HandEyeError(CannotWrite...) when DIR cannot be written; a failing
/// figure script is reported in `problem`, not thrown (the YAML files stand).
ReportFiles write_report(const std::string& directory, const CalibrationReport& report, const SampleSet& samples,
                         const std::string& source);

/// "the camera's z (optical axis)" for a direction close to a camera axis, else
/// "the camera-frame direction (0.57, 0.57, 0.57)".
std::string camera_axis_name(const Eigen::Vector3d& direction);

}  // namespace handeye
