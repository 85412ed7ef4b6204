// The calibration report: how far this session's X can be trusted, and what to
// do about it, from the samples alone (no truth needed, so it works on real
// sessions). `handeye report` and the node's /save_calibration write it; the
// figures and the HTML page are scripts/report.py's.
//
// Three views of X's uncertainty, per axis (ROS order x, y, z, rx, ry, rz):
//  - predicted: the estimator's covariance (the product);
//  - leave-one-out: the jackknife over the kept samples. Each X_(i) is solved
//    without sample i, d_i = (t_(i) - t, log(R_(i) R^T)), and
//        sigma_k^2 = (n-1)/n * sum_i (d_ik - mean_k)^2        (Efron's jackknife);
//  - split-half (split_check.h): each split's difference d = X_a - X_b over the
//    sigma its covariance predicts, s_k = sqrt((Sigma_a + Sigma_b)_kk); the
//    predicted sigma scaled by the RMS of d_k / s_k over the splits. Its NEES is
//    judged against what an honest covariance gives on the same poses (the
//    calibrated check, honesty_check), not against a fixed 6.
// An honest covariance has all three alike. The jackknife variance itself has a
// relative 1 sigma of about sqrt(2/(n-1)) (27% at 30 samples), so only ratios
// beyond `ratio_advice` are called out; the split-half NEES by the check's verdict.
//
// The rotation axes: each pair of kept samples i < j gives the camera-side
// motion B = P_i P_j^-1 (P = T_camera_pattern), whose rotation axis is in the
// camera frame. X's rotation is pinned only about axes the motions turn about:
// the eigenvalues of M = sum_ij theta_ij^2 a_ij a_ij^T say how much turning
// each direction saw; the weakest one, below `weak_axis_share` of the
// strongest, is called out.
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
  /// which the advice calls the covariance overconfident. Honest simulated sessions
  /// (test_report) reach 1.98 at most.
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
